#include "sdf_tracker/pipeline/submap_store.h"

#include <stdexcept>
#include <string>

namespace sdf_tracker {

void SubmapStore::reset(std::unique_ptr<BlockSwapFile> swap) {
  clear();
  std::lock_guard<std::mutex> lock(mutex_);
  swap_ = std::move(swap);
}

void SubmapStore::add(Submap submap) {
  if (!submap.map) throw std::invalid_argument("a submap without a map");
  if (swap_ && submap.map->type() != MapType::kSparse) {
    throw std::invalid_argument("a dense grid cannot be a submap that swaps (submaps are sparse maps)");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  places_.push_back(submap.place);
  Stored stored;
  stored.map = std::move(submap.map);
  stored_.push_back(std::move(stored));
}

void SubmapStore::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  places_.clear();
  stored_.clear();
  if (swap_) swap_->clear();
}

std::shared_ptr<const TsdfMap> SubmapStore::map(int node) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Stored& stored = stored_.at(static_cast<size_t>(node));
  if (stored.map) return stored.map;
  if (std::shared_ptr<const TsdfMap> held = stored.read_back.lock()) return held;
  auto map = std::make_shared<SparseTsdfMap>(stored.config);
  if (stored.holds_colour) map->enableColour();
  VoxelBlock block;
  for (size_t n = 0; n < stored.blocks.size(); ++n) {
    if (!swap_->read(recordKey(node, n), &block)) {
      throw std::runtime_error("the swap file in " + swap_->directory() + " lost a block of submap " +
                               std::to_string(node));
    }
    map->insert(stored.blocks[n], block);
  }
  stored.read_back = map;
  return map;
}

const TsdfMap* SubmapStore::inMemory(int node) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stored_.at(static_cast<size_t>(node)).map.get();
}

TsdfMap& SubmapStore::newest() {
  std::lock_guard<std::mutex> lock(mutex_);
  return *stored_.back().map;  // never swapped (swapOut)
}

bool SubmapStore::swapped(int node) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !stored_.at(static_cast<size_t>(node)).map;
}

int SubmapStore::swappedCount() const {
  std::lock_guard<std::mutex> lock(mutex_);
  int count = 0;
  for (const Stored& stored : stored_) count += stored.map ? 0 : 1;
  return count;
}

Eigen::AlignedBox3f SubmapStore::mappedBox(int node) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Stored& stored = stored_.at(static_cast<size_t>(node));
  return stored.map ? sdf_tracker::mappedBox(*stored.map) : stored.box;
}

size_t SubmapStore::memoryBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  size_t bytes = 0;
  for (const Stored& stored : stored_) {
    if (stored.map) {
      bytes += stored.map->memoryBytes();
    } else if (std::shared_ptr<const TsdfMap> held = stored.read_back.lock()) {
      bytes += held->memoryBytes();
    }
  }
  return bytes;
}

size_t SubmapStore::bytesOnDisk() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return swap_ ? swap_->bytesOnDisk() : 0;
}

void SubmapStore::swapOut(int node) {
  std::lock_guard<std::mutex> lock(mutex_);
  Stored& stored = stored_.at(static_cast<size_t>(node));
  if (!stored.map) return;
  if (!swap_) throw std::logic_error("no swap file to swap submap " + std::to_string(node) + " out to");
  if (static_cast<size_t>(node) + 1 == stored_.size()) {
    throw std::logic_error("the newest submap may still be fused into: it stays in memory");
  }
  const auto& map = static_cast<const SparseTsdfMap&>(*stored.map);  // add() takes only sparse ones
  std::vector<SparseTsdfMap::BlockIndex> blocks = map.blockIndices();
  size_t written = 0;
  try {
    for (; written < blocks.size(); ++written) swap_->put(recordKey(node, written), *map.find(blocks[written]));
  } catch (const std::runtime_error&) {
    for (size_t n = 0; n < written; ++n) swap_->erase(recordKey(node, n));
    throw;
  }
  stored.config = map.config();
  stored.holds_colour = map.holdsColour();
  stored.box = sdf_tracker::mappedBox(map);
  stored.blocks = std::move(blocks);
  stored.map.reset();
}

}  // namespace sdf_tracker
