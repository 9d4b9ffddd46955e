#include "sdf_tracker/ros/map_publisher.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <unordered_set>

#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/surface/surface.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

namespace {

/// Niceness of the extraction thread: it runs on what the tracker leaves of the CPU.
constexpr int kBackgroundNice = 10;
/// ~mesh_blocks messages kept for a subscriber that has not taken them yet.
constexpr uint32_t kMeshBlocksQueue = 100;

}  // namespace

MapSnapshot::MapSnapshot(std::mutex& map_mutex, std::function<const st::TsdfMap*()> live)
    : map_mutex_(map_mutex), live_(std::move(live)) {}

bool MapSnapshot::copyAllIfStale(const st::TsdfMap& live) {
  const bool sparse = live.type() == st::MapType::kSparse;
  const bool stale = !copy_ || copy_->identity() != live.identity() ||
                     (sparse && static_cast<const st::SparseTsdfMap&>(live).clearedAt() > synced_revision_);
  if (!stale) return false;
  copy_ = live.clone();
  if (sparse) synced_revision_ = static_cast<const st::SparseTsdfMap&>(live).revision();
  return true;
}

const st::TsdfMap* MapSnapshot::update(int slabs_per_lock, int blocks_per_lock) {
  std::vector<st::SparseTsdfMap::BlockIndex> changed, removed;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    const st::TsdfMap* live = live_();
    if (!live) return nullptr;
    if (copyAllIfStale(*live)) return copy_.get();
    if (live->type() == st::MapType::kSparse) {
      const auto& sparse = static_cast<const st::SparseTsdfMap&>(*live);
      changed = sparse.changedSince(synced_revision_);
      if (sparse.removedAt() > synced_revision_) {
        // Blocks left the live map (swapped out under MaxMemoryMB): the copy lets them go too,
        // so that it is bounded as the live map is.
        static_cast<const st::SparseTsdfMap&>(*copy_).forEachBlock(
            [&](const st::SparseTsdfMap::BlockIndex& index, const st::VoxelBlock&) {
              if (!sparse.find(index)) removed.push_back(index);
            });
      }
      synced_revision_ = sparse.revision();
    }
  }
  if (copy_->type() == st::MapType::kSparse) {
    auto& copy = static_cast<st::SparseTsdfMap&>(*copy_);
    for (const auto& index : removed) copy.remove(index);
    for (size_t first = 0; first < changed.size(); first += blocks_per_lock) {
      const std::vector<st::SparseTsdfMap::BlockIndex> piece(
          changed.begin() + first, changed.begin() + std::min(changed.size(), first + blocks_per_lock));
      std::lock_guard<std::mutex> lock(map_mutex_);
      const st::TsdfMap* live = live_();
      if (!live || copyAllIfStale(*live)) return copy_.get();
      copy.copyBlocksFrom(static_cast<const st::SparseTsdfMap&>(*live), piece);
    }
    return copy_.get();
  }
  for (int k = 0;; k += slabs_per_lock) {
    std::lock_guard<std::mutex> lock(map_mutex_);
    const st::TsdfMap* live = live_();
    if (!live) return nullptr;
    if (copyAllIfStale(*live)) return copy_.get();
    const auto& dense = static_cast<const st::TsdfVolume&>(*live);
    if (k >= dense.dims().z()) return copy_.get();
    static_cast<st::TsdfVolume&>(*copy_).copySlabsFrom(dense, k, k + slabs_per_lock);
  }
}

MapPublisher::MapPublisher(ros::NodeHandle pnh, std::mutex& map_mutex, std::function<std::vector<LiveMapPart>()> live,
                           std::function<Eigen::Isometry3d()> T_map_W, std::function<ros::Time()> stamp,
                           std::string map_frame, double cloud_rate_hz, double mesh_rate_hz)
    : map_mutex_(map_mutex),
      live_(std::move(live)),
      T_map_W_(std::move(T_map_W)),
      stamp_(std::move(stamp)),
      map_frame_(std::move(map_frame)),
      cloud_period_s_(cloud_rate_hz > 0.0 ? 1.0 / cloud_rate_hz : 0.0),
      mesh_period_s_(mesh_rate_hz > 0.0 ? 1.0 / mesh_rate_hz : 0.0) {
  cloud_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("cloud", 1, true);
  mesh_pub_ = pnh.advertise<visualization_msgs::Marker>("mesh", 1, true);
  // Not latched: each message holds only what changed; a new subscriber is sent everything. A
  // message dropped would lose its chunks for good: a queue that a slow viewer does not overrun.
  mesh_blocks_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
      "mesh_blocks", kMeshBlocksQueue, [this](const ros::SingleSubscriberPublisher&) { resend_mesh_blocks_ = true; });
  if (cloud_period_s_ > 0.0 || mesh_period_s_ > 0.0) thread_ = std::thread(&MapPublisher::run, this);
}

