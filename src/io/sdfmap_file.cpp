#include "sdf_tracker/io/sdfmap_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::io {

namespace {

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

constexpr char kMapMagic[8] = {'S', 'D', 'F', 'T', 'M', 'A', 'P', '\n'};
constexpr uint32_t kMapVersion = 4;
constexpr uint32_t kFirstMapVersion = 1;  ///< no place memory
constexpr uint32_t kPlacesVersion = 2;    ///< from this version on: the place memory
constexpr uint32_t kMapFrameVersion = 3;  ///< from this version on: the map frame
constexpr uint32_t kColourVersion = 4;    ///< from this version on: the colour flag (and colours)

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
/// Version 2's place memory header, right after MapFileHeader.
struct PlacesHeader {
  uint64_t keyframe_count;
  int32_t grid_width;
  int32_t grid_height;
  int32_t fern_count;
  int32_t tests_per_fern;
  uint64_t seed;
  double min_test_depth_m;
  double max_test_depth_m;
};
struct KeyframePose {
  double position[3];
  double orientation[4];  ///< qx qy qz qw
};
/// Version 3's map frame, right after PlacesHeader.
struct MapFrameRecord {
  uint64_t known;  ///< 1: T_map_W holds the map frame; 0: none was saved
  KeyframePose T_map_W;
};
/// Version 4's colour flag, right after MapFrameRecord: 1 when every block's record is followed
/// by a colour per voxel.
struct ColourRecord {
  uint64_t holds_colour;
};
#pragma pack(pop)
static_assert(sizeof(MapFileHeader) == 64 && sizeof(PlacesHeader) == 48 && sizeof(KeyframePose) == 56 &&
                  sizeof(MapFrameRecord) == 64 && sizeof(ColourRecord) == 8 && sizeof(Voxel) == 8 &&
                  sizeof(VoxelColour) == 4,
              "the .sdfmap layout is fixed");
constexpr size_t kBlockColourBytes = kBlockVoxels * sizeof(VoxelColour);

KeyframePose poseRecordOf(const Eigen::Isometry3d& T) {
  KeyframePose pose;
  const Eigen::Quaterniond q(T.rotation());
  for (int axis = 0; axis < 3; ++axis) pose.position[axis] = T.translation()[axis];
  const double orientation[4] = {q.x(), q.y(), q.z(), q.w()};
  std::copy(orientation, orientation + 4, pose.orientation);
  return pose;
}
Eigen::Isometry3d poseOf(const KeyframePose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(pose.position[0], pose.position[1], pose.position[2]);
  T.linear() = Eigen::Quaterniond(pose.orientation[3], pose.orientation[0], pose.orientation[1], pose.orientation[2])
                   .normalized()
                   .toRotationMatrix();
  return T;
}

/// Why a saved pose cannot be one ("" when it can).
std::string poseProblem(const KeyframePose& pose) {
  for (double x : pose.position) {
    if (!std::isfinite(x) || std::fabs(x) > 1e7) return "position " + std::to_string(x) + " m is not a place";
  }
  double norm2 = 0.0;
  for (double q : pose.orientation) norm2 += std::isfinite(q) ? q * q : 1e300;
  if (std::fabs(std::sqrt(norm2) - 1.0) > 1e-6) return "orientation of norm " + std::to_string(std::sqrt(norm2)) + " (not a unit quaternion)";
  return "";
}

/// The place memory's header for `keyframes` keyframes of `descriptor`, and the descriptor a
/// header states: the one mapping between the file's fields and the config's.
PlacesHeader placesHeaderOf(const PlaceDescriptorConfig& descriptor, uint64_t keyframes) {
  return {keyframes,          descriptor.grid_width, descriptor.grid_height,      descriptor.fern_count,
          descriptor.tests_per_fern, descriptor.seed, descriptor.min_test_depth_m, descriptor.max_test_depth_m};
}
PlaceDescriptorConfig descriptorOf(const PlacesHeader& header) {
  PlaceDescriptorConfig descriptor;
  descriptor.grid_width = header.grid_width;
  descriptor.grid_height = header.grid_height;
  descriptor.fern_count = header.fern_count;
  descriptor.tests_per_fern = header.tests_per_fern;
  descriptor.seed = header.seed;
  descriptor.min_test_depth_m = header.min_test_depth_m;
  descriptor.max_test_depth_m = header.max_test_depth_m;
  return descriptor;
}

/// Why a saved keyframe cannot be one ("" when it can).
std::string keyframeProblem(const KeyframePose& pose, const uint8_t* code, const PlaceDescriptorConfig& descriptor) {
  if (std::string problem = poseProblem(pose); !problem.empty()) return problem;
  for (int f = 0; f < descriptor.fern_count; ++f) {
    if (code[f] >> descriptor.tests_per_fern) {
      return "fern " + std::to_string(f) + " has code " + std::to_string(code[f]) + ", beyond its " +
             std::to_string(descriptor.tests_per_fern) + " bits";
    }
  }
  return "";
}

}  // namespace

