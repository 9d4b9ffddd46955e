#include "sdf_tracker/io/vti_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <vector>

#include <Eigen/Core>

#include "sdf_tracker/io/files.h"
#include "sdf_tracker/util/memory.h"

namespace sdf_tracker::io {

namespace {

/// The value of attribute `name` in the first element that has it, e.g. Spacing="0.1 0.1 0.1".
std::string xmlAttribute(const std::string& text, const std::string& name, const std::string& path) {
  const std::string key = " " + name + "=\"";
  const size_t start = text.find(key);
  if (start == std::string::npos) throwFileError(path, "missing attribute " + name);
  const size_t value_start = start + key.size();
  const size_t end = text.find('"', value_start);
  if (end == std::string::npos) throwFileError(path, "unterminated attribute " + name);
  return text.substr(value_start, end - value_start);
}

template <typename T, int N>
Eigen::Matrix<T, N, 1> parseNumbers(const std::string& text, const std::string& what, const std::string& path) {
  std::istringstream in(text);
  Eigen::Matrix<T, N, 1> values;
  for (int i = 0; i < N; ++i) {
    if (!(in >> values[i])) throwFileError(path, what + " must hold " + std::to_string(N) + " numbers (got \"" + text + "\")");
  }
  return values;
}

}  // namespace

void writeVti(const std::string& path, const TsdfVolume& volume) {
  const Eigen::Vector3i d = volume.dims();
  const Eigen::Vector3d o = volume.config().origin_W;
  const uint64_t array_bytes = volume.voxelCount() * sizeof(float);
  const bool coloured = volume.holdsColour();
  const uint64_t colour_bytes = coloured ? volume.voxelCount() * 3 : 0, colour_weight_bytes = colour_bytes / 3;
  // Both before the file is opened: a grid too large for the memory or the disk is refused by name.
  requireMemory(array_bytes, "writing " + path);
  requireFreeSpace(path, 2 * array_bytes + colour_bytes + colour_weight_bytes,
                   "the grid's " + std::to_string(volume.voxelCount()) + " voxels");
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
    << array_bytes + sizeof(uint64_t) << "\"/>\n";
  // Colour as ParaView shows it (colour by "colour", Map Scalars off), and its weight.
  if (coloured) {
    s << "        <DataArray type=\"UInt8\" Name=\"colour\" NumberOfComponents=\"3\" format=\"appended\" offset=\""
      << 2 * (array_bytes + sizeof(uint64_t)) << "\"/>\n"
      << "        <DataArray type=\"UInt8\" Name=\"colour_weight\" format=\"appended\" offset=\""
      << 2 * (array_bytes + sizeof(uint64_t)) + colour_bytes + sizeof(uint64_t) << "\"/>\n";
  }
  s << "      </PointData>\n    </Piece>\n  </ImageData>\n  <AppendedData encoding=\"raw\">\n   _";
  std::vector<float> buffer(volume.voxelCount());
  for (int field = 0; field < 2; ++field) {
    for (size_t i = 0; i < buffer.size(); ++i) {
      const Voxel v = volume.voxel(i);
      buffer[i] = field == 0 ? v.distance_m : v.weight;
    }
    writeBinary(s, array_bytes);
    s.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(array_bytes));
  }
  if (coloured) {
    std::vector<uint8_t> rgb(colour_bytes), weights(colour_weight_bytes);
    for (size_t i = 0; i < weights.size(); ++i) {
      const VoxelColour c = volume.colour(i);
      rgb[3 * i] = c.r, rgb[3 * i + 1] = c.g, rgb[3 * i + 2] = c.b;
      weights[i] = c.weight;
    }
    writeBinary(s, colour_bytes);
    s.write(reinterpret_cast<const char*>(rgb.data()), static_cast<std::streamsize>(colour_bytes));
    writeBinary(s, colour_weight_bytes);
    s.write(reinterpret_cast<const char*>(weights.data()), static_cast<std::streamsize>(colour_weight_bytes));
  }
  s << "\n  </AppendedData>\n</VTKFile>\n";
  out.commit();
}