MapPublisher::~MapPublisher() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void MapPublisher::run() {
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), kBackgroundNice);
#ifdef _OPENMP
  omp_set_num_threads(1);  // this thread's own setting: extraction must not compete for both cores
#endif
  using Clock = std::chrono::steady_clock;
  auto periodOf = [](double s) { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s)); };
  Clock::time_point next_cloud = Clock::now() + periodOf(cloud_period_s_);
  Clock::time_point next_mesh = Clock::now() + periodOf(mesh_period_s_);
  const Clock::time_point never = Clock::time_point::max();
  if (cloud_period_s_ <= 0.0) next_cloud = never;
  if (mesh_period_s_ <= 0.0) next_mesh = never;
  while (true) {
    {
      std::unique_lock<std::mutex> lock(wake_mutex_);
      if (wake_.wait_until(lock, std::min(next_cloud, next_mesh), [this] { return stopping_; })) return;
    }
    const Clock::time_point now = Clock::now();
    const bool cloud_due = now >= next_cloud && cloud_pub_.getNumSubscribers() > 0;
    const bool mesh_due = now >= next_mesh && mesh_pub_.getNumSubscribers() > 0;
    const bool mesh_blocks_due = now >= next_mesh && mesh_blocks_pub_.getNumSubscribers() > 0;
    if (now >= next_cloud) next_cloud = now + periodOf(cloud_period_s_);
    if (now >= next_mesh) next_mesh = now + periodOf(mesh_period_s_);
    if (!cloud_due && !mesh_due && !mesh_blocks_due) continue;
    std_msgs::Header header;
    header.stamp = stamp_();
    header.frame_id = map_frame_;
    if (!updateParts()) continue;
    const Eigen::Isometry3d T_map_W = T_map_W_();
    if (cloud_due || mesh_due) {
      const st::TsdfMap& map = wholeMap();
      if (cloud_due) cloud_pub_.publish(toCloudMsg(st::extractSurfaceCloud(map), header, T_map_W, colour_));
      if (mesh_due) mesh_pub_.publish(toMarker(st::extractMesh(map), header, T_map_W));
    }
    if (mesh_blocks_due) publishMeshBlocks(header, T_map_W);
  }
}

visualization_msgs::Marker MapPublisher::chunkMarker(const st::TriangleMesh& mesh, int id, const std_msgs::Header& header,
                                                     const Eigen::Isometry3d& T_map_part) {
  visualization_msgs::Marker marker = toMarker(mesh, header, T_map_part);
  marker.ns = "mesh_blocks";
  marker.id = id;
  if (mesh.triangles.empty()) marker.action = visualization_msgs::Marker::DELETE;
  return marker;
}

bool MapPublisher::updateParts() {
  std::vector<Eigen::Isometry3d> placements;
  std::vector<bool> swapped;
  {
    std::lock_guard<std::mutex> lock(map_mutex_);
    for (const LiveMapPart& part : live_()) {
      placements.push_back(part.T_W_part);
      swapped.push_back(part.swapped);
    }
  }
  // Parts the map no longer has (a reset, another map loaded): the viewer starts over.
  if (parts_.size() > placements.size()) {
    parts_.resize(placements.size());
    start_over_ = true;
  }
  const auto newPart = [this](size_t index) {
    Part part;
    part.snapshot = std::make_unique<MapSnapshot>(map_mutex_, [this, index]() -> const st::TsdfMap* {
      const std::vector<LiveMapPart> live = live_();
      return index < live.size() ? live[index].map : nullptr;
    });
    return part;
  };
  while (parts_.size() < placements.size()) parts_.push_back(newPart(parts_.size()));
  for (size_t i = 0; i < parts_.size(); ++i) {
    Part& part = parts_[i];
    if (swapped[i]) {
      // Its chunks as sent stay; its copy and mesher's state go (a swapped submap never changes).
      part.swapped = true;
      part.snapshot.reset();
      part.copy = nullptr;
      part.mesher = st::ChunkedMesher();
    } else if (part.swapped) {
      // In memory where a swapped one was: another map replaced the map, and the viewer starts over.
      part = newPart(i);
      start_over_ = true;
    }
    part.T_W_part = placements[i];
    if (part.swapped) continue;
    part.copy = part.snapshot->update();
    if (!part.copy) return false;  // the map changed since the parts were counted: next time
  }
  return !parts_.empty();
}

const st::TsdfMap& MapPublisher::wholeMap() {
  if (parts_.size() == 1 && parts_.front().T_W_part.matrix() == Eigen::Matrix4d::Identity()) return *parts_.front().copy;
  // The submaps before the active one merged once, until one of them changes or moves (a pose
  // graph solution); a submap closed since is merged onto them, and each time the active one.
  std::vector<st::GrowingMerge::Part> closed;
  for (size_t i = 0; i + 1 < parts_.size(); ++i) {
    const Part& part = parts_[i];
    if (part.swapped) continue;
    closed.push_back({{&static_cast<const st::SparseTsdfMap&>(*part.copy), part.T_W_part}, part.copy->identity(),
                      part.snapshot->syncedRevision()});
  }
  const Part& active = parts_.back();
  const st::PlacedMap active_placed{&static_cast<const st::SparseTsdfMap&>(*active.copy), active.T_W_part};
  if (closed.empty()) {
    merged_ = std::make_unique<st::SparseTsdfMap>(st::mergeMaps({active_placed}));
    return *merged_;
  }
  const st::SparseTsdfMap& closed_merged = closed_merge_.update(closed);
  merged_ = std::make_unique<st::SparseTsdfMap>(
      st::mergeMaps({{&closed_merged, Eigen::Isometry3d::Identity()}, active_placed}));
  return *merged_;
}

