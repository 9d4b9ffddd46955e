#include "sdf_tracker/core/sparse_tsdf_map.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace sdf_tracker {

SparseTsdfMap::SparseTsdfMap(const VolumeConfig& config) : TsdfMap(config, MapType::kSparse) {}

SparseTsdfMap::SparseTsdfMap(const SparseTsdfMap& other)
    : TsdfMap(other), revision_(other.revision_), cleared_at_(other.cleared_at_) {
  blocks_.reserve(other.blocks_.size());
  for (const auto& [key, block] : other.blocks_) blocks_.emplace(key, std::make_unique<VoxelBlock>(*block));
}

SparseTsdfMap& SparseTsdfMap::operator=(const SparseTsdfMap& other) {
  if (this != &other) *this = SparseTsdfMap(other);
  return *this;
}

const VoxelBlock* SparseTsdfMap::find(const BlockIndex& block) const {
  if (!inKeyRange(block)) return nullptr;
  const auto it = blocks_.find(keyOf(block));
  return it == blocks_.end() ? nullptr : it->second.get();
}

VoxelBlock* SparseTsdfMap::find(const BlockIndex& block) {
  return const_cast<VoxelBlock*>(static_cast<const SparseTsdfMap*>(this)->find(block));
}

VoxelBlock& SparseTsdfMap::allocate(const BlockIndex& block) {
  if (!inKeyRange(block)) {
    std::ostringstream msg;
    msg << "block (" << block.transpose() << ") lies beyond the sparse map's reach of " << kMaxBlock
        << " blocks from the origin (" << kMaxBlock * blockSize() << " m)";
    throw std::out_of_range(msg.str());
  }
  std::unique_ptr<VoxelBlock>& slot = blocks_[keyOf(block)];
  if (!slot) {
    slot = std::make_unique<VoxelBlock>();
    slot->voxels.fill(Voxel{positive_truncation_, 0.0f});
  }
  return *slot;
}

void SparseTsdfMap::remove(const BlockIndex& block) {
  if (inKeyRange(block)) blocks_.erase(keyOf(block));
}

std::vector<SparseTsdfMap::BlockIndex> SparseTsdfMap::indicesOf(std::vector<uint64_t> keys) {
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<BlockIndex> indices;
  indices.reserve(keys.size());
  for (uint64_t key : keys) indices.push_back(indexOf(key));
  return indices;
}

std::vector<SparseTsdfMap::BlockIndex> SparseTsdfMap::blockIndices() const {
  std::vector<uint64_t> keys;
  keys.reserve(blocks_.size());
  for (const auto& entry : blocks_) keys.push_back(entry.first);
  return indicesOf(std::move(keys));
}

Voxel SparseTsdfMap::voxel(const Eigen::Vector3i& voxel) const {
  const VoxelBlock* block = find(blockOf(voxel));
  return block ? block->voxels[VoxelBlock::index(localOf(voxel))] : Voxel{positive_truncation_, 0.0f};
}

void SparseTsdfMap::bounds(Eigen::Vector3i* first, Eigen::Vector3i* dims) const {
  if (blocks_.empty()) {
    *first = *dims = Eigen::Vector3i::Zero();
    return;
  }
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(INT_MAX), hi = Eigen::Vector3i::Constant(INT_MIN);
  for (const auto& entry : blocks_) {
    const BlockIndex b = indexOf(entry.first);
    lo = lo.cwiseMin(b);
    hi = hi.cwiseMax(b);
  }
  *first = firstVoxel(lo);
  *dims = (hi - lo + Eigen::Vector3i::Ones()) * kBlockSide;
}

TsdfVolume SparseTsdfMap::toDense(const Eigen::Vector3i& first, const Eigen::Vector3i& dims) const {
  VolumeConfig dense = config_;
  dense.dims = dims;
  dense.origin_W = config_.origin_W + config_.voxel_size_m * first.cast<double>();
  TsdfVolume volume(dense);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z(); ++k) {
    for (int j = 0; j < dims.y(); ++j) {
      for (int i = 0; i < dims.x(); ++i) volume.setVoxel(i, j, k, voxel(first + Eigen::Vector3i(i, j, k)));
    }
  }
  return volume;
}

void SparseTsdfMap::clear() {
  blocks_.clear();
  cleared_at_ = ++revision_;
}

std::vector<SparseTsdfMap::BlockIndex> SparseTsdfMap::changedSince(uint64_t revision) const {
  std::vector<uint64_t> keys;
  for (const auto& [key, block] : blocks_) {
    if (block->changed_at > revision) keys.push_back(key);
  }
  return indicesOf(std::move(keys));
}

