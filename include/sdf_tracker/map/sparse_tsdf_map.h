#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "sdf_tracker/map/block_table.h"
#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"

namespace sdf_tracker {

/// Voxels along each edge of a block.
constexpr int kBlockSide = 8;
constexpr int kBlockVoxels = kBlockSide * kBlockSide * kBlockSide;

/// Blocks along each edge of a chunk: the coarser unit in which the mesh is published
/// (ChunkedMesher) and swapped blocks are listed (MapMemoryBudget). 4^3 blocks, 0.64 m at 2 cm.
constexpr int kChunkShift = 2;
constexpr int kChunkBlocks = 1 << kChunkShift;

/// A box of block (or chunk) indices, both ends included; empty when last < first on an axis.
struct BlockBox {
  Eigen::Vector3i first = Eigen::Vector3i::Zero();
  Eigen::Vector3i last = -Eigen::Vector3i::Ones();

  bool empty() const { return (last.array() < first.array()).any(); }
  bool contains(const Eigen::Vector3i& index) const {
    return (index.array() >= first.array()).all() && (index.array() <= last.array()).all();
  }
  /// Indices it holds (a double: a box may hold more than size_t counts).
  double count() const { return empty() ? 0.0 : (last - first + Eigen::Vector3i::Ones()).cast<double>().prod(); }
  /// Calls fn(index) for every index, x fastest.
  template <typename Fn>
  void forEach(Fn&& fn) const {
    for (int z = first.z(); z <= last.z(); ++z) {
      for (int y = first.y(); y <= last.y(); ++y) {
        for (int x = first.x(); x <= last.x(); ++x) fn(Eigen::Vector3i(x, y, z));
      }
    }
  }
};

/// A cube of kBlockSide^3 voxels, x fastest, then y, then z. Cache-line aligned, so a row of
/// voxels along x is one line and a trilinear sample inside the block reads at most four.
struct alignas(64) VoxelBlock {
  std::array<Voxel, kBlockVoxels> voxels;
  /// The map's revision when a voxel of this block last changed, or when the block came back
  /// into the map from a swap file (see SparseTsdfMap::revision()).
  uint64_t changed_at = 0;
  /// A colour per voxel, in the voxels' order, in a map that holds colour; empty in one that
  /// does not (SparseTsdfMap::holdsColour()).
  std::vector<VoxelColour> colours;

  static int index(int x, int y, int z) { return (z * kBlockSide + y) * kBlockSide + x; }
  static int index(const Eigen::Vector3i& local) { return index(local.x(), local.y(), local.z()); }
};

/// A TSDF stored in voxel blocks that exist only where a measurement's truncation band reached:
/// memory grows with the observed surface, not with the extent. Block b holds the voxels
/// kBlockSide * b + [0, kBlockSide)^3 of the lattice; voxels of blocks that do not exist are
/// unobserved. Blocks are added and changed by one writer; concurrent reads are safe while
/// nothing writes.
class SparseTsdfMap : public TsdfMap {
 public:
  using BlockIndex = Eigen::Vector3i;

  /// Throws std::invalid_argument naming every violation of the config (whose type it sets to
  /// sparse; dims are not read).
  explicit SparseTsdfMap(const VolumeConfig& config);
  SparseTsdfMap(const SparseTsdfMap&) = default;
  SparseTsdfMap& operator=(const SparseTsdfMap&) = default;
  SparseTsdfMap(SparseTsdfMap&&) = default;
  SparseTsdfMap& operator=(SparseTsdfMap&&) = default;

