#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>

#include <Eigen/Geometry>
#include <ros/ros.h>
#include <std_msgs/Header.h>

#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/surface/chunked_mesh.h"

namespace sdf_tracker_ros {

/// A copy of the live map, taken in short pieces so that the tracker is never held up for long.
class MapSnapshot {
 public:
  /// `live` is read only while `map_mutex` is held; `live()` may return nullptr (no map yet).
  MapSnapshot(std::mutex& map_mutex, std::function<const sdf_tracker::TsdfMap*()> live);

  /// Brings the copy up to date in pieces, each under the lock: a dense grid in groups of
  /// `slabs_per_lock` z-slices, a sparse map in groups of `blocks_per_lock` of the blocks changed
  /// since the last update; blocks the live map dropped (MaxMemoryMB) leave the copy, which so
  /// stays as small as the live map. Pieces may come from consecutive frames (as a screen refresh
  /// would); each voxel is consistent. Returns the copy, or nullptr when there is no map.
  const sdf_tracker::TsdfMap* update(int slabs_per_lock = 8, int blocks_per_lock = 256);
  /// Sparse: the copy holds every change of the live map up to this revision of it.
  uint64_t syncedRevision() const { return synced_revision_; }

 private:
  /// Copies the whole live map when there is no copy or it can no longer be brought up to date
  /// (another map replaced it, or it was cleared since); true when it did.
  bool copyAllIfStale(const sdf_tracker::TsdfMap& live);

  std::mutex& map_mutex_;
  std::function<const sdf_tracker::TsdfMap*()> live_;
  std::unique_ptr<sdf_tracker::TsdfMap> copy_;
  uint64_t synced_revision_ = 0;  ///< sparse: the live map's revision the copy holds
};

/// Publishes the map as ~cloud, ~mesh and ~mesh_blocks from a snapshot on its own low-priority
/// thread, each at its rate and only while someone subscribes: map extraction never blocks
/// tracking and takes only what CPU the tracker leaves. ~mesh_blocks sends a sparse map's mesh in
/// chunks, only those that changed (everything again to a new subscriber); a dense grid's as one.
class MapPublisher {
 public:
  /// `T_map_W` gives the map frame's pose in the tracker's world, `stamp` the latest frame's stamp.
  MapPublisher(ros::NodeHandle pnh, std::mutex& map_mutex, std::function<const sdf_tracker::TsdfMap*()> live,
               std::function<Eigen::Isometry3d()> T_map_W, std::function<ros::Time()> stamp, std::string map_frame,
               double cloud_rate_hz, double mesh_rate_hz);
  ~MapPublisher();

  /// On (once colour images come), ~cloud always carries an rgb field (grey, kUnseenColour, before
  /// the map holds colour): rviz's RGB8 colour transformer, once it met a cloud without, would not
  /// come back.
  void setColour(bool colour_on) { colour_ = colour_on; }

 private:
  void run();
  /// ~mesh_blocks: the chunks that changed since the last call (all after a restart).
  void publishMeshBlocks(const sdf_tracker::TsdfMap& map, const std_msgs::Header& header,
                         const Eigen::Isometry3d& T_map_W);

  ros::Publisher cloud_pub_, mesh_pub_, mesh_blocks_pub_;
  MapSnapshot snapshot_;
  std::function<Eigen::Isometry3d()> T_map_W_;
  std::function<ros::Time()> stamp_;
  std::string map_frame_;
  double cloud_period_s_, mesh_period_s_;  ///< 0: never
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::atomic<bool> resend_mesh_blocks_{true};  ///< a new subscriber needs every chunk
  std::atomic<bool> colour_{false};
  sdf_tracker::ChunkedMesher mesher_;
  std::unordered_map<uint64_t, int> chunk_marker_ids_;  ///< chunk key -> marker id
  Eigen::Isometry3d mesh_blocks_T_map_W_ = Eigen::Isometry3d::Identity();
  bool mesh_blocks_held_colour_ = false;  ///< the map held colour at the last ~mesh_blocks update
  std::thread thread_;
};

}  // namespace sdf_tracker_ros
