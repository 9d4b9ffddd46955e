#include "sdf_tracker/core/io.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <sys/stat.h>

#include <opencv2/imgcodecs.hpp>

namespace sdf_tracker::io {

namespace {

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

std::string temporaryPathFor(const std::string& path) { return path + ".tmp"; }

/// An output file that appears under its final name only when commit() succeeds.
class AtomicOutput {
 public:
  explicit AtomicOutput(const std::string& path)
      : path_(path), temporary_(temporaryPathFor(path)), out_(temporary_, std::ios::binary | std::ios::trunc) {
    if (!out_) fail(path_, std::string("cannot open for writing: ") + std::strerror(errno));
  }
  ~AtomicOutput() {
    if (!committed_) std::remove(temporary_.c_str());
  }
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  std::ofstream& stream() { return out_; }

  void commit() {
    out_.close();
    if (!out_) fail(path_, "write failed (disk full?)");
    if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
      fail(path_, std::string("cannot move the written file into place: ") + std::strerror(errno));
    }
    committed_ = true;
  }

 private:
  std::string path_;
  std::string temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

template <typename T>
void writeBinary(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// 64-bit FNV-1a, fed in pieces.
class Fnv1a {
 public:
  void add(const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash_ = (hash_ ^ p[i]) * 0x100000001b3ull;
  }
  uint64_t value() const { return hash_; }

 private:
  uint64_t hash_ = 0xcbf29ce484222325ull;
};

bool hasExtension(const std::string& path, const std::string& extension) {
  return path.size() > extension.size() && path.compare(path.size() - extension.size(), extension.size(), extension) == 0;
}

void writeVector3(std::ostream& out, const Eigen::Vector3f& v) {
  writeBinary(out, v.x());
  writeBinary(out, v.y());
  writeBinary(out, v.z());
}

/// The value of attribute `name` in the first element that has it, e.g. Spacing="0.1 0.1 0.1".
std::string xmlAttribute(const std::string& text, const std::string& name, const std::string& path) {
  const std::string key = " " + name + "=\"";
  const size_t start = text.find(key);
  if (start == std::string::npos) fail(path, "missing attribute " + name);
  const size_t value_start = start + key.size();
  const size_t end = text.find('"', value_start);
  if (end == std::string::npos) fail(path, "unterminated attribute " + name);
  return text.substr(value_start, end - value_start);
}

template <typename T, int N>
Eigen::Matrix<T, N, 1> parseNumbers(const std::string& text, const std::string& what, const std::string& path) {
  std::istringstream in(text);
  Eigen::Matrix<T, N, 1> values;
  for (int i = 0; i < N; ++i) {
    if (!(in >> values[i])) fail(path, what + " must hold " + std::to_string(N) + " numbers (got \"" + text + "\")");
  }
  return values;
}

}  // namespace

std::string PngHeader::describe() const {
  const char* kind = colour_type == 0   ? "greyscale"
                     : colour_type == 2 ? "RGB"
                     : colour_type == 3 ? "palette"
                     : colour_type == 4 ? "greyscale + alpha"
                     : colour_type == 6 ? "RGBA"
                                        : "unknown colour type";
  return std::to_string(bit_depth) + "-bit " + kind;
}

PngHeader readPngHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  unsigned char bytes[26];
  in.read(reinterpret_cast<char*>(bytes), sizeof(bytes));
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() != sizeof(bytes) || std::memcmp(bytes, kSignature, 8) != 0 || std::memcmp(bytes + 12, "IHDR", 4) != 0) {
    fail(path, "not a PNG file (no PNG signature and header)");
  }
  auto bigEndian = [&](int at) {
    return (static_cast<uint32_t>(bytes[at]) << 24) | (static_cast<uint32_t>(bytes[at + 1]) << 16) |
           (static_cast<uint32_t>(bytes[at + 2]) << 8) | bytes[at + 3];
  };
  const uint32_t width = bigEndian(16), height = bigEndian(20);
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) {
    fail(path, "PNG header gives an invalid size " + std::to_string(width) + "x" + std::to_string(height));
  }
  return {static_cast<int>(width), static_cast<int>(height), bytes[24], bytes[25]};
}

