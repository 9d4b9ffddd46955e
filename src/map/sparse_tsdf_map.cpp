#include "sdf_tracker/map/sparse_tsdf_map.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace sdf_tracker {

SparseTsdfMap::SparseTsdfMap(const VolumeConfig& config) : TsdfMap(config, MapType::kSparse) {}

VoxelBlock& SparseTsdfMap::allocate(const BlockIndex& block) {
  if (!inKeyRange(block)) {
    std::ostringstream msg;
    msg << "block (" << block.transpose() << ") lies beyond the sparse map's reach of " << kMaxBlock
        << " blocks from the origin (" << kMaxBlock * blockSize() << " m)";
    throw std::out_of_range(msg.str());
  }
  return blocks_.findOrInsert(keyOf(block), [this] {
    auto fresh = std::make_unique<VoxelBlock>();
    fresh->voxels.fill(Voxel{positive_truncation_, 0.0f});
    if (holds_colour_) fresh->colours.assign(kBlockVoxels, VoxelColour{});
    return fresh;
  });
}

void SparseTsdfMap::insert(const BlockIndex& index, const VoxelBlock& block) {
  VoxelBlock& into = allocate(index);
  into = block;
  if (!holds_colour_) {
    std::vector<VoxelColour>().swap(into.colours);
  } else if (into.colours.size() != static_cast<size_t>(kBlockVoxels)) {
    into.colours.assign(kBlockVoxels, VoxelColour{});
  }
}

void SparseTsdfMap::enableColour() {
  if (holds_colour_) return;
  holds_colour_ = true;
  blocks_.forEach([](uint64_t, VoxelBlock& block) { block.colours.assign(kBlockVoxels, VoxelColour{}); });
}

void SparseTsdfMap::remove(const BlockIndex& block) {
  if (inKeyRange(block) && blocks_.erase(keyOf(block))) removed_at_ = ++revision_;
}

void SparseTsdfMap::discardUnobserved(const BlockIndex& block) {
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
  blocks_.forEach([&keys](uint64_t key, const VoxelBlock&) { keys.push_back(key); });
  return indicesOf(std::move(keys));
}

Voxel SparseTsdfMap::voxel(const Eigen::Vector3i& voxel) const {
  const VoxelBlock* block = find(blockOf(voxel));
  return block ? block->voxels[VoxelBlock::index(localOf(voxel))] : Voxel{positive_truncation_, 0.0f};
}

VoxelColour SparseTsdfMap::colour(const Eigen::Vector3i& voxel) const {
  const VoxelBlock* block = find(blockOf(voxel));
  return block && !block->colours.empty() ? block->colours[VoxelBlock::index(localOf(voxel))] : VoxelColour{};
}

void SparseTsdfMap::bounds(Eigen::Vector3i* first, Eigen::Vector3i* dims) const {
  if (blocks_.empty()) {
    *first = *dims = Eigen::Vector3i::Zero();
    return;
  }
  Eigen::Vector3i lo = Eigen::Vector3i::Constant(INT_MAX), hi = Eigen::Vector3i::Constant(INT_MIN);
  forEachBlock([&lo, &hi](const BlockIndex& b, const VoxelBlock&) {
    lo = lo.cwiseMin(b);
    hi = hi.cwiseMax(b);
  });
  *first = firstVoxel(lo);
  *dims = (hi - lo + Eigen::Vector3i::Ones()) * kBlockSide;
}

