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
constexpr uint32_t kMapVersion = 5;
constexpr uint32_t kFirstMapVersion = 1;  ///< no place memory
constexpr uint32_t kPlacesVersion = 2;    ///< from this version on: the place memory
constexpr uint32_t kMapFrameVersion = 3;  ///< from this version on: the map frame
constexpr uint32_t kColourVersion = 4;    ///< from this version on: the colour flag (and colours)
constexpr uint32_t kSubmapsVersion = 5;   ///< from this version on: submaps, their graph, each keyframe's submap

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
/// Version 5's counts, right after ColourRecord: the submaps' records, then the edges', follow.
struct SubmapsRecord {
  uint64_t submap_count;
  uint64_t edge_count;
};
/// A submap's place and how many of the blocks (in submap order) are its.
struct SubmapRecord {
  KeyframePose T_W_anchor;
  KeyframePose T_map_W;
  uint64_t block_count;
  int64_t frames_fused;
  double path_m;
};
/// A pose graph edge: where `to` lies in `from`'s frame, and its information (row-major).
struct EdgeRecord {
  int32_t from;
  int32_t to;
  uint32_t kind;  ///< 0 odometry, 1 loop
  uint32_t reserved;
  KeyframePose T_from_to;
  double information[36];
};
#pragma pack(pop)
static_assert(sizeof(MapFileHeader) == 64 && sizeof(PlacesHeader) == 48 && sizeof(KeyframePose) == 56 &&
                  sizeof(MapFrameRecord) == 64 && sizeof(ColourRecord) == 8 && sizeof(SubmapsRecord) == 16 &&
                  sizeof(SubmapRecord) == 136 && sizeof(EdgeRecord) == 360 && sizeof(Voxel) == 8 &&
                  sizeof(VoxelColour) == 4,
              "the .sdfmap layout is fixed");
constexpr size_t kBlockColourBytes = kBlockVoxels * sizeof(VoxelColour);
/// A record read without a number of its kind (a header).
constexpr uint64_t kNoRecordNumber = UINT64_MAX;

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

/// Why a saved edge cannot be one of the graph ("" when it can; the nodes are checked with the
/// submaps, SubmapGraph::problem).
std::string edgeProblem(const EdgeRecord& edge) {
  if (edge.kind > 1) return "kind " + std::to_string(edge.kind) + " is neither 0 (odometry) nor 1 (loop)";
  if (edge.reserved != 0) return "reserved field " + std::to_string(edge.reserved) + " is not 0";
  if (std::string problem = poseProblem(edge.T_from_to); !problem.empty()) return problem;
  const std::string why =
      informationProblem(Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(edge.information));
  return why.empty() ? "" : "information is " + why;
}

/// A submap to write: its blocks and its place.
struct SubmapToWrite {
  const SparseTsdfMap* map;
  SubmapPlace place;
};