void MapPublisher::publishMeshBlocks(const std_msgs::Header& header, const Eigen::Isometry3d& T_map_W) {
  visualization_msgs::MarkerArray array;
  auto startOver = [&] {
    visualization_msgs::Marker clear;
    clear.header = header;
    clear.ns = "mesh_blocks";
    clear.action = visualization_msgs::Marker::DELETEALL;
    array.markers.push_back(clear);
    // A swapped part cannot be meshed again: its chunks as sent go out again (as if it moved),
    // under the ids they have, which new ones must not take.
    bool kept = false;
    for (Part& part : parts_) {
      if (part.swapped) {
        part.shown_T_map_part.matrix().setZero();
        kept = kept || !part.chunks.empty();
      } else {
        part.chunks.clear();
      }
    }
    if (!kept) next_marker_id_ = 1;
  };
  const bool resend = resend_mesh_blocks_.exchange(false);
  if (parts_.size() == 1 && parts_.front().copy->type() == st::MapType::kDense) {
    // One marker of the whole mesh; the chunks of a sparse map shown before go.
    if (!dense_shown_) startOver();
    Part& part = parts_.front();
    array.markers.push_back(chunkMarker(st::extractMesh(*part.copy), 0, header, T_map_W * part.T_W_part));
    dense_shown_ = true;
    start_over_ = false;
    mesh_blocks_pub_.publish(array);
    return;
  }
  // The chunks of each part that changed; every chunk of every part when the viewer starts over
  // (a new viewer, a part replaced or cleared, parts dropped): the array then begins with
  // DELETEALL. A part meshed for the first time (a new submap) is only added to.
  bool start_over = resend || start_over_ || dense_shown_;
  std::vector<std::vector<st::ChunkedMesher::Chunk>> updates(parts_.size());
  for (int attempt = 0; attempt < 2; ++attempt) {
    bool restarted = false;
    for (size_t i = 0; i < parts_.size(); ++i) {
      Part& part = parts_[i];
      if (part.swapped) continue;  // its chunks as sent
      const auto& sparse = static_cast<const st::SparseTsdfMap&>(*part.copy);
      // Chunks meshed before the map held colour were sent grey: the first update with colour
      // sends every chunk again, in colour, not only those that changed.
      const bool gained_colour = sparse.holdsColour() && !part.held_colour;
      updates[i] = part.mesher.update(sparse, part.snapshot->syncedRevision(), start_over || gained_colour);
      restarted |= part.mesher.restarted() && part.meshed && !start_over;
      part.meshed = true;
      part.held_colour = sparse.holdsColour();
    }
    if (!restarted) break;
    start_over = true;  // a part's map was replaced or cleared: everything again, from the start
  }
  if (start_over) startOver();
  start_over_ = false;
  dense_shown_ = false;
  for (size_t i = 0; i < parts_.size(); ++i) {
    Part& part = parts_[i];
    const Eigen::Isometry3d T_map_part = T_map_W * part.T_W_part;
    // A part the pose graph moved (or the map frame, restored): its chunks again, at the new place.
    const bool moved = T_map_part.matrix() != part.shown_T_map_part.matrix();
    part.shown_T_map_part = T_map_part;
    std::unordered_set<uint64_t> sent;
    for (st::ChunkedMesher::Chunk& chunk : updates[i]) {
      const uint64_t key = st::SparseTsdfMap::keyOf(chunk.index);
      const auto shown = part.chunks.find(key);
      if (chunk.mesh.triangles.empty()) {
        if (shown == part.chunks.end()) continue;
        array.markers.push_back(chunkMarker(chunk.mesh, shown->second.first, header, T_map_part));
        part.chunks.erase(shown);
        continue;
      }
      const int id = shown != part.chunks.end() ? shown->second.first : next_marker_id_++;
      array.markers.push_back(chunkMarker(chunk.mesh, id, header, T_map_part));
      part.chunks[key] = {id, std::move(chunk.mesh)};
      sent.insert(key);
    }
    if (moved) {
      for (const auto& [key, shown] : part.chunks) {
        if (!sent.count(key)) array.markers.push_back(chunkMarker(shown.second, shown.first, header, T_map_part));
      }
    }
  }
  if (!array.markers.empty()) mesh_blocks_pub_.publish(array);
}

}  // namespace sdf_tracker_ros