namespace {

/// The lattice voxels [first, first + dims) of a map on `lattice`, read through voxelAt(index)
/// (and, when `colourAt` is given, their colours through it), as a dense grid at their place.
template <typename VoxelAt, typename ColourAt>
TsdfVolume cropOf(const VolumeConfig& lattice, const Eigen::Vector3i& first, const Eigen::Vector3i& dims,
                  const VoxelAt& voxelAt, const ColourAt* colourAt) {
  VolumeConfig crop = lattice;
  crop.dims = dims;
  crop.origin_W = lattice.origin_W + lattice.voxel_size_m * first.cast<double>();
  TsdfVolume volume(crop);
  if (colourAt) volume.enableColour();
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z(); ++k) {
    for (int j = 0; j < dims.y(); ++j) {
      for (int i = 0; i < dims.x(); ++i) {
        const Eigen::Vector3i voxel = first + Eigen::Vector3i(i, j, k);
        volume.setVoxel(i, j, k, voxelAt(voxel));
        if (colourAt) volume.setColour(i, j, k, (*colourAt)(voxel));
      }
    }
  }
  return volume;
}

}  // namespace

TsdfVolume SparseTsdfMap::toDense(const Eigen::Vector3i& first, const Eigen::Vector3i& dims) const {
  const auto colourAt = [this](const Eigen::Vector3i& index) { return colour(index); };
  return cropOf(config_, first, dims, [this](const Eigen::Vector3i& index) { return voxel(index); },
                holds_colour_ ? &colourAt : nullptr);
}

bool SparseTsdfMap::observesNothing() const {
  bool nothing = true;
  blocks_.forEach([&nothing](uint64_t, const VoxelBlock& block) {
    nothing = nothing && std::none_of(block.voxels.begin(), block.voxels.end(), [](const Voxel& v) { return v.weight > 0.0f; });
  });
  return nothing;
}

void SparseTsdfMap::clear() {
  blocks_.clear();
  holds_colour_ = false;
  cleared_at_ = ++revision_;
}

std::vector<SparseTsdfMap::BlockIndex> SparseTsdfMap::changedSince(uint64_t revision) const {
  std::vector<uint64_t> keys;
  blocks_.forEach([&keys, revision](uint64_t key, const VoxelBlock& block) {
    if (block.changed_at > revision) keys.push_back(key);
  });
  return indicesOf(std::move(keys));
}

void SparseTsdfMap::copyBlocksFrom(const SparseTsdfMap& source, const std::vector<BlockIndex>& blocks) {
  if (!config_.sameGrid(source.config_)) {
    throw std::invalid_argument("copyBlocksFrom: the maps differ in geometry");
  }
  if (source.holds_colour_) enableColour();
  for (const BlockIndex& index : blocks) {
    const VoxelBlock* from = source.find(index);
    if (from) insert(index, *from);
    else remove(index);
  }
}

size_t SparseTsdfMap::memoryBytes() const {
  // The blocks (with their colours) and the table's slots.
  const size_t block_bytes = sizeof(VoxelBlock) + (holds_colour_ ? kBlockVoxels * sizeof(VoxelColour) : 0);
  return blocks_.size() * block_bytes + blocks_.capacity() * BlockTable<VoxelBlock>::slotBytes();
}

template <typename FindBlock>
void SparseTsdfMap::cornersVia(const Cell& cell, Voxel (&corners)[8], const FindBlock& findBlock) const {
  const Eigen::Vector3i& base = cell.base;
  const Eigen::Vector3i local = localOf(base);
  const Voxel unobserved{positive_truncation_, 0.0f};
  if (local.maxCoeff() < kBlockSide - 1) {
    // The whole cell lies in one block (343 of 512 cells): one lookup.
    const VoxelBlock* block = findBlock(blockOf(base));
    if (!block) {
      std::fill(std::begin(corners), std::end(corners), unobserved);
      return;
    }
    const Voxel* v = block->voxels.data() + VoxelBlock::index(local);
    constexpr int dy = kBlockSide, dz = kBlockSide * kBlockSide;
    corners[0] = v[0], corners[1] = v[1], corners[2] = v[dy], corners[3] = v[dy + 1];
    corners[4] = v[dz], corners[5] = v[dz + 1], corners[6] = v[dz + dy], corners[7] = v[dz + dy + 1];
  } else {
    // The cell straddles blocks: each corner from its own block.
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3i corner = base + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
      const VoxelBlock* block = findBlock(blockOf(corner));
      corners[c] = block ? block->voxels[VoxelBlock::index(localOf(corner))] : unobserved;
    }
  }
}