/// Writes version 5 (see the header).
void writeVersion5(const std::string& path, const std::vector<SubmapToWrite>& submaps, const std::vector<PoseEdge>& edges,
                   const std::vector<int>& keyframe_submaps, const PlaceMemory* places,
                   const std::optional<Eigen::Isometry3d>& T_map_W) {
  const SparseTsdfMap& first = *submaps.front().map;
  bool holds_colour = false;
  std::vector<std::vector<SparseTsdfMap::BlockIndex>> indices;
  uint64_t blocks = 0;
  for (size_t i = 0; i < submaps.size(); ++i) {
    if (!submaps[i].map->config().sameLattice(first.config())) {
      throwFileError(path, "not written: submap " + std::to_string(i) + " has another lattice than submap 0");
    }
    holds_colour = holds_colour || submaps[i].map->holdsColour();
    indices.push_back(submaps[i].map->blockIndices());
    blocks += indices.back().size();
  }
  const size_t keyframes = places ? places->keyframes().size() : 0;
  if (keyframe_submaps.size() != keyframes) {
    throwFileError(path, "not written: " + std::to_string(keyframe_submaps.size()) + " keyframes' submaps for " +
                             std::to_string(keyframes) + " keyframes");
  }
  MapFileHeader header;
  std::memcpy(header.magic, kMapMagic, sizeof(kMapMagic));
  header.version = kMapVersion;
  header.block_side = kBlockSide;
  header.voxel_size_m = first.config().voxel_size_m;
  header.positive_truncation_m = first.config().positive_truncation_m;
  for (int axis = 0; axis < 3; ++axis) header.origin_W[axis] = first.config().origin_W[axis];
  header.block_count = blocks;
  const PlacesHeader places_header =
      placesHeaderOf(places ? places->config().descriptor : PlaceDescriptorConfig(), keyframes);
  MapFrameRecord map_frame{};
  map_frame.known = T_map_W ? 1 : 0;
  map_frame.T_map_W = poseRecordOf(T_map_W.value_or(Eigen::Isometry3d::Identity()));
  const ColourRecord colour{holds_colour ? 1u : 0u};
  const SubmapsRecord counts{submaps.size(), edges.size()};

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
  put(&counts, sizeof(counts));
  for (size_t i = 0; i < submaps.size(); ++i) {
    const SubmapPlace& place = submaps[i].place;
    const SubmapRecord submap{poseRecordOf(place.T_W_anchor), poseRecordOf(place.T_map_W), indices[i].size(),
                              place.frames_fused, place.path_m};
    put(&submap, sizeof(submap));
  }
  for (const PoseEdge& edge : edges) {
    EdgeRecord record{edge.from, edge.to, edge.kind == PoseEdgeKind::kLoop ? 1u : 0u, 0u, poseRecordOf(edge.T_from_to), {}};
    Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(record.information) = edge.information;
    put(&record, sizeof(record));
  }
  auto record = std::make_unique<MapFileBlock>();
  const VoxelColour no_colour[kBlockVoxels] = {};
  for (size_t i = 0; i < submaps.size(); ++i) {
    for (const SparseTsdfMap::BlockIndex& index : indices[i]) {
      for (int axis = 0; axis < 3; ++axis) record->index[axis] = index[axis];
      const VoxelBlock& block = *submaps[i].map->find(index);
      std::copy(block.voxels.begin(), block.voxels.end(), record->voxels);
      put(record.get(), sizeof(MapFileBlock));
      if (holds_colour) put(submaps[i].map->holdsColour() ? block.colours.data() : no_colour, kBlockColourBytes);
    }
  }
  for (size_t k = 0; k < keyframes; ++k) {
    const Keyframe& keyframe = places->keyframes()[k];
    const KeyframePose pose = poseRecordOf(keyframe.T_W_C);
    put(&pose, sizeof(pose));
    put(keyframe.code.data(), keyframe.code.size());
    const int32_t submap = keyframe_submaps[k];
    put(&submap, sizeof(submap));
  }
  const uint64_t checksum = hash.value();
  out.stream().write(reinterpret_cast<const char*>(&checksum), sizeof(checksum));
  out.commit();
}

}  // namespace

void writeSparseMap(const std::string& path, const SparseTsdfMap& map, const PlaceMemory* places,
                    const std::optional<Eigen::Isometry3d>& T_map_W) {
  const size_t keyframes = places ? places->keyframes().size() : 0;
  writeVersion5(path, {SubmapToWrite{&map, SubmapPlace()}}, {}, std::vector<int>(keyframes, 0), places, T_map_W);
}

void writeSubmaps(const std::string& path, const SubmapGraph& saved, const PlaceMemory* places,
                  const std::optional<Eigen::Isometry3d>& T_map_W) {
  if (const std::string problem = saved.problem(places ? places->keyframes().size() : 0); !problem.empty()) {
    throwFileError(path, "not written: " + problem);
  }
  std::optional<SparseTsdfMap> grid_as_blocks;  // a dense grid, alone, is stored as its observed blocks
  std::vector<SubmapToWrite> submaps;
  for (const Submap& submap : saved.submaps) {
    if (submap.map->type() == MapType::kSparse) {
      submaps.push_back({&static_cast<const SparseTsdfMap&>(*submap.map), submap.place});
    } else {
      grid_as_blocks = toSparseMap(*submap.map);
      submaps.push_back({&*grid_as_blocks, submap.place});
    }
  }
  writeVersion5(path, submaps, saved.edges, saved.keyframe_submaps, places, T_map_W);
}