DepthImage readDepthPng(const std::string& path, double depth_factor, int expected_width, int expected_height) {
  if (!(depth_factor > 0.0 && std::isfinite(depth_factor))) {
    fail(path, "depth factor must be > 0 (got " + std::to_string(depth_factor) + ")");
  }
  const PngHeader header = readPngHeader(path);
  if (header.colour_type != 0 || header.bit_depth != 16) {
    fail(path, "depth must be a 16-bit greyscale PNG (got " + header.describe() + ")");
  }
  if (expected_width > 0 && (header.width != expected_width || header.height != expected_height)) {
    fail(path, "image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                   " but the intrinsics are for " + std::to_string(expected_width) + "x" +
                   std::to_string(expected_height));
  }
  if (static_cast<long long>(header.width) * header.height > kMaxImagePixels) {
    fail(path, "image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                   ", larger than any depth camera's (at most " + std::to_string(kMaxImagePixels) + " pixels)");
  }
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
  if (raw.empty()) fail(path, "cannot decode the PNG (corrupt?)");
  if (raw.type() != CV_16UC1 || raw.cols != header.width || raw.rows != header.height) {
    fail(path, "decoded image does not match its PNG header (corrupt?)");
  }
  return DepthImage::fromRaw16(raw.ptr<uint16_t>(), raw.cols, raw.rows, depth_factor);
}

void writeDepthPng(const std::string& path, const DepthImage& depth, double depth_factor) {
  std::vector<uint16_t> values = depth.toRaw16(depth_factor);
  const cv::Mat raw(depth.height(), depth.width(), CV_16UC1, values.data());
  std::vector<uchar> png;
  if (!cv::imencode(".png", raw, png)) fail(path, "PNG encoding failed");
  AtomicOutput out(path);
  out.stream().write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.commit();
}

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
  hasExtension(path, ".obj") ? writeObj(path, mesh) : writePly(path, mesh);
}

TriangleMesh readPlyMesh(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::string line;
  if (!std::getline(in, line) || line != "ply") fail(path, "not a PLY file (first line is not \"ply\")");
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
      if (format != "binary_little_endian" && format != "ascii") fail(path, "unsupported PLY format " + format);
      binary = format == "binary_little_endian";
    } else if (keyword == "element") {
      long long count = -1;
      words >> element >> count;
      if (count < 0) fail(path, "element " + element + " needs a count of at least 0 (\"" + line + "\")");
      if (element == "vertex") vertex_count = count;
      if (element == "face") face_count = count;
    } else if (keyword == "property" && element == "vertex") {
      std::string type;
      words >> type;
      if (type != "float") fail(path, "only float vertex properties are supported (got " + type + ")");
      ++vertex_floats;
    }
  }
  if (line != "end_header") fail(path, "PLY header has no end_header");
  if (vertex_floats < 3) fail(path, "PLY vertices need x, y and z");
  // The counts are the file's word: check them against its size before allocating anything.
  const std::streamoff body_start = in.tellg();
  in.seekg(0, std::ios::end);
  const uint64_t body_bytes = static_cast<uint64_t>(in.tellg() - body_start);
  in.seekg(body_start);
  const uint64_t min_vertex_bytes = binary ? 4ull * vertex_floats : 2ull * vertex_floats;  // "0 " per value
  const uint64_t min_face_bytes = binary ? 13 : 8;                                          // "3 0 1 2\n"
  if (vertex_count > body_bytes / min_vertex_bytes || face_count > body_bytes / min_face_bytes ||
      vertex_count * min_vertex_bytes + face_count * min_face_bytes > body_bytes) {
    fail(path, "header claims " + std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
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
    if (!in) fail(path, "PLY ends inside vertex " + std::to_string(i) + " of " + std::to_string(vertex_count));
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
    if (!in) fail(path, "PLY ends inside face " + std::to_string(i) + " of " + std::to_string(face_count));
    if (corners != 3) fail(path, "face " + std::to_string(i) + " has " + std::to_string(corners) + " corners, not 3");
    if (t.minCoeff() < 0 || static_cast<uint64_t>(t.maxCoeff()) >= vertex_count) {
      fail(path, "face " + std::to_string(i) + " indexes a vertex that does not exist");
    }
    mesh.triangles[i] = t;
  }
  return mesh;
}