bool SparseTsdfMap::cellAt(const Eigen::Vector3f& p_W, Cell* cell) const {
  const Eigen::Vector3f g = toLattice(p_W);
  if (!withinReach(g)) return false;
  const Eigen::Vector3f floor_g(std::floor(g.x()), std::floor(g.y()), std::floor(g.z()));
  cell->fraction = g - floor_g;
  cell->base = floor_g.cast<int>();
  return true;
}

bool SparseTsdfMap::cellCorners(const Eigen::Vector3f& p_W, Voxel (&corners)[8], Eigen::Vector3f* fraction) const {
  Cell cell;
  if (!cellAt(p_W, &cell)) return false;
  this->corners(cell, corners);
  *fraction = cell.fraction;
  return true;
}

void SparseTsdfMap::corners(const Cell& cell, Voxel (&corners)[8]) const {
  // cellAt() checked withinReach(), so every block index is in key range.
  cornersVia(cell, corners, [this](const BlockIndex& block) { return blocks_.find(keyOf(block)); });
}

bool SparseTsdfMap::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  Voxel corners[8];
  Eigen::Vector3f fraction;
  return cellCorners(p_W, corners, &fraction) && interpolate(corners, fraction, out);
}

SparseTsdfMap::RegionReader::RegionReader(const SparseTsdfMap& map, const Eigen::AlignedBox3f& region_W,
                                          std::vector<const SparseTsdfMap*> beneath)
    : map_(map), beneath_(std::move(beneath)) {
  for (const SparseTsdfMap* under : beneath_) {
    if (!under || !under->config().sameGrid(map.config())) {
      throw std::invalid_argument("RegionReader: a map beneath is missing or lies on another grid");
    }
  }
  // A cell at the box's far edge reads the next voxel too.
  const Eigen::AlignedBox3f cells_W(region_W.min(), region_W.max() + Eigen::Vector3f::Constant(map.voxelSize()));
  const BlockBox box = map.blockRange(cells_W);
  if (box.empty() || box.count() > kMaxCells) return;  // read through the table
  first_ = box.first;
  dims_ = box.last - box.first + BlockIndex::Ones();
  cells_.assign(static_cast<size_t>(box.count()), nullptr);
  const auto place = [this](const BlockIndex& index, const VoxelBlock& block) {
    const BlockIndex at = index - first_;
    cells_[(at.z() * dims_.y() + at.y()) * dims_.x() + at.x()] = &block;
  };
  // The lowest first: each map's blocks over those beneath it.
  for (auto under = beneath_.rbegin(); under != beneath_.rend(); ++under) (*under)->forEachBlockIn(box, place);
  map.forEachBlockIn(box, place);
}

bool SparseTsdfMap::RegionReader::cellCorners(const Eigen::Vector3f& p_W, Voxel (&corners)[8],
                                              Eigen::Vector3f* fraction) const {
  Cell cell;
  if (!map_.cellAt(p_W, &cell)) return false;
  this->corners(cell, corners);
  *fraction = cell.fraction;
  return true;
}

void SparseTsdfMap::RegionReader::corners(const Cell& cell, Voxel (&corners)[8]) const {
  map_.cornersVia(cell, corners, [this](const BlockIndex& block) { return find(block); });
}

bool SparseTsdfMap::RegionReader::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  Voxel corners[8];
  Eigen::Vector3f fraction;
  return cellCorners(p_W, corners, &fraction) && map_.interpolate(corners, fraction, out);
}

std::unique_ptr<FieldSampler> SparseTsdfMap::sampler(const Eigen::AlignedBox3f& region_W) const {
  return std::make_unique<RegionReader>(*this, region_W);
}

