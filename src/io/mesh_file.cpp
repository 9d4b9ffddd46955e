#include "sdf_tracker/io/mesh_file.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <vector>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::io {

namespace {

void writeVector3(std::ostream& out, const Eigen::Vector3f& v) {
  writeBinary(out, v.x());
  writeBinary(out, v.y());
  writeBinary(out, v.z());
}

/// The vertex element's properties: position, normal and, when there are colours, red, green and
/// blue as PLY readers (MeshLab, CloudCompare, Open3D) take them.
void writeVertexProperties(std::ostream& s, size_t count, bool coloured) {
  s << "element vertex " << count << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n";
  if (coloured) s << "property uchar red\nproperty uchar green\nproperty uchar blue\n";
}

void writeVertex(std::ostream& s, const Eigen::Vector3f& p, const Eigen::Vector3f& n, const Rgb* colour) {
  writeVector3(s, p);
  writeVector3(s, n);
  if (colour) s.write(reinterpret_cast<const char*>(colour->data()), 3);
}

}  // namespace

void writePly(const std::string& path, const SurfaceCloud& cloud) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  const bool coloured = !cloud.colours.empty();
  s << "ply\nformat binary_little_endian 1.0\ncomment sdf_tracker surface cloud (world frame, metres)\n";
  writeVertexProperties(s, cloud.points_W.size(), coloured);
  s << "end_header\n";
  for (size_t i = 0; i < cloud.points_W.size(); ++i) {
    writeVertex(s, cloud.points_W[i], cloud.normals_W[i], coloured ? &cloud.colours[i] : nullptr);
  }
  out.commit();
}

void writePly(const std::string& path, const TriangleMesh& mesh) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  const bool coloured = !mesh.colours.empty();
  s << "ply\nformat binary_little_endian 1.0\ncomment sdf_tracker mesh (world frame, metres)\n";
  writeVertexProperties(s, mesh.vertices_W.size(), coloured);
  s << "element face " << mesh.triangles.size() << "\n"
    << "property list uchar int vertex_indices\nend_header\n";
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    writeVertex(s, mesh.vertices_W[i], mesh.normals_W[i], coloured ? &mesh.colours[i] : nullptr);
  }
  for (const auto& t : mesh.triangles) {
    writeBinary(s, static_cast<uint8_t>(3));
    for (int m = 0; m < 3; ++m) writeBinary(s, static_cast<int32_t>(t[m]));
  }
  out.commit();
}

void writeObj(const std::string& path, const TriangleMesh& mesh) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << "# sdf_tracker mesh (world frame, metres)";
  // Vertex colours as MeshLab, Blender and Open3D read them: three more numbers, 0 to 1, on each v.
  if (!mesh.colours.empty()) s << ", vertex colours r g b in [0, 1] after x y z";
  s << '\n' << std::setprecision(7);
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    const Eigen::Vector3f& v = mesh.vertices_W[i];
    s << "v " << v.x() << ' ' << v.y() << ' ' << v.z();
    if (!mesh.colours.empty()) {
      const Rgb& c = mesh.colours[i];
      s << std::setprecision(4) << ' ' << c[0] / 255.0 << ' ' << c[1] / 255.0 << ' ' << c[2] / 255.0
        << std::setprecision(7);
    }
    s << '\n';
  }
  for (const auto& n : mesh.normals_W) s << "vn " << n.x() << ' ' << n.y() << ' ' << n.z() << '\n';
  for (const auto& t : mesh.triangles) {
    s << "f";
    for (int m = 0; m < 3; ++m) s << ' ' << t[m] + 1 << "//" << t[m] + 1;
    s << '\n';
  }
  out.commit();
}

void writeMesh(const std::string& path, const TriangleMesh& mesh) {
  if (hasExtension(path, ".obj")) return writeObj(path, mesh);
  if (hasExtension(path, ".ply")) return writePly(path, mesh);
  throwFileError(path, "unknown mesh file extension (known: .ply, .obj)");
}