SavedMap readSubmaps(const std::string& path) {
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
  uint64_t headers = sizeof(header);
  // Reads `bytes` into `data`, hashed; a short read fails naming `what` (and its number).
  auto readHashed = [&](void* data, size_t bytes, const char* what, uint64_t number = kNoRecordNumber) {
    if (!in.read(static_cast<char*>(data), static_cast<std::streamsize>(bytes))) {
      throwFileError(path, std::string("read failed in ") + what + (number == kNoRecordNumber ? "" : " " + std::to_string(number)));
    }
    hash.add(data, bytes);
  };
  // Reads a fixed record that the version holds, before the file's length is checked.
  auto readRecord = [&](void* record, size_t bytes, const char* where) {
    headers += bytes;
    if (file_bytes < headers) throwFileError(path, std::string("truncated in ") + where);
    readHashed(record, bytes, where);
  };
  // Version 2: the place memory's header, and what its keyframes take.
  PlacesHeader places_header{};
  PlaceDescriptorConfig descriptor;
  uint64_t keyframe_bytes = 0;
  const bool has_places = header.version >= kPlacesVersion;
  const bool has_submaps = header.version >= kSubmapsVersion;
  if (has_places) {
    readRecord(&places_header, sizeof(places_header), "the place memory's header");
    descriptor = descriptorOf(places_header);
    if (const auto violations = descriptor.validate(); !violations.empty()) {
      throwFileError(path, "invalid place descriptor: " + violations.front());
    }
    keyframe_bytes = sizeof(KeyframePose) + static_cast<uint64_t>(descriptor.fern_count) +
                     (has_submaps ? sizeof(int32_t) : 0);
  }
  // Version 3: the map frame.
  MapFrameRecord map_frame{};
  if (header.version >= kMapFrameVersion) {
    readRecord(&map_frame, sizeof(map_frame), "the map frame");
    if (map_frame.known > 1) throwFileError(path, "map frame: flag " + std::to_string(map_frame.known) + " is neither 0 nor 1");
    if (map_frame.known == 1) {
      if (const std::string problem = poseProblem(map_frame.T_map_W); !problem.empty()) {
        throwFileError(path, "map frame: " + problem);
      }
    }
  }
  // Version 4: whether colours follow the blocks.
  ColourRecord colour{0};
  if (header.version >= kColourVersion) {
    readRecord(&colour, sizeof(colour), "the colour flag");
    if (colour.holds_colour > 1) {
      throwFileError(path, "colour flag " + std::to_string(colour.holds_colour) + " is neither 0 nor 1");
    }
  }
  // Version 5: how many submaps and edges (before: one submap, no edge).
  SubmapsRecord counts{1, 0};
  if (has_submaps) readRecord(&counts, sizeof(counts), "the submap count");
  const uint64_t submap_record_bytes = has_submaps ? sizeof(SubmapRecord) : 0;
  // The length must match the counts exactly before anything is allocated for blocks, submaps or
  // keyframes. In 64 bits the sum may wrap for counts no file could hold: say so rather than a
  // wrong size.
  const uint64_t block_bytes = sizeof(MapFileBlock) + (colour.holds_colour ? kBlockColourBytes : 0);
  const uint64_t payload = file_bytes - headers;
  const uint64_t limit = UINT64_MAX / 8;
  const bool representable = header.block_count < limit / block_bytes &&
                             (keyframe_bytes == 0 || places_header.keyframe_count < limit / keyframe_bytes) &&
                             counts.submap_count < limit / sizeof(SubmapRecord) &&
                             counts.edge_count < limit / sizeof(EdgeRecord);
  const uint64_t expected = representable ? header.block_count * block_bytes +
                                                places_header.keyframe_count * keyframe_bytes +
                                                counts.submap_count * submap_record_bytes +
                                                counts.edge_count * sizeof(EdgeRecord) + sizeof(uint64_t)
                                          : 0;
  if (!representable || payload != expected) {
    std::string listed = std::to_string(header.block_count) + " blocks";
    if (has_places) listed += (has_submaps ? ", " : " and ") + std::to_string(places_header.keyframe_count) + " keyframes";
    if (has_submaps) {
      listed += ", " + std::to_string(counts.submap_count) + " submaps and " + std::to_string(counts.edge_count) + " edges";
    }
    throwFileError(path, "its header lists " + listed + " (" +
                             (representable ? std::to_string(expected) : std::string("more than 2^60")) +
                             " bytes after the header) but the file holds " + std::to_string(payload) +
                             " bytes after the header: truncated or not written by this package");
  }
  if (counts.submap_count == 0) throwFileError(path, "it lists no submap");

  SavedMap saved;
  std::vector<uint64_t> submap_blocks;
  if (has_submaps) {
    uint64_t blocks_listed = 0;
    for (uint64_t i = 0; i < counts.submap_count; ++i) {
      SubmapRecord record;
      readHashed(&record, sizeof(record), "submap", i);
      const std::string name = "submap " + std::to_string(i);
      for (const auto& [pose, what] : {std::pair{&record.T_W_anchor, "anchor"}, std::pair{&record.T_map_W, "place"}}) {
        if (const std::string problem = poseProblem(*pose); !problem.empty()) throwFileError(path, name + ": " + what + ": " + problem);
      }
      if (record.block_count > header.block_count - blocks_listed) {
        throwFileError(path, name + " lists " + std::to_string(record.block_count) + " blocks, beyond the " +
                                 std::to_string(header.block_count) + " of the file");
      }
      blocks_listed += record.block_count;
      if (record.frames_fused < 0 || record.frames_fused > INT32_MAX) {
        throwFileError(path, name + ": " + std::to_string(record.frames_fused) + " frames fused");
      }
      if (!std::isfinite(record.path_m) || record.path_m < 0.0 || record.path_m > 1e9) {
        throwFileError(path, name + ": path of " + std::to_string(record.path_m) + " m");
      }
      SubmapPlace place;
      place.T_W_anchor = poseOf(record.T_W_anchor);
      place.T_map_W = poseOf(record.T_map_W);
      place.node = static_cast<int>(i);
      place.frames_fused = static_cast<int>(record.frames_fused);
      place.path_m = record.path_m;
      saved.submaps.submaps.push_back(Submap{nullptr, place});
      submap_blocks.push_back(record.block_count);
    }
    if (blocks_listed != header.block_count) {
      throwFileError(path, "its submaps list " + std::to_string(blocks_listed) + " blocks, its header " +
                               std::to_string(header.block_count));
    }
    for (uint64_t e = 0; e < counts.edge_count; ++e) {
      EdgeRecord record;
      readHashed(&record, sizeof(record), "edge", e);
      if (const std::string problem = edgeProblem(record); !problem.empty()) {
        throwFileError(path, "edge " + std::to_string(e) + ": " + problem);
      }
      PoseEdge edge;
      edge.from = record.from;
      edge.to = record.to;
      edge.kind = record.kind == 1 ? PoseEdgeKind::kLoop : PoseEdgeKind::kOdometry;
      edge.T_from_to = poseOf(record.T_from_to);
      edge.information = Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(record.information);
      saved.submaps.edges.push_back(edge);
    }
  } else {
    saved.submaps.submaps.push_back(Submap{nullptr, SubmapPlace()});
    submap_blocks.push_back(header.block_count);
  }

  auto record = std::make_unique<MapFileBlock>();
  uint64_t b = 0;  // over all submaps, as the messages count them
  try {
    for (size_t i = 0; i < submap_blocks.size(); ++i) {
      auto map = std::make_unique<SparseTsdfMap>(config);
      if (colour.holds_colour) map->enableColour();
      for (uint64_t end = b + submap_blocks[i]; b < end; ++b) {
        readHashed(record.get(), sizeof(MapFileBlock), "block", b);
        const SparseTsdfMap::BlockIndex index(record->index[0], record->index[1], record->index[2]);
        std::ostringstream where;
        where << "block " << b << " at (" << index.transpose() << ")";
        if (has_submaps) where << " of submap " << i;
        if (!SparseTsdfMap::inKeyRange(index)) throwFileError(path, where.str() + " lies beyond the map's reach");
        if (map->find(index)) throwFileError(path, where.str() + " appears twice");
        for (int v = 0; v < kBlockVoxels; ++v) {
          const std::string problem = voxelProblem(record->voxels[v], config.positive_truncation_m);
          if (!problem.empty()) throwFileError(path, where.str() + ", voxel " + std::to_string(v) + ": " + problem);
        }
        VoxelBlock& block = map->allocate(index);
        std::copy(record->voxels, record->voxels + kBlockVoxels, block.voxels.begin());
        if (colour.holds_colour) readHashed(block.colours.data(), kBlockColourBytes, "the colours of block", b);
      }
      saved.submaps.submaps[i].map = std::move(map);
    }
  } catch (const std::bad_alloc&) {
    throwFileError(path, "not enough memory for its " + std::to_string(header.block_count) + " blocks");
  }
  SavedPlaces places;
  places.descriptor = descriptor;
  std::vector<uint8_t> code(static_cast<size_t>(has_places ? descriptor.fern_count : 0));
  for (uint64_t k = 0; k < places_header.keyframe_count; ++k) {
    KeyframePose pose;
    int32_t submap = 0;
    readHashed(&pose, sizeof(pose), "keyframe", k);
    readHashed(code.data(), code.size(), "keyframe", k);
    if (has_submaps) readHashed(&submap, sizeof(submap), "keyframe", k);
    const std::string problem = keyframeProblem(pose, code.data(), descriptor);
    if (!problem.empty()) throwFileError(path, "keyframe " + std::to_string(k) + ": " + problem);
    Keyframe keyframe;
    keyframe.T_W_C = poseOf(pose);
    keyframe.code = code;
    places.keyframes.push_back(std::move(keyframe));
    saved.submaps.keyframe_submaps.push_back(submap);
  }
  uint64_t checksum = 0;
  if (!in.read(reinterpret_cast<char*>(&checksum), sizeof(checksum)) || checksum != hash.value()) {
    throwFileError(path, "checksum mismatch: the file is corrupt");
  }
  if (const std::string problem = saved.submaps.problem(places.keyframes.size()); !problem.empty()) {
    throwFileError(path, problem);
  }
  if (has_places) saved.places = std::move(places);
  if (map_frame.known == 1) saved.T_map_W = poseOf(map_frame.T_map_W);
  return saved;
}

SparseTsdfMap readSparseMap(const std::string& path) {
  std::unique_ptr<TsdfMap> merged = mergeSubmaps(std::move(readSubmaps(path).submaps.submaps));
  return std::move(static_cast<SparseTsdfMap&>(*merged));
}

}  // namespace sdf_tracker::io