void SparseTsdfMap::copyBlocksFrom(const SparseTsdfMap& source, const std::vector<BlockIndex>& blocks) {
  if (!config_.sameGrid(source.config_)) {
    throw std::invalid_argument("copyBlocksFrom: the maps differ in geometry");
  }
  for (const BlockIndex& index : blocks) {
    const VoxelBlock* from = source.find(index);
    if (from) allocate(index) = *from;
    else remove(index);
  }
}

size_t SparseTsdfMap::memoryBytes() const {
  // The blocks, and the hash table's buckets and nodes (key, pointer, next) as libstdc++ lays them out.
  return blocks_.size() * (sizeof(VoxelBlock) + 3 * sizeof(void*)) + blocks_.bucket_count() * sizeof(void*);
}

bool SparseTsdfMap::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  const Eigen::Vector3f g = toLattice(p_W);
  if (!withinReach(g)) return false;
  const Eigen::Vector3f floor_g(std::floor(g.x()), std::floor(g.y()), std::floor(g.z()));
  const Eigen::Vector3i base = floor_g.cast<int>();
  const Eigen::Vector3i local = localOf(base);
  Voxel corners[8];
  if (local.maxCoeff() < kBlockSide - 1) {
    // The whole cell lies in one block (343 of 512 cells): one lookup.
    const VoxelBlock* block = find(blockOf(base));
    if (!block) return false;
    const Voxel* v = block->voxels.data() + VoxelBlock::index(local);
    constexpr int dy = kBlockSide, dz = kBlockSide * kBlockSide;
    corners[0] = v[0], corners[1] = v[1], corners[2] = v[dy], corners[3] = v[dy + 1];
    corners[4] = v[dz], corners[5] = v[dz + 1], corners[6] = v[dz + dy], corners[7] = v[dz + dy + 1];
  } else {
    // The cell straddles blocks along the axes where it sits on the block's last voxel: one
    // lookup per block it touches (two, four or eight).
    const BlockIndex first_block = blockOf(base);
    const int straddled = (local.x() == kLocalMask) | (local.y() == kLocalMask) << 1 | (local.z() == kLocalMask) << 2;
    const VoxelBlock* blocks[8] = {};
    for (int c = 0; c < 8; ++c) {
      const int slot = c & straddled;  // which neighbouring block holds corner c
      if (!blocks[slot]) {
        blocks[slot] = find(first_block + Eigen::Vector3i(slot & 1, (slot >> 1) & 1, (slot >> 2) & 1));
        if (!blocks[slot]) return false;
      }
      const Eigen::Vector3i corner = base + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
      corners[c] = blocks[slot]->voxels[VoxelBlock::index(localOf(corner))];
    }
  }
  return interpolate(corners, g - floor_g, out);
}

TsdfVolume toDenseVolume(const TsdfMap& map) {
  if (map.type() == MapType::kDense) return static_cast<const TsdfVolume&>(map);
  const auto& sparse = static_cast<const SparseTsdfMap&>(map);
  Eigen::Vector3i first, dims;
  sparse.bounds(&first, &dims);
  if (dims.minCoeff() < 2) throw std::invalid_argument("the sparse map holds no block to export");
  return sparse.toDense(first, dims);
}

SparseTsdfMap toSparseMap(const TsdfMap& map) {
  if (map.type() == MapType::kSparse) return static_cast<const SparseTsdfMap&>(map);
  const auto& dense = static_cast<const TsdfVolume&>(map);
  SparseTsdfMap sparse(dense.config());
  const Eigen::Vector3i dims = dense.dims();
  const SparseTsdfMap::BlockIndex last = SparseTsdfMap::blockOf(dims - Eigen::Vector3i::Ones());
  for (int bz = 0; bz <= last.z(); ++bz) {
    for (int by = 0; by <= last.y(); ++by) {
      for (int bx = 0; bx <= last.x(); ++bx) {
        const SparseTsdfMap::BlockIndex index(bx, by, bz);
        const Eigen::Vector3i first = SparseTsdfMap::firstVoxel(index);
        const Eigen::Vector3i end = (first + Eigen::Vector3i::Constant(kBlockSide)).cwiseMin(dims);
        VoxelBlock* block = nullptr;
        for (int k = first.z(); k < end.z(); ++k) {
          for (int j = first.y(); j < end.y(); ++j) {
            for (int i = first.x(); i < end.x(); ++i) {
              const Voxel v = dense.voxel(i, j, k);
              if (v.weight <= 0.0f) continue;
              if (!block) block = &sparse.allocate(index);
              block->voxels[VoxelBlock::index(SparseTsdfMap::localOf({i, j, k}))] = v;
            }
          }
        }
      }
    }
  }
  return sparse;
}

}  // namespace sdf_tracker