void writeSparseMap(const std::string& path, const SparseTsdfMap& map, const PlaceMemory* places,
                    const std::optional<Eigen::Isometry3d>& T_map_W) {
  MapFileHeader header;
  std::memcpy(header.magic, kMapMagic, sizeof(kMapMagic));
  header.version = kMapVersion;
  header.block_side = kBlockSide;
  header.voxel_size_m = map.config().voxel_size_m;
  header.positive_truncation_m = map.config().positive_truncation_m;
  for (int axis = 0; axis < 3; ++axis) header.origin_W[axis] = map.config().origin_W[axis];
  const std::vector<SparseTsdfMap::BlockIndex> indices = map.blockIndices();
  header.block_count = indices.size();
  const PlacesHeader places_header = placesHeaderOf(places ? places->config().descriptor : PlaceDescriptorConfig(),
                                                   places ? places->keyframes().size() : 0);
  MapFrameRecord map_frame{};
  map_frame.known = T_map_W ? 1 : 0;
  map_frame.T_map_W = poseRecordOf(T_map_W.value_or(Eigen::Isometry3d::Identity()));
  const ColourRecord colour{map.holdsColour() ? 1u : 0u};

  AtomicOutput out(path);
  Fnv1a hash;
  auto put = [&](const void* data, size_t bytes) {
    hash.add(data, bytes);
    out.stream().write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
  };
  put(&header, sizeof(header));
  put(&places_header, sizeof(places_header));
  put(&map_frame, sizeof(map_frame));
  put(&colour, sizeof(colour));
  auto record = std::make_unique<MapFileBlock>();
  for (const SparseTsdfMap::BlockIndex& index : indices) {
    for (int axis = 0; axis < 3; ++axis) record->index[axis] = index[axis];
    const VoxelBlock& block = *map.find(index);
    std::copy(block.voxels.begin(), block.voxels.end(), record->voxels);
    put(record.get(), sizeof(MapFileBlock));
    if (colour.holds_colour) put(block.colours.data(), kBlockColourBytes);
  }
  if (places) {
    for (const Keyframe& keyframe : places->keyframes()) {
      const KeyframePose pose = poseRecordOf(keyframe.T_W_C);
      put(&pose, sizeof(pose));
      put(keyframe.code.data(), keyframe.code.size());
    }
  }
  const uint64_t checksum = hash.value();
  out.stream().write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
  out.commit();
}