Eigen::AlignedBox3f mappedBox(const TsdfMap& map) {
  if (map.type() != MapType::kSparse) return map.holdableRegion();
  Eigen::Vector3i first, dims;
  static_cast<const SparseTsdfMap&>(map).bounds(&first, &dims);
  return Eigen::AlignedBox3f(map.position(first), map.position(first + dims - Eigen::Vector3i::Ones()));
}

TsdfVolume toDenseVolume(const TsdfMap& map) {
  if (map.type() == MapType::kDense) return static_cast<const TsdfVolume&>(map);
  const auto& sparse = static_cast<const SparseTsdfMap&>(map);
  Eigen::Vector3i first, dims;
  sparse.bounds(&first, &dims);
  if (dims.minCoeff() < 2) throw std::invalid_argument("the sparse map holds no block to export");
  return sparse.toDense(first, dims);
}

TsdfVolume toDenseVolume(const TsdfMap& map, const Eigen::AlignedBox3d& region_W) {
  const DenseRegion region = denseRegionOf(map, region_W);
  if (map.type() == MapType::kSparse) return static_cast<const SparseTsdfMap&>(map).toDense(region.first, region.dims);
  const auto& dense = static_cast<const TsdfVolume&>(map);
  const auto colourAt = [&dense](const Eigen::Vector3i& v) { return dense.colour(v.x(), v.y(), v.z()); };
  return cropOf(map.config(), region.first, region.dims,
                [&dense](const Eigen::Vector3i& v) { return dense.voxel(v.x(), v.y(), v.z()); },
                dense.holdsColour() ? &colourAt : nullptr);
}

DenseRegion denseRegionOf(const TsdfMap& map, const Eigen::AlignedBox3d& region_W) {
  const VolumeConfig& c = map.config();
  // The lattice voxels inside the box: from the first at or above its minimum to the last at or
  // below its maximum.
  Eigen::Vector3d lo = ((region_W.min() - c.origin_W) / c.voxel_size_m).array().ceil();
  Eigen::Vector3d hi = ((region_W.max() - c.origin_W) / c.voxel_size_m).array().floor();
  if (map.type() == MapType::kDense) {
    lo = lo.cwiseMax(Eigen::Vector3d::Zero());
    hi = hi.cwiseMin((c.dims - Eigen::Vector3i::Ones()).cast<double>());
  }
  const Eigen::Vector3d dims = hi - lo + Eigen::Vector3d::Ones();
  if (!region_W.min().allFinite() || !region_W.max().allFinite() || !(dims.minCoeff() >= 2.0) ||
      !(dims.maxCoeff() <= 4096.0)) {
    std::ostringstream msg;
    msg << "the region from (" << region_W.min().transpose() << ") to (" << region_W.max().transpose()
        << ") m holds " << (dims.array().max(0.0)).transpose() << " voxels of the map's "
        << c.voxel_size_m << " m lattice";
    msg << (map.type() == MapType::kDense ? " inside its grid" : "") << "; a volume needs 2 to 4096 along each axis";
    throw std::invalid_argument(msg.str());
  }
  return {lo.cast<int>(), dims.cast<int>()};
}

uint64_t DenseRegion::bytes(const VolumeConfig& config) const {
  return static_cast<uint64_t>(dims.x()) * dims.y() * dims.z() *
         (config.compact_voxels ? sizeof(CompactVoxel) : sizeof(Voxel));
}

SparseTsdfMap toSparseMap(const TsdfMap& map) {
  if (map.type() == MapType::kSparse) return static_cast<const SparseTsdfMap&>(map);
  const auto& dense = static_cast<const TsdfVolume&>(map);
  SparseTsdfMap sparse(dense.config());
  if (dense.holdsColour()) sparse.enableColour();
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
              const int local = VoxelBlock::index(SparseTsdfMap::localOf({i, j, k}));
              block->voxels[local] = v;
              if (dense.holdsColour()) block->colours[local] = dense.colour(i, j, k);
            }
          }
        }
      }
    }
  }
  return sparse;
}

}  // namespace sdf_tracker