void writeVti(const std::string& path, const TsdfVolume& volume) {
  const Eigen::Vector3i d = volume.dims();
  const Eigen::Vector3d o = volume.config().origin_W;
  const uint64_t array_bytes = volume.voxelCount() * sizeof(float);
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << std::setprecision(17);
  s << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    << "  <ImageData WholeExtent=\"0 " << d.x() - 1 << " 0 " << d.y() - 1 << " 0 " << d.z() - 1 << "\" Origin=\""
    << o.x() << ' ' << o.y() << ' ' << o.z() << "\" Spacing=\"" << volume.config().voxel_size_m << ' '
    << volume.config().voxel_size_m << ' ' << volume.config().voxel_size_m << "\">\n"
    << "    <FieldData>\n"
    << "      <DataArray type=\"Float64\" Name=\"positive_truncation_m\" NumberOfTuples=\"1\" format=\"ascii\">"
    << volume.config().positive_truncation_m << "</DataArray>\n"
    << "    </FieldData>\n"
    << "    <Piece Extent=\"0 " << d.x() - 1 << " 0 " << d.y() - 1 << " 0 " << d.z() - 1 << "\">\n"
    << "      <PointData Scalars=\"distance\">\n"
    << "        <DataArray type=\"Float32\" Name=\"distance\" format=\"appended\" offset=\"0\"/>\n"
    << "        <DataArray type=\"Float32\" Name=\"weight\" format=\"appended\" offset=\""
    << array_bytes + sizeof(uint64_t) << "\"/>\n"
    << "      </PointData>\n    </Piece>\n  </ImageData>\n  <AppendedData encoding=\"raw\">\n   _";
  std::vector<float> buffer(volume.voxelCount());
  for (int field = 0; field < 2; ++field) {
    for (size_t i = 0; i < buffer.size(); ++i) {
      const Voxel v = volume.voxel(i);
      buffer[i] = field == 0 ? v.distance_m : v.weight;
    }
    writeBinary(s, array_bytes);
    s.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(array_bytes));
  }
  s << "\n  </AppendedData>\n</VTKFile>\n";
  out.commit();
}

