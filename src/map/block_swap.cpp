#include "sdf_tracker/map/block_swap.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace sdf_tracker {

namespace {

std::runtime_error swapError(const std::string& what, const std::string& directory) {
  return std::runtime_error("block swap file in " + directory + ": " + what + ": " + std::strerror(errno));
}

}  // namespace

BlockSwapFile::BlockSwapFile(const std::string& directory) : directory_(directory) {
  std::string path = directory + "/sdf_tracker_swap_XXXXXX";
  fd_ = ::mkstemp(path.data());
  if (fd_ < 0) throw swapError("cannot create a file", directory_);
  ::unlink(path.c_str());  // gone from the directory now; the space is freed when fd_ closes
}

BlockSwapFile::~BlockSwapFile() {
  if (fd_ >= 0) ::close(fd_);
}

void BlockSwapFile::put(uint64_t key, const VoxelBlock& block) {
  size_t record;
  const auto existing = record_of_.find(key);
  if (existing != record_of_.end()) {
    record = existing->second;
  } else if (!free_records_.empty()) {
    record = free_records_.back();
  } else {
    record = records_;
  }
  std::vector<char> bytes(kRecordBytes, 0);
  char* at = bytes.data();
  std::memcpy(at, block.voxels.data(), sizeof(block.voxels));
  std::memcpy(at += sizeof(block.voxels), &block.changed_at, sizeof(block.changed_at));
  const uint64_t has_colour = block.colours.size() == static_cast<size_t>(kBlockVoxels) ? 1 : 0;
  std::memcpy(at += sizeof(block.changed_at), &has_colour, sizeof(has_colour));
  if (has_colour) std::memcpy(at + sizeof(has_colour), block.colours.data(), kColourBytes);
  const ssize_t written = ::pwrite(fd_, bytes.data(), kRecordBytes, static_cast<off_t>(record * kRecordBytes));
  if (written != static_cast<ssize_t>(kRecordBytes)) {
    if (written >= 0) errno = ENOSPC;  // a short write: the disk filled up
    throw swapError("cannot write a block", directory_);
  }
  if (existing != record_of_.end()) return;
  if (!free_records_.empty() && free_records_.back() == record) free_records_.pop_back();
  if (record == records_) ++records_;
  record_of_.emplace(key, record);
}

bool BlockSwapFile::read(uint64_t key, VoxelBlock* block) const {
  const auto it = record_of_.find(key);
  if (it == record_of_.end()) return false;
  std::vector<char> bytes(kRecordBytes);
  const ssize_t got = ::pread(fd_, bytes.data(), kRecordBytes, static_cast<off_t>(it->second * kRecordBytes));
  if (got != static_cast<ssize_t>(kRecordBytes)) {
    if (got >= 0) errno = EIO;
    throw swapError("cannot read a block back", directory_);
  }
  const char* at = bytes.data();
  std::memcpy(block->voxels.data(), at, sizeof(block->voxels));
  std::memcpy(&block->changed_at, at += sizeof(block->voxels), sizeof(block->changed_at));
  uint64_t has_colour = 0;
  std::memcpy(&has_colour, at += sizeof(block->changed_at), sizeof(has_colour));
  if (has_colour) {
    block->colours.resize(kBlockVoxels);
    std::memcpy(block->colours.data(), at + sizeof(has_colour), kColourBytes);
  } else {
    block->colours.clear();
  }
  return true;
}

void BlockSwapFile::erase(uint64_t key) {
  const auto it = record_of_.find(key);
  if (it == record_of_.end()) return;
  free_records_.push_back(it->second);
  record_of_.erase(it);
}

void BlockSwapFile::clear() {
  record_of_.clear();
  free_records_.clear();
  records_ = 0;
  if (::ftruncate(fd_, 0) != 0) {
    // Only the space is not given back: the records are rewritten from the start all the same.
  }
}

std::vector<uint64_t> BlockSwapFile::keys() const {
  std::vector<uint64_t> keys;
  keys.reserve(record_of_.size());
  for (const auto& entry : record_of_) keys.push_back(entry.first);
  return keys;
}

MapMemoryBudget::MapMemoryBudget(size_t max_bytes, const std::string& directory)
    : max_bytes_(max_bytes), swap_(directory) {
  if (max_bytes == 0) throw std::invalid_argument("a memory budget of zero bytes");
}