  /// The block holding a lattice voxel, and the voxel's place in it.
  static BlockIndex blockOf(const Eigen::Vector3i& voxel) {
    return {voxel.x() >> kBlockShift, voxel.y() >> kBlockShift, voxel.z() >> kBlockShift};
  }
  static Eigen::Vector3i localOf(const Eigen::Vector3i& voxel) {
    return {voxel.x() & kLocalMask, voxel.y() & kLocalMask, voxel.z() & kLocalMask};
  }
  /// The lattice voxel at a block's local (0, 0, 0).
  static Eigen::Vector3i firstVoxel(const BlockIndex& block) { return block * kBlockSide; }
  /// A block index packed into 64 bits (21 bits per axis: +-2^20 blocks, 167 km at 2 cm voxels),
  /// and back; keys sort in the order blockIndices() lists. Indices beyond that reach wrap.
  static uint64_t keyOf(const BlockIndex& block) {
    constexpr uint64_t mask = (1ull << kKeyBits) - 1;
    return (static_cast<uint64_t>(block.x() + kMaxBlock + 1) & mask) |
           ((static_cast<uint64_t>(block.y() + kMaxBlock + 1) & mask) << kKeyBits) |
           ((static_cast<uint64_t>(block.z() + kMaxBlock + 1) & mask) << (2 * kKeyBits));
  }
  static BlockIndex indexOf(uint64_t key) {
    constexpr uint64_t mask = (1ull << kKeyBits) - 1;
    return {static_cast<int>(key & mask) - kMaxBlock - 1, static_cast<int>((key >> kKeyBits) & mask) - kMaxBlock - 1,
            static_cast<int>((key >> (2 * kKeyBits)) & mask) - kMaxBlock - 1};
  }
  /// The block indices of these keys, sorted as blockIndices() lists them, without repeats.
  static std::vector<BlockIndex> indicesOf(std::vector<uint64_t> keys);
  /// The block that holds the voxel cell around continuous lattice coordinates (withinReach).
  static BlockIndex blockContaining(const Eigen::Vector3f& lattice) {
    return blockOf(Eigen::Vector3i(static_cast<int>(std::floor(lattice.x())), static_cast<int>(std::floor(lattice.y())),
                                   static_cast<int>(std::floor(lattice.z()))));
  }
  /// Whether continuous lattice coordinates lie within the blocks' reach (false for NaN).
  static bool withinReach(const Eigen::Vector3f& lattice) {
    // Written so that NaN fails the comparison.
    return lattice.cwiseAbs().maxCoeff() < static_cast<float>(kMaxBlock) * kBlockSide;
  }
  /// The blocks that hold the lattice voxels inside box_W; empty when box_W is, or when it leaves
  /// the maps' reach.
  BlockBox blockRange(const Eigen::AlignedBox3f& box_W) const {
    BlockBox blocks;
    if (box_W.isEmpty()) return blocks;
    const Eigen::Vector3f lo = toLattice(box_W.min()), hi = toLattice(box_W.max());
    if (!withinReach(lo) || !withinReach(hi)) return blocks;
    blocks.first = blockContaining(lo);
    blocks.last = blockContaining(hi);
    return blocks;
  }
  /// The chunk that holds a block (kChunkBlocks^3 blocks), the chunks that overlap a box of
  /// blocks, and a chunk's blocks.
  static Eigen::Vector3i chunkOf(const BlockIndex& block) {
    return {block.x() >> kChunkShift, block.y() >> kChunkShift, block.z() >> kChunkShift};
  }
  static BlockBox chunksOf(const BlockBox& blocks) { return {chunkOf(blocks.first), chunkOf(blocks.last)}; }
  static BlockBox blocksOf(const Eigen::Vector3i& chunk) {
    return {chunk * kChunkBlocks, chunk * kChunkBlocks + Eigen::Vector3i::Constant(kChunkBlocks - 1)};
  }
  /// Whether a block index lies within the maps' reach (keyOf() does not wrap).
  /// (Compares each index with both bounds: the absolute value of INT_MIN does not exist.)
  static bool inKeyRange(const BlockIndex& block) {
    return (block.array() >= -kMaxBlock).all() && (block.array() <= kMaxBlock).all();
  }
  /// Block edge length [m].
  float blockSize() const { return kBlockSide * voxelSize(); }

