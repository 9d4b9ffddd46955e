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

}  // namespace

void writePly(const std::string& path, const SurfaceCloud& cloud) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << "ply\nformat binary_little_endian 1.0\ncomment sdf_tracker surface cloud (world frame, metres)\n"
    << "element vertex " << cloud.points_W.size() << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\nend_header\n";
  for (size_t i = 0; i < cloud.points_W.size(); ++i) {
    writeVector3(s, cloud.points_W[i]);
    writeVector3(s, cloud.normals_W[i]);
  }
  out.commit();
}

void writePly(const std::string& path, const TriangleMesh& mesh) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << "ply\nformat binary_little_endian 1.0\ncomment sdf_tracker mesh (world frame, metres)\n"
    << "element vertex " << mesh.vertices_W.size() << "\n"
    << "property float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "element face " << mesh.triangles.size() << "\n"
    << "property list uchar int vertex_indices\nend_header\n";
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    writeVector3(s, mesh.vertices_W[i]);
    writeVector3(s, mesh.normals_W[i]);
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
  s << "# sdf_tracker mesh (world frame, metres)\n" << std::setprecision(7);
  for (const auto& v : mesh.vertices_W) s << "v " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
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
      std::string type;
      words >> type;
      if (type != "float") throwFileError(path, "only float vertex properties are supported (got " + type + ")");
      ++vertex_floats;
    }
  }
  if (line != "end_header") throwFileError(path, "PLY header has no end_header");
  if (vertex_floats < 3) throwFileError(path, "PLY vertices need x, y and z");
  // The counts are the file's word: check them against its size before allocating anything.
  const std::streamoff body_start = in.tellg();
  in.seekg(0, std::ios::end);
  const uint64_t body_bytes = static_cast<uint64_t>(in.tellg() - body_start);
  in.seekg(body_start);
  const uint64_t min_vertex_bytes = binary ? 4ull * vertex_floats : 2ull * vertex_floats;  // "0 " per value
  const uint64_t min_face_bytes = binary ? 13 : 8;                                          // "3 0 1 2\n"
  if (vertex_count > body_bytes / min_vertex_bytes || face_count > body_bytes / min_face_bytes ||
      vertex_count * min_vertex_bytes + face_count * min_face_bytes > body_bytes) {
    throwFileError(path, "header claims " + std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
                   " faces, more than its " + std::to_string(body_bytes) + " bytes can hold");
  }
  TriangleMesh mesh;
  mesh.vertices_W.resize(vertex_count);
  std::vector<float> values(vertex_floats);
  for (size_t i = 0; i < vertex_count; ++i) {
    for (auto& value : values) {
      if (binary) in.read(reinterpret_cast<char*>(&value), sizeof(float));
      else in >> value;
    }
    if (!in) throwFileError(path, "PLY ends inside vertex " + std::to_string(i) + " of " + std::to_string(vertex_count));
    mesh.vertices_W[i] = Eigen::Vector3f(values[0], values[1], values[2]);
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