TsdfVolume readVti(const std::string& path, bool compact_voxels) {
  uint64_t file_bytes = 0;
  std::ifstream in = openForReading(path, &file_bytes);
  // The XML header ends where the raw data starts; it is small (our writer's is under 1 KiB).
  constexpr size_t kMaxHeaderBytes = 64 * 1024;
  std::string text(static_cast<size_t>(std::min<uint64_t>(file_bytes, kMaxHeaderBytes)), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (text.find("<VTKFile type=\"ImageData\"") == std::string::npos) throwFileError(path, "not a VTK ImageData (.vti) file");
  const size_t data_marker = text.find("<AppendedData encoding=\"raw\">");
  if (data_marker == std::string::npos) throwFileError(path, "no raw AppendedData section in its first 64 KiB");
  const size_t underscore = text.find('_', data_marker);
  if (underscore == std::string::npos) throwFileError(path, "AppendedData has no '_' marker");
  const std::string header = text.substr(0, data_marker);
  if (xmlAttribute(header, "header_type", path) != "UInt64") throwFileError(path, "header_type must be UInt64");

  const auto extent = parseNumbers<int, 6>(xmlAttribute(header, "WholeExtent", path), "WholeExtent", path);
  const auto spacing = parseNumbers<double, 3>(xmlAttribute(header, "Spacing", path), "Spacing", path);
  VolumeConfig config;
  for (int axis = 0; axis < 3; ++axis) {  // in 64 bits: the extent is the file's word, not ours
    const long long size = static_cast<long long>(extent[2 * axis + 1]) - extent[2 * axis] + 1;
    if (size < 2 || size > 4096) {
      throwFileError(path, "WholeExtent " + xmlAttribute(header, "WholeExtent", path) + " gives " + std::to_string(size) +
                     " samples along an axis (2 to 4096 allowed)");
    }
    config.dims[axis] = static_cast<int>(size);
  }
  config.origin_W = parseNumbers<double, 3>(xmlAttribute(header, "Origin", path), "Origin", path);
  config.voxel_size_m = spacing.x();
  config.compact_voxels = compact_voxels;
  if (std::fabs(spacing.y() - spacing.x()) > 1e-9 || std::fabs(spacing.z() - spacing.x()) > 1e-9) {
    throwFileError(path, "voxels must be cubic (Spacing " + xmlAttribute(header, "Spacing", path) + ")");
  }
  const std::string truncation_key = "Name=\"positive_truncation_m\"";
  const size_t truncation_at = header.find(truncation_key);
  if (truncation_at == std::string::npos) throwFileError(path, "missing field positive_truncation_m");
  config.positive_truncation_m =
      parseNumbers<double, 1>(header.substr(header.find('>', truncation_at) + 1), "positive_truncation_m", path)[0];
  const auto violations = config.validate();
  if (!violations.empty()) throwFileError(path, "invalid volume geometry: " + violations.front());

  // The file must hold both arrays before anything is allocated for them: a short file that
  // claims a large grid is refused here, not after allocating the grid.
  const uint64_t voxel_count = static_cast<uint64_t>(config.dims.x()) * config.dims.y() * config.dims.z();
  const uint64_t array_bytes = voxel_count * sizeof(float);
  const uint64_t data_start = underscore + 1;
  // A colour array (this writer's, after the two float arrays) when the header names one.
  const bool coloured = header.find("Name=\"colour\"") != std::string::npos;
  const uint64_t colour_data = coloured ? 2 * sizeof(uint64_t) + 4 * voxel_count : 0;
  const uint64_t data_bytes = 2 * (sizeof(uint64_t) + array_bytes) + colour_data;
  if (file_bytes < data_start || file_bytes - data_start < data_bytes) {
    throwFileError(path, "file is truncated: its header describes " + std::to_string(config.dims.x()) + "x" +
                   std::to_string(config.dims.y()) + "x" + std::to_string(config.dims.z()) + " voxels" +
                   (coloured ? " in colour" : "") + " (" + std::to_string(data_bytes) + " bytes of data) but it holds " +
                   std::to_string(file_bytes > data_start ? file_bytes - data_start : 0) + " bytes after the header");
  }
  requireMemory(voxel_count * (2 * sizeof(float) + (compact_voxels ? sizeof(CompactVoxel) : sizeof(Voxel)) +
                               (coloured ? 4 + sizeof(VoxelColour) : 0)),
                path + ": its " + std::to_string(voxel_count) + " voxels");
  try {
    TsdfVolume volume(config);
    std::vector<float> distances(voxel_count), values(voxel_count);
    in.clear();
    in.seekg(static_cast<std::streamoff>(data_start));
    for (int field = 0; field < 2; ++field) {
      uint64_t bytes = 0;
      in.read(reinterpret_cast<char*>(&bytes), sizeof(bytes));
      if (bytes != array_bytes) {
        throwFileError(path, "array " + std::to_string(field) + " holds " + std::to_string(bytes) + " bytes, expected " +
                       std::to_string(array_bytes));
      }
      std::vector<float>& target = field == 0 ? distances : values;
      in.read(reinterpret_cast<char*>(target.data()), static_cast<std::streamsize>(array_bytes));
      if (!in) throwFileError(path, "file is truncated inside the voxel data");
    }
    for (size_t i = 0; i < voxel_count; ++i) {
      const Voxel voxel{distances[i], values[i]};
      const std::string problem = voxelProblem(voxel, config.positive_truncation_m);
      if (!problem.empty()) throwFileError(path, "voxel " + std::to_string(i) + ": " + problem);
      volume.setVoxel(i, voxel);
    }
    if (coloured) {
      std::vector<uint8_t> rgb(3 * voxel_count), weights(voxel_count);
      for (std::vector<uint8_t>* target : {&rgb, &weights}) {
        uint64_t bytes = 0;
        in.read(reinterpret_cast<char*>(&bytes), sizeof(bytes));
        if (bytes != target->size()) {
          throwFileError(path, std::string(target == &rgb ? "the colour" : "the colour weight") + " array holds " +
                                   std::to_string(bytes) + " bytes, expected " + std::to_string(target->size()));
        }
        in.read(reinterpret_cast<char*>(target->data()), static_cast<std::streamsize>(bytes));
        if (!in) throwFileError(path, "file is truncated inside the colour data");
      }
      volume.enableColour();
      for (size_t i = 0; i < voxel_count; ++i) {
        volume.setColour(i, VoxelColour{rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2], weights[i]});
      }
    }
    return volume;
  } catch (const std::bad_alloc&) {
    throwFileError(path, "not enough memory for its " + std::to_string(voxel_count) + " voxels");
  }
}

}  // namespace sdf_tracker::io