  const VoxelBlock* find(const BlockIndex& block) const {
    return inKeyRange(block) ? blocks_.find(keyOf(block)) : nullptr;
  }
  VoxelBlock* find(const BlockIndex& block) { return inKeyRange(block) ? blocks_.find(keyOf(block)) : nullptr; }
  /// The block, added with every voxel unobserved (and no colour seen) if it did not exist.
  VoxelBlock& allocate(const BlockIndex& block);
  /// Puts `block` in the map under `index`, replacing what was there; its colour is made to agree
  /// with the map's: none seen when the map holds colour and the block brings none, dropped when
  /// the map holds none (call enableColour() first to keep it).
  void insert(const BlockIndex& index, const VoxelBlock& block);
  /// Drops the block (its voxels become unobserved); nothing when it does not exist. A reader's
  /// copy learns of it through removedAt().
  void remove(const BlockIndex& block);
  /// Drops a block added for the change under way that the change left unobserved: no reader
  /// can hold it, so unlike remove() it is not a change for readers.
  void discardUnobserved(const BlockIndex& block);
  size_t blockCount() const { return blocks_.size(); }
  /// Calls fn(index, block) for every block, in no particular order.
  template <typename Fn>
  void forEachBlock(Fn&& fn) {
    blocks_.forEach([&fn](uint64_t key, VoxelBlock& block) { fn(indexOf(key), block); });
  }
  template <typename Fn>
  void forEachBlock(Fn&& fn) const {
    blocks_.forEach([&fn](uint64_t key, const VoxelBlock& block) { fn(indexOf(key), block); });
  }
  /// Calls fn(index, block) for every block in `box`, in no particular order, at the cost of the
  /// smaller of the box and the map: a box much smaller than the map costs the same however large
  /// the map grows.
  template <typename Fn>
  void forEachBlockIn(const BlockBox& box, Fn&& fn) const {
    if (box.count() > static_cast<double>(blocks_.size())) {
      forEachBlock([&](const BlockIndex& index, const VoxelBlock& block) {
        if (box.contains(index)) fn(index, block);
      });
    } else {
      box.forEach([&](const BlockIndex& index) {
        if (const VoxelBlock* block = find(index)) fn(index, *block);
      });
    }
  }
  /// The same, with the blocks writable.
  template <typename Fn>
  void forEachBlockIn(const BlockBox& box, Fn&& fn) {
    static_cast<const SparseTsdfMap*>(this)->forEachBlockIn(
        box, [&fn](const BlockIndex& index, const VoxelBlock& block) { fn(index, const_cast<VoxelBlock&>(block)); });
  }
  /// Every block's index, in a fixed (sorted) order.
  std::vector<BlockIndex> blockIndices() const;
  /// A lattice voxel; unobserved (Dmax, 0) where no block holds it. Not for hot loops.
  Voxel voxel(const Eigen::Vector3i& voxel) const;
  /// A lattice voxel's colour; none seen where no block (or no colour) holds it.
  VoxelColour colour(const Eigen::Vector3i& voxel) const;

  /// The smallest box of lattice voxels [first, first + dims) that holds every block; dims is zero
  /// when there is no block.
  void bounds(Eigen::Vector3i* first, Eigen::Vector3i* dims) const;
  /// The voxels [first, first + dims) as a dense grid at their place (unobserved where no block
  /// holds them), e.g. to export a region to ParaView. Throws std::invalid_argument when the grid
  /// would be too large (VolumeConfig::validate).
  TsdfVolume toDense(const Eigen::Vector3i& first, const Eigen::Vector3i& dims) const;