TsdfVolume readVti(const std::string& path, bool compact_voxels) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const uint64_t file_bytes = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  // The XML header ends where the raw data starts; it is small (our writer's is under 1 KiB).
  constexpr size_t kMaxHeaderBytes = 64 * 1024;
  std::string text(static_cast<size_t>(std::min<uint64_t>(file_bytes, kMaxHeaderBytes)), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (text.find("<VTKFile type=\"ImageData\"") == std::string::npos) fail(path, "not a VTK ImageData (.vti) file");
  const size_t data_marker = text.find("<AppendedData encoding=\"raw\">");
  if (data_marker == std::string::npos) fail(path, "no raw AppendedData section in its first 64 KiB");
  const size_t underscore = text.find('_', data_marker);
  if (underscore == std::string::npos) fail(path, "AppendedData has no '_' marker");
  const std::string header = text.substr(0, data_marker);
  if (xmlAttribute(header, "header_type", path) != "UInt64") fail(path, "header_type must be UInt64");

  const auto extent = parseNumbers<int, 6>(xmlAttribute(header, "WholeExtent", path), "WholeExtent", path);
  const auto spacing = parseNumbers<double, 3>(xmlAttribute(header, "Spacing", path), "Spacing", path);
  VolumeConfig config;
  for (int axis = 0; axis < 3; ++axis) {  // in 64 bits: the extent is the file's word, not ours
    const long long size = static_cast<long long>(extent[2 * axis + 1]) - extent[2 * axis] + 1;
    if (size < 2 || size > 4096) {
      fail(path, "WholeExtent " + xmlAttribute(header, "WholeExtent", path) + " gives " + std::to_string(size) +
                     " samples along an axis (2 to 4096 allowed)");
    }
    config.dims[axis] = static_cast<int>(size);
  }
  config.origin_W = parseNumbers<double, 3>(xmlAttribute(header, "Origin", path), "Origin", path);
  config.voxel_size_m = spacing.x();
  config.compact_voxels = compact_voxels;
  if (std::fabs(spacing.y() - spacing.x()) > 1e-9 || std::fabs(spacing.z() - spacing.x()) > 1e-9) {
    fail(path, "voxels must be cubic (Spacing " + xmlAttribute(header, "Spacing", path) + ")");
  }
  const std::string truncation_key = "Name=\"positive_truncation_m\"";
  const size_t truncation_at = header.find(truncation_key);
  if (truncation_at == std::string::npos) fail(path, "missing field positive_truncation_m");
  config.positive_truncation_m =
      parseNumbers<double, 1>(header.substr(header.find('>', truncation_at) + 1), "positive_truncation_m", path)[0];
  const auto violations = config.validate();  // includes the memory budget of the grid
  if (!violations.empty()) fail(path, "invalid volume geometry: " + violations.front());

  // The file must hold both arrays before anything is allocated for them: a short file that
  // claims a large grid is refused here, not after allocating the grid.
  const uint64_t voxel_count = static_cast<uint64_t>(config.dims.x()) * config.dims.y() * config.dims.z();
  const uint64_t array_bytes = voxel_count * sizeof(float);
  const uint64_t data_start = underscore + 1;
  if (file_bytes < data_start || file_bytes - data_start < 2 * (sizeof(uint64_t) + array_bytes)) {
    fail(path, "file is truncated: its header describes " + std::to_string(config.dims.x()) + "x" +
                   std::to_string(config.dims.y()) + "x" + std::to_string(config.dims.z()) + " voxels (" +
                   std::to_string(2 * array_bytes) + " bytes of data) but it holds " +
                   std::to_string(file_bytes > data_start ? file_bytes - data_start : 0) + " bytes after the header");
  }
  try {
    TsdfVolume volume(config);
    std::vector<float> distances(voxel_count), values(voxel_count);
    in.clear();
    in.seekg(static_cast<std::streamoff>(data_start));
    for (int field = 0; field < 2; ++field) {
      uint64_t bytes = 0;
      in.read(reinterpret_cast<char*>(&bytes), sizeof(bytes));
      if (bytes != array_bytes) {
        fail(path, "array " + std::to_string(field) + " holds " + std::to_string(bytes) + " bytes, expected " +
                       std::to_string(array_bytes));
      }
      std::vector<float>& target = field == 0 ? distances : values;
      in.read(reinterpret_cast<char*>(target.data()), static_cast<std::streamsize>(array_bytes));
      if (!in) fail(path, "file is truncated inside the voxel data");
      for (size_t i = 0; i < voxel_count; ++i) {
        if (!std::isfinite(target[i]) || (field == 1 && target[i] < 0.0f)) {
          fail(path, std::string(field == 0 ? "distance" : "weight") + " of voxel " + std::to_string(i) +
                         " is invalid (" + std::to_string(target[i]) + ")");
        }
      }
    }
    for (size_t i = 0; i < voxel_count; ++i) volume.setVoxel(i, Voxel{distances[i], values[i]});
    return volume;
  } catch (const std::bad_alloc&) {
    fail(path, "not enough memory for its " + std::to_string(voxel_count) + " voxels");
  }
}

namespace {

constexpr char kMapMagic[8] = {'S', 'D', 'F', 'T', 'M', 'A', 'P', '\n'};
constexpr uint32_t kMapVersion = 1;

/// The header of a .sdfmap file, field by field as stored.
#pragma pack(push, 1)
struct MapFileHeader {
  char magic[8];
  uint32_t version;
  uint32_t block_side;
  double voxel_size_m;
  double positive_truncation_m;
  double origin_W[3];
  uint64_t block_count;
};
struct MapFileBlock {
  int32_t index[3];
  Voxel voxels[kBlockVoxels];
};
#pragma pack(pop)
static_assert(sizeof(MapFileHeader) == 64 && sizeof(Voxel) == 8, "the .sdfmap layout is fixed");

[[noreturn]] void failUnknownMapExtension(const std::string& path) {
  fail(path, "unknown map file extension (known: .sdfmap, .vti)");
}

}  // namespace