TriangleMesh readPlyMesh(const std::string& path) {
  std::ifstream in = openForReading(path);
  std::string line;
  if (!std::getline(in, line) || line != "ply") throwFileError(path, "not a PLY file (first line is not \"ply\")");
  bool binary = false;
  size_t vertex_count = 0, face_count = 0;
  // The vertex properties in order: float ones, and uchar red, green and blue.
  struct Property {
    bool is_float;
    std::string name;
  };
  std::vector<Property> properties;
  int vertex_floats = 0;
  std::string element;
  while (std::getline(in, line) && line != "end_header") {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "format") {
      std::string format;
      words >> format;
      if (format != "binary_little_endian" && format != "ascii") throwFileError(path, "unsupported PLY format " + format);
      binary = format == "binary_little_endian";
    } else if (keyword == "element") {
      long long count = -1;
      words >> element >> count;
      if (count < 0) throwFileError(path, "element " + element + " needs a count of at least 0 (\"" + line + "\")");
      if (element == "vertex") vertex_count = count;
      if (element == "face") face_count = count;
    } else if (keyword == "property" && element == "vertex") {
      std::string type, name;
      words >> type >> name;
      const bool colour = name == "red" || name == "green" || name == "blue";
      if (type != "float" && !(type == "uchar" && colour)) {
        throwFileError(path, "only float vertex properties and uchar red, green, blue are supported (got " + type +
                                 " " + name + ")");
      }
      properties.push_back({type == "float", name});
      vertex_floats += type == "float";
    }
  }
  if (line != "end_header") throwFileError(path, "PLY header has no end_header");
  if (vertex_floats < 3 || properties[0].name != "x" || properties[1].name != "y" || properties[2].name != "z") {
    throwFileError(path, "PLY vertices need x, y and z first");
  }
  int colour_at[3] = {-1, -1, -1};
  for (size_t p = 0; p < properties.size(); ++p) {
    const std::string& name = properties[p].name;
    if (name == "red") colour_at[0] = static_cast<int>(p);
    if (name == "green") colour_at[1] = static_cast<int>(p);
    if (name == "blue") colour_at[2] = static_cast<int>(p);
  }
  const bool coloured = colour_at[0] >= 0 && colour_at[1] >= 0 && colour_at[2] >= 0;
  // The counts are the file's word: check them against its size before allocating anything.
  const std::streamoff body_start = in.tellg();
  in.seekg(0, std::ios::end);
  const uint64_t body_bytes = static_cast<uint64_t>(in.tellg() - body_start);
  in.seekg(body_start);
  const uint64_t vertex_bytes = 4ull * vertex_floats + (properties.size() - vertex_floats);
  const uint64_t min_vertex_bytes = binary ? vertex_bytes : 2ull * properties.size();  // "0 " per value
  const uint64_t min_face_bytes = binary ? 13 : 8;                                          // "3 0 1 2\n"
  if (vertex_count > body_bytes / min_vertex_bytes || face_count > body_bytes / min_face_bytes ||
      vertex_count * min_vertex_bytes + face_count * min_face_bytes > body_bytes) {
    throwFileError(path, "header claims " + std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
                   " faces, more than its " + std::to_string(body_bytes) + " bytes can hold");
  }
  TriangleMesh mesh;
  mesh.vertices_W.resize(vertex_count);
  if (coloured) mesh.colours.resize(vertex_count);
  std::vector<float> values(properties.size());
  for (size_t i = 0; i < vertex_count; ++i) {
    for (size_t p = 0; p < properties.size(); ++p) {
      if (properties[p].is_float) {
        if (binary) in.read(reinterpret_cast<char*>(&values[p]), sizeof(float));
        else in >> values[p];
      } else {
        int level = 0;
        if (binary) {
          uint8_t byte = 0;
          in.read(reinterpret_cast<char*>(&byte), 1);
          level = byte;
        } else {
          in >> level;
        }
        if (in && (level < 0 || level > 255)) {
          throwFileError(path, "vertex " + std::to_string(i) + ": " + properties[p].name + " " + std::to_string(level) +
                                   " is not within [0, 255]");
        }
        values[p] = static_cast<float>(level);
      }
    }
    if (!in) throwFileError(path, "PLY ends inside vertex " + std::to_string(i) + " of " + std::to_string(vertex_count));
    mesh.vertices_W[i] = Eigen::Vector3f(values[0], values[1], values[2]);
    if (coloured) {
      for (int c = 0; c < 3; ++c) mesh.colours[i][c] = static_cast<uint8_t>(values[colour_at[c]]);
    }
  }
  mesh.triangles.resize(face_count);
  for (size_t i = 0; i < face_count; ++i) {
    int corners = 0;
    Eigen::Vector3i t;
    if (binary) {
      uint8_t n = 0;
      in.read(reinterpret_cast<char*>(&n), 1);
      corners = n;
      if (corners == 3) in.read(reinterpret_cast<char*>(t.data()), 3 * sizeof(int32_t));
    } else {
      in >> corners;
      if (corners == 3) in >> t[0] >> t[1] >> t[2];
    }
    if (!in) throwFileError(path, "PLY ends inside face " + std::to_string(i) + " of " + std::to_string(face_count));
    if (corners != 3) throwFileError(path, "face " + std::to_string(i) + " has " + std::to_string(corners) + " corners, not 3");
    if (t.minCoeff() < 0 || static_cast<uint64_t>(t.maxCoeff()) >= vertex_count) {
      throwFileError(path, "face " + std::to_string(i) + " indexes a vertex that does not exist");
    }
    mesh.triangles[i] = t;
  }
  return mesh;
}

}  // namespace sdf_tracker::io