SparseTsdfMap readSparseMap(const std::string& path, std::optional<SavedPlaces>* places,
                            std::optional<Eigen::Isometry3d>* T_map_W) {
  uint64_t file_bytes = 0;
  std::ifstream in = openForReading(path, &file_bytes);
  MapFileHeader header;
  if (file_bytes < sizeof(header) || !in.read(reinterpret_cast<char*>(&header), sizeof(header)) ||
      std::memcmp(header.magic, kMapMagic, sizeof(kMapMagic)) != 0) {
    throwFileError(path, "not an sdf_tracker map (.sdfmap) file");
  }
  if (header.version < kFirstMapVersion || header.version > kMapVersion) {
    throwFileError(path, "format version " + std::to_string(header.version) + "; this build reads versions " +
                   std::to_string(kFirstMapVersion) + " to " + std::to_string(kMapVersion));
  }
  if (header.block_side != static_cast<uint32_t>(kBlockSide)) {
    throwFileError(path, "blocks of " + std::to_string(header.block_side) + "^3 voxels; this build uses " +
                   std::to_string(kBlockSide) + "^3");
  }
  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = header.voxel_size_m;
  config.positive_truncation_m = header.positive_truncation_m;
  config.origin_W = Eigen::Vector3d(header.origin_W[0], header.origin_W[1], header.origin_W[2]);
  if (const auto violations = config.validate(); !violations.empty()) {
    throwFileError(path, "invalid map geometry: " + violations.front());
  }
  Fnv1a hash;
  hash.add(&header, sizeof(header));
  // Version 2: the place memory's header, and what its keyframes take.
  PlacesHeader places_header{};
  PlaceDescriptorConfig descriptor;
  uint64_t keyframe_bytes = 0;
  const bool has_places = header.version >= kPlacesVersion;
  if (has_places) {
    if (file_bytes < sizeof(header) + sizeof(places_header) ||
        !in.read(reinterpret_cast<char*>(&places_header), sizeof(places_header))) {
      throwFileError(path, "truncated in the place memory's header");
    }
    hash.add(&places_header, sizeof(places_header));
    descriptor = descriptorOf(places_header);
    if (const auto violations = descriptor.validate(); !violations.empty()) {
      throwFileError(path, "invalid place descriptor: " + violations.front());
    }
    keyframe_bytes = sizeof(KeyframePose) + static_cast<uint64_t>(descriptor.fern_count);
  }
  // Version 3: the map frame.
  MapFrameRecord map_frame{};
  const bool has_map_frame = header.version >= kMapFrameVersion;
  if (has_map_frame) {
    if (file_bytes < sizeof(header) + sizeof(places_header) + sizeof(map_frame) ||
        !in.read(reinterpret_cast<char*>(&map_frame), sizeof(map_frame))) {
      throwFileError(path, "truncated in the map frame");
    }
    hash.add(&map_frame, sizeof(map_frame));
    if (map_frame.known > 1) throwFileError(path, "map frame: flag " + std::to_string(map_frame.known) + " is neither 0 nor 1");
    if (map_frame.known == 1) {
      if (const std::string problem = poseProblem(map_frame.T_map_W); !problem.empty()) {
        throwFileError(path, "map frame: " + problem);
      }
    }
  }
  // Version 4: whether colours follow the blocks.
  ColourRecord colour{0};
  const bool has_colour_flag = header.version >= kColourVersion;
  if (has_colour_flag) {
    if (file_bytes < sizeof(header) + sizeof(places_header) + sizeof(map_frame) + sizeof(colour) ||
        !in.read(reinterpret_cast<char*>(&colour), sizeof(colour))) {
      throwFileError(path, "truncated in the colour flag");
    }
    hash.add(&colour, sizeof(colour));
    if (colour.holds_colour > 1) {
      throwFileError(path, "colour flag " + std::to_string(colour.holds_colour) + " is neither 0 nor 1");
    }
  }
  // The length must match the counts exactly before anything is allocated for blocks or keyframes.
  const uint64_t block_bytes = sizeof(MapFileBlock) + (colour.holds_colour ? kBlockColourBytes : 0);
  const uint64_t headers = sizeof(header) + (has_places ? sizeof(places_header) : 0) +
                           (has_map_frame ? sizeof(map_frame) : 0) + (has_colour_flag ? sizeof(colour) : 0);
  const uint64_t payload = file_bytes - headers;
  // In 64 bits the sum may wrap for counts no file could hold: say so rather than a wrong size.
  const uint64_t limit = UINT64_MAX / 4;
  const bool representable = header.block_count < limit / block_bytes &&
                             (keyframe_bytes == 0 || places_header.keyframe_count < limit / keyframe_bytes);
  const uint64_t expected = representable ? header.block_count * block_bytes +
                                                places_header.keyframe_count * keyframe_bytes + sizeof(uint64_t)
                                          : 0;
  if (!representable || payload != expected) {
    std::string listed = std::to_string(header.block_count) + " blocks";
    if (has_places) listed += " and " + std::to_string(places_header.keyframe_count) + " keyframes";
    throwFileError(path, "its header lists " + listed + " (" +
                             (representable ? std::to_string(expected) : std::string("more than 2^62")) +
                             " bytes after the header) but the file holds " + std::to_string(payload) +
                             " bytes after the header: truncated or not written by this package");
  }

  SparseTsdfMap map(config);
  if (colour.holds_colour) map.enableColour();
  auto record = std::make_unique<MapFileBlock>();
  try {
    for (uint64_t b = 0; b < header.block_count; ++b) {
      if (!in.read(reinterpret_cast<char*>(record.get()), sizeof(MapFileBlock))) {
        throwFileError(path, "read failed in block " + std::to_string(b));
      }
      hash.add(record.get(), sizeof(MapFileBlock));
      const SparseTsdfMap::BlockIndex index(record->index[0], record->index[1], record->index[2]);
      std::ostringstream where;
      where << "block " << b << " at (" << index.transpose() << ")";
      if (!SparseTsdfMap::inKeyRange(index)) throwFileError(path, where.str() + " lies beyond the map's reach");
      if (map.find(index)) throwFileError(path, where.str() + " appears twice");
      for (int v = 0; v < kBlockVoxels; ++v) {
        const std::string problem = voxelProblem(record->voxels[v], config.positive_truncation_m);
        if (!problem.empty()) throwFileError(path, where.str() + ", voxel " + std::to_string(v) + ": " + problem);
      }
      VoxelBlock& block = map.allocate(index);
      std::copy(record->voxels, record->voxels + kBlockVoxels, block.voxels.begin());
      if (colour.holds_colour) {
        if (!in.read(reinterpret_cast<char*>(block.colours.data()), kBlockColourBytes)) {
          throwFileError(path, "read failed in the colours of block " + std::to_string(b));
        }
        hash.add(block.colours.data(), kBlockColourBytes);
      }
    }
  } catch (const std::bad_alloc&) {
    throwFileError(path, "not enough memory for its " + std::to_string(header.block_count) + " blocks");
  }
  SavedPlaces saved;
  saved.descriptor = descriptor;
  std::vector<uint8_t> code(static_cast<size_t>(has_places ? descriptor.fern_count : 0));
  for (uint64_t k = 0; k < places_header.keyframe_count; ++k) {
    KeyframePose pose;
    if (!in.read(reinterpret_cast<char*>(&pose), sizeof(pose)) ||
        !in.read(reinterpret_cast<char*>(code.data()), static_cast<std::streamsize>(code.size()))) {
      throwFileError(path, "read failed in keyframe " + std::to_string(k));
    }
    hash.add(&pose, sizeof(pose));
    hash.add(code.data(), code.size());
    const std::string problem = keyframeProblem(pose, code.data(), descriptor);
    if (!problem.empty()) throwFileError(path, "keyframe " + std::to_string(k) + ": " + problem);
    Keyframe keyframe;
    keyframe.T_W_C = poseOf(pose);
    keyframe.code = code;
    saved.keyframes.push_back(std::move(keyframe));
  }
  uint64_t checksum = 0;
  if (!in.read(reinterpret_cast<char*>(&checksum), sizeof(checksum)) || checksum != hash.value()) {
    throwFileError(path, "checksum mismatch: the file is corrupt");
  }
  if (places) {
    places->reset();
    if (has_places) *places = std::move(saved);
  }
  if (T_map_W) {
    T_map_W->reset();
    if (map_frame.known == 1) *T_map_W = poseOf(map_frame.T_map_W);
  }
  return map;
}

}  // namespace sdf_tracker::io