size_t MapMemoryBudget::restore(SparseTsdfMap* map, const BlockBox& box) {
  if (swap_.size() == 0 || box.empty()) return 0;
  std::vector<SparseTsdfMap::BlockIndex> wanted;
  SparseTsdfMap::chunksOf(box).forEach([&](const Eigen::Vector3i& chunk) {
    const auto listed = swapped_by_chunk_.find(SparseTsdfMap::keyOf(chunk));
    if (listed == swapped_by_chunk_.end()) return;
    std::vector<SparseTsdfMap::BlockIndex>& blocks = listed->second;
    // Those in the box leave the list (order does not matter: swap with the last).
    for (size_t n = 0; n < blocks.size();) {
      if (box.contains(blocks[n])) {
        wanted.push_back(blocks[n]);
        blocks[n] = blocks.back();
        blocks.pop_back();
      } else {
        ++n;
      }
    }
    if (blocks.empty()) swapped_by_chunk_.erase(listed);
  });
  // Stamped as changed now: a reader's copy dropped them when they left (removedAt()).
  const uint64_t revision = wanted.empty() ? 0 : map->beginRevision();
  VoxelBlock block;
  for (size_t n = 0; n < wanted.size(); ++n) {
    const uint64_t key = SparseTsdfMap::keyOf(wanted[n]);
    try {
      swap_.read(key, &block);
    } catch (const std::runtime_error&) {
      // The blocks not read stay in the file and listed; the map goes on without them.
      for (size_t m = n; m < wanted.size(); ++m) listSwapped(wanted[m]);
      throw;
    }
    block.changed_at = revision;
    map->insert(wanted[n], block);
    swap_.erase(key);
  }
  return wanted.size();
}

size_t MapMemoryBudget::evict(SparseTsdfMap* map, const BlockBox& keep, const Eigen::Vector3f& centre_W) {
  if (map->memoryBytes() <= max_bytes_) return 0;
  std::vector<std::pair<float, SparseTsdfMap::BlockIndex>> candidates;  // squared distance, block
  const Eigen::Vector3f half_block = Eigen::Vector3f::Constant(0.5f * map->blockSize());
  map->forEachBlock([&](const SparseTsdfMap::BlockIndex& b, const VoxelBlock&) {
    if (keep.contains(b)) return;
    const Eigen::Vector3f centre = map->position(SparseTsdfMap::firstVoxel(b)) + half_block;
    candidates.emplace_back((centre - centre_W).squaredNorm(), b);
  });
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && SparseTsdfMap::keyOf(a.second) < SparseTsdfMap::keyOf(b.second));
  });
  const size_t low_water = static_cast<size_t>(kLowWater * static_cast<double>(max_bytes_));
  size_t evicted = 0;
  for (const auto& candidate : candidates) {
    if (map->memoryBytes() <= low_water) break;
    swap_.put(SparseTsdfMap::keyOf(candidate.second), *map->find(candidate.second));
    listSwapped(candidate.second);
    map->remove(candidate.second);
    ++evicted;
  }
  return evicted;
}

void MapMemoryBudget::listSwapped(const SparseTsdfMap::BlockIndex& block) {
  swapped_by_chunk_[SparseTsdfMap::keyOf(SparseTsdfMap::chunkOf(block))].push_back(block);
}

std::string MapMemoryBudget::takeStartNotice() {
  if (told_of_start_ || swap_.size() == 0) return "";
  told_of_start_ = true;
  std::ostringstream notice;
  notice << "the map reached MaxMemoryMB=" << max_bytes_ / 1048576.0 << ": blocks away from the camera go to a swap file in "
         << swap_.directory() << " and come back when seen again";
  return notice.str();
}

std::string MapMemoryBudget::takeOverrunWarning(const SparseTsdfMap& map) {
  const bool over = map.memoryBytes() > max_bytes_;
  const bool news = over && !was_over_;
  was_over_ = over;
  if (!news) return "";
  std::ostringstream warning;
  warning << std::fixed << std::setprecision(1) << "the map holds " << map.memoryBytes() / 1048576.0
          << " MiB, above MaxMemoryMB=" << max_bytes_ / 1048576.0
          << ": the blocks around the camera's view, which are never swapped, need more; raise MaxMemoryMB "
             "or lower MaxDepth";
  return warning.str();
}

SparseTsdfMap MapMemoryBudget::whole(const SparseTsdfMap& map) const {
  SparseTsdfMap copy = map;
  VoxelBlock block;
  for (uint64_t key : swap_.keys()) {
    swap_.read(key, &block);
    copy.insert(SparseTsdfMap::indexOf(key), block);
  }
  return copy;
}

}  // namespace sdf_tracker
