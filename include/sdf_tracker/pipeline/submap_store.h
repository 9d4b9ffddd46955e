#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/map/block_swap.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/submaps.h"

namespace sdf_tracker {

/// The closed submaps (those before the active one), oldest first: each one's place, and its map,
/// held in memory or, under a memory budget (MaxMemoryMB), written whole to a swap file
/// (swapOut()) and read back for whoever needs it while they hold it (map()). A closed submap is
/// no longer fused into, except the newest during a handover, so what the file holds stays right.
///
/// The places are the tracking thread's. map() may be called from any thread (a loop search reads
/// a submap on its own); add(), swapOut() and clear() are the tracking thread's, and clear() must
/// not run while another thread reads a map it got from map() through a raw pointer.
class SubmapStore {
 public:
  /// Without a swap file nothing can be swapped out.
  explicit SubmapStore(std::unique_ptr<BlockSwapFile> swap = nullptr) : swap_(std::move(swap)) {}
  SubmapStore(const SubmapStore&) = delete;
  SubmapStore& operator=(const SubmapStore&) = delete;

  /// Forgets every submap and takes `swap` as the swap file (none: swapping off).
  void reset(std::unique_ptr<BlockSwapFile> swap);

  size_t size() const { return places_.size(); }
  bool empty() const { return places_.empty(); }
  /// Where submap `node` lies; throws std::out_of_range for no such submap.
  const SubmapPlace& place(int node) const { return places_.at(static_cast<size_t>(node)); }
  SubmapPlace& place(int node) { return places_.at(static_cast<size_t>(node)); }
  /// Every submap's place, by node.
  const std::vector<SubmapPlace>& places() const { return places_; }
  const SubmapPlace& newestPlace() const { return places_.back(); }
  SubmapPlace& newestPlace() { return places_.back(); }

  /// Adds the submap just closed (its map must be a sparse one when swapping is on).
  void add(Submap submap);
  /// Forgets every submap and empties the swap file.
  void clear();

  /// Submap `node`'s map: the one in memory, or read back from the swap file (a copy that lives
  /// while someone holds it; those asking meanwhile share it). Throws std::out_of_range for no
  /// such submap, std::runtime_error when the swap file cannot be read.
  std::shared_ptr<const TsdfMap> map(int node) const;
  /// Submap `node`'s map when it is in memory, else nullptr.
  const TsdfMap* inMemory(int node) const;
  /// The newest one's map, which a handover still fuses into (it is never swapped out).
  TsdfMap& newest();
  /// Whether submap `node` is in the swap file (not in memory).
  bool swapped(int node) const;
  int swappedCount() const;
  /// The box of every voxel submap `node` may have observed (mappedBox(); kept when it went to the
  /// swap file).
  Eigen::AlignedBox3f mappedBox(int node) const;
  /// Bytes the maps in memory hold, copies read back and still held included.
  size_t memoryBytes() const;
  /// The swap file's size (0 without one).
  size_t bytesOnDisk() const;
  /// Whether there is a swap file to swap out to.
  bool swaps() const { return swap_ != nullptr; }
  /// Where the swap file is ("" without one).
  std::string swapDirectory() const { return swap_ ? swap_->directory() : std::string(); }

  /// Writes submap `node` to the swap file and frees its map (a reader holding it keeps it until
  /// it lets go); nothing when it is swapped already. Throws std::logic_error without a swap file
  /// or for the newest submap, and std::runtime_error (the disk is full) naming the directory; the
  /// submap then stays in memory and nothing of it stays in the file.
  void swapOut(int node);

 private:
  struct Stored {
    std::shared_ptr<TsdfMap> map;  ///< null while swapped out
    /// While swapped out: a copy read back that someone still holds.
    mutable std::weak_ptr<const TsdfMap> read_back;
    // While swapped out: what reads it back.
    VolumeConfig config;
    bool holds_colour = false;
    std::vector<SparseTsdfMap::BlockIndex> blocks;  ///< block n is the file's record recordKey(node, n)
    Eigen::AlignedBox3f box;
  };
  /// The swap file's key of block n of submap `node`.
  static uint64_t recordKey(int node, size_t n) { return (static_cast<uint64_t>(node) << 40) | n; }

  std::vector<SubmapPlace> places_;
  std::vector<Stored> stored_;
  std::unique_ptr<BlockSwapFile> swap_;
  mutable std::mutex mutex_;  ///< guards stored_ and swap_
};

}  // namespace sdf_tracker
