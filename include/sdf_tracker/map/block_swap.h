#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "sdf_tracker/map/sparse_tsdf_map.h"

namespace sdf_tracker {

/// Voxel blocks kept on disk, in fixed-size records of an unnamed temporary file: the file is
/// unlinked as soon as it is opened, so the system removes it when the process ends, however it
/// ends. Records freed by read-back are reused. Not thread safe.
class BlockSwapFile {
 public:
  /// Opens the file in `directory`; throws std::runtime_error naming the directory and the reason
  /// when it cannot.
  explicit BlockSwapFile(const std::string& directory);
  ~BlockSwapFile();
  BlockSwapFile(const BlockSwapFile&) = delete;
  BlockSwapFile& operator=(const BlockSwapFile&) = delete;

  /// Writes the block under `key` (SparseTsdfMap::keyOf), replacing what it held. Throws
  /// std::runtime_error (e.g. the disk is full) naming the directory; nothing is stored then.
  void put(uint64_t key, const VoxelBlock& block);
  /// Reads the block under `key`; false when there is none. Throws std::runtime_error on a read
  /// error.
  bool read(uint64_t key, VoxelBlock* block) const;
  /// Forgets the block under `key` (its record is reused).
  void erase(uint64_t key);
  /// Forgets every block and empties the file.
  void clear();

  bool contains(uint64_t key) const { return record_of_.count(key) > 0; }
  size_t size() const { return record_of_.size(); }
  /// The file's size.
  size_t bytesOnDisk() const { return records_ * kRecordBytes; }
  const std::string& directory() const { return directory_; }
  /// Every key held, in no particular order.
  std::vector<uint64_t> keys() const;

 private:
  /// A record: the voxels, the revision stamp, whether the block holds colour, and room for its
  /// colours (zeros when it holds none).
  static constexpr size_t kColourBytes = kBlockVoxels * sizeof(VoxelColour);
  static constexpr size_t kRecordBytes =
      sizeof(VoxelBlock::voxels) + sizeof(VoxelBlock::changed_at) + sizeof(uint64_t) + kColourBytes;

  std::string directory_;
  int fd_ = -1;
  std::unordered_map<uint64_t, size_t> record_of_;
  std::vector<size_t> free_records_;
  size_t records_ = 0;  ///< records the file holds, used or free
};

/// Keeps a sparse map's memory under a budget: blocks away from the camera are written to a
/// BlockSwapFile and dropped from the map, and read back when the camera comes near them again.
/// The map plus the swapped blocks is the whole map (see whole()).
class MapMemoryBudget {
 public:
  /// Throws std::invalid_argument for a budget of zero and std::runtime_error when the swap file
  /// cannot be opened in `directory`.
  MapMemoryBudget(size_t max_bytes, const std::string& directory);

  size_t maxBytes() const { return max_bytes_; }
  const BlockSwapFile& swap() const { return swap_; }

  /// Reads back into the map every swapped block in `box`, stamped as changed at a new revision
  /// (SparseTsdfMap::changedSince), so that a reader's copy takes it again; returns how many.
  size_t restore(SparseTsdfMap* map, const BlockBox& box);
  /// When the map holds more than the budget: writes its blocks outside `keep`, farthest from
  /// `centre_W` first, to the swap file and drops them, until it holds at most kLowWater of the
  /// budget (or only blocks in `keep` are left). Returns how many. A block that cannot be written
  /// stays in the map, and the error (std::runtime_error) is passed on.
  size_t evict(SparseTsdfMap* map, const BlockBox& keep, const Eigen::Vector3f& centre_W);
  /// After evict(): what to tell the user, once, when the first blocks have gone to the swap file
  /// (since the budget was made or cleared); empty otherwise.
  std::string takeStartNotice();
  /// After evict() on `map`: why the map is above the budget (eviction spares the blocks around
  /// the camera's view, and those alone can need more), once each time it goes over; empty while
  /// it stays over and while it holds at most the budget.
  std::string takeOverrunWarning(const SparseTsdfMap& map);
  /// The map with every swapped block put back: what a save or a whole mesh must read.
  SparseTsdfMap whole(const SparseTsdfMap& map) const;
  /// Forgets every swapped block (the map was cleared or replaced); the user is told again when
  /// the next map swaps or goes over.
  void clear() {
    swap_.clear();
    swapped_by_chunk_.clear();
    told_of_start_ = was_over_ = false;
  }

  /// Eviction stops at this fraction of the budget, so it runs now and then, not every frame.
  static constexpr double kLowWater = 0.9;

 private:
  /// Swapped blocks listed by chunk (SparseTsdfMap::chunkOf), so that finding those near a view
  /// probes a few chunks instead of every block of its box or every block swapped.
  void listSwapped(const SparseTsdfMap::BlockIndex& block);

  size_t max_bytes_;
  BlockSwapFile swap_;
  std::unordered_map<uint64_t, std::vector<SparseTsdfMap::BlockIndex>> swapped_by_chunk_;
  bool told_of_start_ = false;  ///< takeStartNotice() has given its notice
  bool was_over_ = false;       ///< the map was above the budget at the last takeOverrunWarning()
};

}  // namespace sdf_tracker