  /// Counts changes: each fusion (and each read-back of swapped blocks) raises it once and stamps
  /// the blocks it changed with it, so a reader can tell which blocks changed since it last
  /// looked; each remove() raises it too (removedAt()).
  uint64_t revision() const { return revision_; }
  uint64_t beginRevision() { return ++revision_; }
  /// The revision of the last clear(): a copy synchronised before it must start afresh.
  uint64_t clearedAt() const { return cleared_at_; }
  /// The revision of the last remove() (e.g. a block swapped out by MapMemoryBudget): a copy
  /// synchronised before it may hold blocks this map no longer holds, which changedSince() does
  /// not list.
  uint64_t removedAt() const { return removed_at_; }
  /// Blocks that changed after `revision` in a fixed (sorted) order.
  std::vector<BlockIndex> changedSince(uint64_t revision) const;
  /// Makes these blocks equal to `source`'s, removing those `source` no longer holds: lets a
  /// reader keep a copy of a live map up to date in short pieces (see changedSince()). Colour
  /// comes too: this map holds colour once `source` does.
  void copyBlocksFrom(const SparseTsdfMap& source, const std::vector<BlockIndex>& blocks);

  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override;
  /// The eight lattice voxels of the cell around p_W, as interpolate() takes them (unobserved
  /// where no block holds one), and p_W's place in the cell ([0, 1) per axis): what sample()
  /// interpolates. False outside the blocks' reach (withinReach).
  bool cellCorners(const Eigen::Vector3f& p_W, Voxel (&corners)[8], Eigen::Vector3f* fraction) const;
  /// A cell of the lattice: the voxel at its lower corner, and where a point lies in it ([0, 1)
  /// per axis). Maps of one grid (VolumeConfig::sameGrid) share their cells.
  struct Cell {
    Eigen::Vector3i base;
    Eigen::Vector3f fraction;
  };
  /// The cell around p_W; false outside the blocks' reach (withinReach), as cellCorners().
  bool cellAt(const Eigen::Vector3f& p_W, Cell* cell) const;
  /// The eight voxels of a cell (cellAt() of this map or one of its grid), as cellCorners() gives
  /// them.
  void corners(const Cell& cell, Voxel (&corners)[8]) const;
  class RegionReader;
  /// A RegionReader: samples in region_W need no hash lookup (about a block's table probe per
  /// sample saved).
  std::unique_ptr<FieldSampler> sampler(const Eigen::AlignedBox3f& region_W) const override;
  void clear() override;
  bool holdsColour() const override { return holds_colour_; }
  /// Every block gets a colour per voxel, and every block added later.
  void enableColour() override;
  size_t voxelCount() const override { return blocks_.size() * kBlockVoxels; }
  bool observesNothing() const override;
  size_t memoryBytes() const override;
  std::unique_ptr<TsdfMap> clone() const override { return std::make_unique<SparseTsdfMap>(*this); }

 private:
  static constexpr int kKeyBits = 21;
  static constexpr int kMaxBlock = (1 << (kKeyBits - 1)) - 1;  ///< block indices lie in [-kMaxBlock, kMaxBlock]
  static constexpr int kBlockShift = 3;
  static constexpr int kLocalMask = kBlockSide - 1;
  static_assert(kBlockSide == 1 << kBlockShift, "kBlockSide must be 2^kBlockShift");

  /// The corners of `cell` with the blocks found through findBlock(BlockIndex) -> const VoxelBlock*.
  template <typename FindBlock>
  void cornersVia(const Cell& cell, Voxel (&corners)[8], const FindBlock& findBlock) const;