void writeSparseMap(const std::string& path, const SparseTsdfMap& map) {
  MapFileHeader header;
  std::memcpy(header.magic, kMapMagic, sizeof(kMapMagic));
  header.version = kMapVersion;
  header.block_side = kBlockSide;
  header.voxel_size_m = map.config().voxel_size_m;
  header.positive_truncation_m = map.config().positive_truncation_m;
  for (int axis = 0; axis < 3; ++axis) header.origin_W[axis] = map.config().origin_W[axis];
  const std::vector<SparseTsdfMap::BlockIndex> indices = map.blockIndices();
  header.block_count = indices.size();

  AtomicOutput out(path);
  Fnv1a hash;
  auto put = [&](const void* data, size_t bytes) {
    hash.add(data, bytes);
    out.stream().write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  };
  put(&header, sizeof(header));
  auto record = std::make_unique<MapFileBlock>();
  for (const SparseTsdfMap::BlockIndex& index : indices) {
    for (int axis = 0; axis < 3; ++axis) record->index[axis] = index[axis];
    const VoxelBlock& block = *map.find(index);
    std::copy(block.voxels.begin(), block.voxels.end(), record->voxels);
    put(record.get(), sizeof(MapFileBlock));
  }
  const uint64_t checksum = hash.value();
  out.stream().write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
  out.commit();
}

SparseTsdfMap readSparseMap(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const uint64_t file_bytes = static_cast<uint64_t>(in.tellg());
  in.seekg(0);
  MapFileHeader header;
  if (file_bytes < sizeof(header) || !in.read(reinterpret_cast<char*>(&header), sizeof(header)) ||
      std::memcmp(header.magic, kMapMagic, sizeof(kMapMagic)) != 0) {
    fail(path, "not an sdf_tracker map (.sdfmap) file");
  }
  if (header.version != kMapVersion) {
    fail(path, "format version " + std::to_string(header.version) + "; this build reads version " +
                   std::to_string(kMapVersion));
  }
  if (header.block_side != static_cast<uint32_t>(kBlockSide)) {
    fail(path, "blocks of " + std::to_string(header.block_side) + "^3 voxels; this build uses " +
                   std::to_string(kBlockSide) + "^3");
  }
  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = header.voxel_size_m;
  config.positive_truncation_m = header.positive_truncation_m;
  config.origin_W = Eigen::Vector3d(header.origin_W[0], header.origin_W[1], header.origin_W[2]);
  if (const auto violations = config.validate(); !violations.empty()) {
    fail(path, "invalid map geometry: " + violations.front());
  }
  // The length must match the block count exactly before anything is allocated for the blocks.
  const uint64_t block_bytes = sizeof(MapFileBlock);
  const uint64_t payload = file_bytes - sizeof(header);
  if (payload < sizeof(uint64_t) || (payload - sizeof(uint64_t)) / block_bytes != header.block_count ||
      (payload - sizeof(uint64_t)) % block_bytes != 0) {
    fail(path, "its header lists " + std::to_string(header.block_count) + " blocks (" +
                   std::to_string(header.block_count * block_bytes + sizeof(uint64_t)) +
                   " bytes after the header) but the file holds " + std::to_string(payload) +
                   " bytes after the header: truncated or not written by this package");
  }

  Fnv1a hash;
  hash.add(&header, sizeof(header));
  SparseTsdfMap map(config);
  auto record = std::make_unique<MapFileBlock>();
  try {
    for (uint64_t b = 0; b < header.block_count; ++b) {
      if (!in.read(reinterpret_cast<char*>(record.get()), sizeof(MapFileBlock))) {
        fail(path, "read failed in block " + std::to_string(b));
      }
      hash.add(record.get(), sizeof(MapFileBlock));
      const SparseTsdfMap::BlockIndex index(record->index[0], record->index[1], record->index[2]);
      std::ostringstream where;
      where << "block " << b << " at (" << index.transpose() << ")";
      if (!SparseTsdfMap::inKeyRange(index)) fail(path, where.str() + " lies beyond the map's reach");
      if (map.find(index)) fail(path, where.str() + " appears twice");
      for (int v = 0; v < kBlockVoxels; ++v) {
        const Voxel& voxel = record->voxels[v];
        if (!std::isfinite(voxel.distance_m)) {
          fail(path, where.str() + ", voxel " + std::to_string(v) + ": invalid distance " +
                         std::to_string(voxel.distance_m));
        }
        if (!std::isfinite(voxel.weight) || voxel.weight < 0.0f) {
          fail(path, where.str() + ", voxel " + std::to_string(v) + ": invalid weight " +
                         std::to_string(voxel.weight) + " (must be finite and at least 0)");
        }
      }
      std::copy(record->voxels, record->voxels + kBlockVoxels, map.allocate(index).voxels.begin());
    }
  } catch (const std::bad_alloc&) {
    fail(path, "not enough memory for its " + std::to_string(header.block_count) + " blocks");
  }
  uint64_t checksum = 0;
  if (!in.read(reinterpret_cast<char*>(&checksum), sizeof(checksum)) || checksum != hash.value()) {
    fail(path, "checksum mismatch: the file is corrupt");
  }
  return map;
}

