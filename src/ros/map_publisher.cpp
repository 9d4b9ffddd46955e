#include "sdf_tracker/ros/map_publisher.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/surface/surface.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

namespace {

/// Niceness of the extraction thread: it runs on what the tracker leaves of the CPU.
constexpr int kBackgroundNice = 10;

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

MapPublisher::MapPublisher(ros::NodeHandle pnh, std::mutex& map_mutex,
                           std::function<const st::TsdfMap*()> live, std::function<Eigen::Isometry3d()> T_map_W,
                           std::function<ros::Time()> stamp, std::string map_frame, double cloud_rate_hz,
                           double mesh_rate_hz)
    : snapshot_(map_mutex, std::move(live)),
      T_map_W_(std::move(T_map_W)),
      stamp_(std::move(stamp)),
      map_frame_(std::move(map_frame)),
      cloud_period_s_(cloud_rate_hz > 0.0 ? 1.0 / cloud_rate_hz : 0.0),
      mesh_period_s_(mesh_rate_hz > 0.0 ? 1.0 / mesh_rate_hz : 0.0) {
  cloud_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("cloud", 1, true);
  mesh_pub_ = pnh.advertise<visualization_msgs::Marker>("mesh", 1, true);
  // Not latched: each message holds only what changed; a new subscriber is sent everything.
  mesh_blocks_pub_ = pnh.advertise<visualization_msgs::MarkerArray>(
      "mesh_blocks", 1, [this](const ros::SingleSubscriberPublisher&) { resend_mesh_blocks_ = true; });
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
    const st::TsdfMap* map = snapshot_.update();
    if (!map) continue;
    std_msgs::Header header;
    header.stamp = stamp_();
    header.frame_id = map_frame_;
    const Eigen::Isometry3d T_map_W = T_map_W_();
    if (cloud_due) cloud_pub_.publish(toCloudMsg(st::extractSurfaceCloud(*map), header, T_map_W, colour_));
    if (mesh_due) mesh_pub_.publish(toMarker(st::extractMesh(*map), header, T_map_W));
    if (mesh_blocks_due) publishMeshBlocks(*map, header, T_map_W);
  }
}

void MapPublisher::publishMeshBlocks(const st::TsdfMap& map, const std_msgs::Header& header,
                                     const Eigen::Isometry3d& T_map_W) {
  visualization_msgs::MarkerArray array;
  auto clearAll = [&] {
    visualization_msgs::Marker clear;
    clear.header = header;
    clear.ns = "mesh_blocks";
    clear.action = visualization_msgs::Marker::DELETEALL;
    array.markers.push_back(clear);
    chunk_marker_ids_.clear();
  };
  auto chunkMarker = [&](const st::TriangleMesh& mesh, int id) {
    visualization_msgs::Marker marker = toMarker(mesh, header, T_map_W);
    marker.ns = "mesh_blocks";
    marker.id = id;
    if (mesh.triangles.empty()) marker.action = visualization_msgs::Marker::DELETE;
    array.markers.push_back(std::move(marker));
  };
  if (map.type() == st::MapType::kDense) {
    // One marker of the whole mesh; the chunks of a sparse map shown before go.
    resend_mesh_blocks_ = false;
    if (!chunk_marker_ids_.empty()) clearAll();
    chunkMarker(st::extractMesh(map), 0);
  } else {
    // Chunks meshed before the map held colour were sent grey: the first update with colour
    // sends every chunk again, in colour, not only those that changed.
    const bool gained_colour = map.holdsColour() && !mesh_blocks_held_colour_;
    const bool everything =
        resend_mesh_blocks_.exchange(false) || T_map_W.matrix() != mesh_blocks_T_map_W_.matrix() || gained_colour;
    mesh_blocks_T_map_W_ = T_map_W;
    mesh_blocks_held_colour_ = map.holdsColour();
    const auto& sparse = static_cast<const st::SparseTsdfMap&>(map);
    const std::vector<st::ChunkedMesher::Chunk> chunks = mesher_.update(sparse, snapshot_.syncedRevision(), everything);
    if (mesher_.restarted()) clearAll();
    for (const st::ChunkedMesher::Chunk& chunk : chunks) {
      const int next_id = static_cast<int>(chunk_marker_ids_.size()) + 1;  // 0 is the dense grid's
      const auto id = chunk_marker_ids_.emplace(st::SparseTsdfMap::keyOf(chunk.index), next_id);
      chunkMarker(chunk.mesh, id.first->second);
    }
  }
  if (!array.markers.empty()) mesh_blocks_pub_.publish(array);
}

}  // namespace sdf_tracker_ros