  BlockTable<VoxelBlock> blocks_;
  uint64_t revision_ = 0;
  uint64_t cleared_at_ = 0;
  uint64_t removed_at_ = 0;
  bool holds_colour_ = false;
};

/// The blocks of a box of block indices around a region of the map in a flat array (null where the
/// map holds none), filled once: samples and cells whose blocks lie in the box read them from it,
/// others go through the map's table. What a loop over a frame's points samples a sparse map
/// through (SparseTsdfMap::sampler()); valid while the map is neither changed nor destroyed.
///
/// Given maps of the same grid `beneath`, it reads them all as one map whose blocks are `map`'s
/// where `map` holds the block, else the first of `beneath` that holds it (what OverlaidMap is
/// read through); then those too must stay unchanged.
class SparseTsdfMap::RegionReader final : public FieldSampler {
 public:
  /// Throws std::invalid_argument when a map beneath is on another grid.
  RegionReader(const SparseTsdfMap& map, const Eigen::AlignedBox3f& region_W,
               std::vector<const SparseTsdfMap*> beneath = {});
  /// As SparseTsdfMap::sample(), with the same result.
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override;
  /// As SparseTsdfMap::cellCorners(), with the same result.
  bool cellCorners(const Eigen::Vector3f& p_W, Voxel (&corners)[8], Eigen::Vector3f* fraction) const;
  /// The eight voxels of a cell (SparseTsdfMap::cellAt() of this map or one of its grid), as
  /// cellCorners() gives them.
  void corners(const Cell& cell, Voxel (&corners)[8]) const;
  const SparseTsdfMap& map() const { return map_; }

 private:
  /// Bounds the array at 2 MiB of pointers (a 10 m cube of 16 cm blocks); larger regions are read
  /// through the table.
  static constexpr double kMaxCells = 1 << 18;

  const VoxelBlock* find(const BlockIndex& block) const {
    // Unsigned, a negative offset compares as large: one test per axis.
    const auto x = static_cast<unsigned>(block.x() - first_.x()), y = static_cast<unsigned>(block.y() - first_.y()),
               z = static_cast<unsigned>(block.z() - first_.z());
    if (x >= static_cast<unsigned>(dims_.x()) || y >= static_cast<unsigned>(dims_.y()) ||
        z >= static_cast<unsigned>(dims_.z())) {
      const uint64_t key = keyOf(block);
      const VoxelBlock* found = map_.blocks_.find(key);
      for (auto under = beneath_.begin(); !found && under != beneath_.end(); ++under) {
        found = (*under)->blocks_.find(key);
      }
      return found;
    }
    return cells_[(z * dims_.y() + y) * dims_.x() + x];
  }

  const SparseTsdfMap& map_;
  std::vector<const SparseTsdfMap*> beneath_;
  BlockIndex first_ = BlockIndex::Zero();
  Eigen::Vector3i dims_ = Eigen::Vector3i::Zero();
  std::vector<const VoxelBlock*> cells_;
};

/// The box that holds every voxel the map may have observed: a sparse map's blocks, a dense grid.
Eigen::AlignedBox3f mappedBox(const TsdfMap& map);
/// The map as a dense grid: a copy of a dense one; the box around every block of a sparse one.
TsdfVolume toDenseVolume(const TsdfMap& map);
/// The lattice voxels of the map inside region_W (world frame, metres; a dense grid's clipped to
/// its extent) as a dense grid at their place, e.g. to look at one room of a large map in
/// ParaView. Throws std::invalid_argument naming the region when it holds fewer than two voxels
/// along an axis, or when the grid would be too large (VolumeConfig::validate).
TsdfVolume toDenseVolume(const TsdfMap& map, const Eigen::AlignedBox3d& region_W);
/// Where toDenseVolume(map, region_W) takes its voxels from: the first lattice voxel and the
/// grid's size. Throws as toDenseVolume does, without allocating anything, so that a region can
/// be checked before it is needed.
struct DenseRegion {
  Eigen::Vector3i first;
  Eigen::Vector3i dims;
  /// The grid's memory, with the voxels of `config` (compact or not).
  uint64_t bytes(const VolumeConfig& config) const;
};
DenseRegion denseRegionOf(const TsdfMap& map, const Eigen::AlignedBox3d& region_W);
/// The map as blocks: a copy of a sparse one; the blocks of a dense one that hold an observed
/// voxel (on the same lattice, so every observed voxel keeps its value).
SparseTsdfMap toSparseMap(const TsdfMap& map);

}  // namespace sdf_tracker