void writeMap(const std::string& path, const TsdfMap& map) {
  if (hasExtension(path, ".sdfmap")) {
    if (map.type() == MapType::kSparse) writeSparseMap(path, static_cast<const SparseTsdfMap&>(map));
    else writeSparseMap(path, toSparseMap(map));
  } else if (hasExtension(path, ".vti")) {
    writeVti(path, toDenseVolume(map));
  } else {
    failUnknownMapExtension(path);
  }
}

std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels) {
  if (hasExtension(path, ".sdfmap")) return std::make_unique<SparseTsdfMap>(readSparseMap(path));
  if (hasExtension(path, ".vti")) return std::make_unique<TsdfVolume>(readVti(path, compact_voxels));
  failUnknownMapExtension(path);
}

void writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  std::ostringstream s;
  s << "# timestamp tx ty tz qx qy qz qw (camera to world)\n" << std::fixed;
  for (const auto& pose : poses) {
    const Eigen::Quaterniond q(pose.T_W_C.linear());
    const Eigen::Vector3d t = pose.T_W_C.translation();
    s << std::setprecision(6) << pose.timestamp_s << std::setprecision(7) << ' ' << t.x() << ' ' << t.y() << ' '
      << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  writeTextFile(path, s.str());
}

std::vector<StampedPose> readTrajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::vector<StampedPose> poses;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    double v[8];
    for (double& value : v) {
      if (!(words >> value) || !std::isfinite(value)) {
        fail(path, "line " + std::to_string(line_number) + " is not \"timestamp tx ty tz qx qy qz qw\": " + line);
      }
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::fabs(q.norm() - 1.0) > 1e-2) {
      fail(path, "line " + std::to_string(line_number) + " has a quaternion of norm " + std::to_string(q.norm()));
    }
    StampedPose pose{v[0], Eigen::Isometry3d::Identity()};
    pose.T_W_C.linear() = q.normalized().toRotationMatrix();
    pose.T_W_C.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(pose);
  }
  return poses;
}

void makeDirectories(const std::string& path) {
  std::string partial = !path.empty() && path[0] == '/' ? "/" : "";
  std::istringstream parts(path);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (part.empty()) continue;
    partial += part + "/";
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST) {
      fail(partial, std::string("cannot create directory: ") + std::strerror(errno));
    }
  }
}

bool removeStaleTemporary(const std::string& path) {
  return std::remove(temporaryPathFor(path).c_str()) == 0;
}

void writeTextFile(const std::string& path, const std::string& text) {
  AtomicOutput out(path);
  out.stream() << text;
  out.commit();
}

}  // namespace sdf_tracker::io
