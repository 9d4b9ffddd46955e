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
  uint64_t file_bytes = 0;
  std::ifstream in = openForReading(path, &file_bytes);
  MapFileHeader header;
  if (file_bytes < sizeof(header) || !in.read(reinterpret_cast<char*>(&header), sizeof(header)) ||
      std::memcmp(header.magic, kMapMagic, sizeof(kMapMagic)) != 0) {
    throwFileError(path, "not an sdf_tracker map (.sdfmap) file");
  }
  if (header.version != kMapVersion) {
    throwFileError(path, "format version " + std::to_string(header.version) + "; this build reads version " +
                   std::to_string(kMapVersion));
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
  // The length must match the block count exactly before anything is allocated for the blocks.
  const uint64_t block_bytes = sizeof(MapFileBlock);
  const uint64_t payload = file_bytes - sizeof(header);
  if (payload < sizeof(uint64_t) || (payload - sizeof(uint64_t)) / block_bytes != header.block_count ||
      (payload - sizeof(uint64_t)) % block_bytes != 0) {
    // In 64 bits the product may wrap for a count no file could hold: say so rather than a wrong size.
    const bool representable = header.block_count < (UINT64_MAX - sizeof(uint64_t)) / block_bytes;
    throwFileError(path, "its header lists " + std::to_string(header.block_count) + " blocks (" +
                             (representable ? std::to_string(header.block_count * block_bytes + sizeof(uint64_t))
                                            : std::string("more than 2^64")) +
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
      std::copy(record->voxels, record->voxels + kBlockVoxels, map.allocate(index).voxels.begin());
    }
  } catch (const std::bad_alloc&) {
    throwFileError(path, "not enough memory for its " + std::to_string(header.block_count) + " blocks");
  }
  uint64_t checksum = 0;
  if (!in.read(reinterpret_cast<char*>(&checksum), sizeof(checksum)) || checksum != hash.value()) {
    throwFileError(path, "checksum mismatch: the file is corrupt");
  }
  return map;
}

}  // namespace sdf_tracker::io
