#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include "sdf_tracker/map/map_merge.h"
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

/// One part of the live map: a submap (the whole map when there are none), and where the pose
/// graph places its frame in the tracker's world.
struct LiveMapPart {
  const sdf_tracker::TsdfMap* map = nullptr;  ///< none while swapped
  Eigen::Isometry3d T_W_part = Eigen::Isometry3d::Identity();
  /// A closed submap in the swap file (MaxMemoryMB): the publisher lets its copy go too.
  bool swapped = false;
};

/// Publishes the map as ~cloud, ~mesh and ~mesh_blocks from a snapshot on its own low-priority
/// thread, each at its rate and only while someone subscribes: map extraction never blocks
/// tracking and takes only what CPU the tracker leaves. ~mesh_blocks sends a sparse map's mesh in
/// chunks, only those that changed (everything again to a new subscriber); a dense grid's as one.
/// A map of submaps: ~cloud and ~mesh show them merged where the pose graph places them (one
/// surface where two overlap); ~mesh_blocks sends each submap's chunks at its place, and when a
/// solution of the graph moves a submap, its chunks again at the new place, not meshed again.
/// A submap swapped out (MaxMemoryMB) leaves the publisher's copies: its chunks stay as sent (and
/// move with it), and ~cloud and ~mesh show the submaps in memory, as for blocks of one map.
class MapPublisher {
 public:
  /// `live` gives the map's parts (SdfPipeline's submaps, oldest first, the active one last; one
  /// part without submaps), read only while `map_mutex` is held; none when there is no map.
  /// `T_map_W` gives the map frame's pose in the tracker's world, `stamp` the latest frame's stamp.
  MapPublisher(ros::NodeHandle pnh, std::mutex& map_mutex, std::function<std::vector<LiveMapPart>()> live,
               std::function<Eigen::Isometry3d()> T_map_W, std::function<ros::Time()> stamp, std::string map_frame,
               double cloud_rate_hz, double mesh_rate_hz);
  ~MapPublisher();

  /// On (once colour images come), ~cloud always carries an rgb field (grey, kUnseenColour, before
  /// the map holds colour): rviz's RGB8 colour transformer, once it met a cloud without, would not
  /// come back.
  void setColour(bool colour_on) { colour_ = colour_on; }

 private:
  /// A part of the map as the publisher holds it: its snapshot, and its chunks as last sent.
  struct Part {
    std::unique_ptr<MapSnapshot> snapshot;
    const sdf_tracker::TsdfMap* copy = nullptr;  ///< the snapshot's, as of the last update
    Eigen::Isometry3d T_W_part = Eigen::Isometry3d::Identity();
    sdf_tracker::ChunkedMesher mesher;
    /// Chunk key -> marker id and mesh, of the chunks shown: a part moved is sent again from them.
    std::unordered_map<uint64_t, std::pair<int, sdf_tracker::TriangleMesh>> chunks;
    Eigen::Isometry3d shown_T_map_part = Eigen::Isometry3d::Identity();  ///< where they were sent
    bool held_colour = false;  ///< the part held colour at the last ~mesh_blocks update
    bool meshed = false;       ///< it was on ~mesh_blocks before
    bool swapped = false;      ///< its submap went to the swap file: no snapshot, no copy
  };

  void run();
  /// Brings the parts up to date with the live map (parts it no longer has are dropped, and the
  /// next ~mesh_blocks message starts over); false when there is no map.
  bool updateParts();
  /// The whole map in the tracker's world: the one part, or the parts merged where they lie.
  const sdf_tracker::TsdfMap& wholeMap();
  /// ~mesh_blocks: the chunks that changed since the last call (all after a restart), and every
  /// chunk of a part that moved.
  void publishMeshBlocks(const std_msgs::Header& header, const Eigen::Isometry3d& T_map_W);
  /// A chunk's marker on ~mesh_blocks (a deletion for an empty mesh).
  static visualization_msgs::Marker chunkMarker(const sdf_tracker::TriangleMesh& mesh, int id,
                                                const std_msgs::Header& header, const Eigen::Isometry3d& T_map_part);

  ros::Publisher cloud_pub_, mesh_pub_, mesh_blocks_pub_;
  std::mutex& map_mutex_;
  std::function<std::vector<LiveMapPart>()> live_;
  std::vector<Part> parts_;
  std::unique_ptr<sdf_tracker::TsdfMap> merged_;  ///< wholeMap() of several parts
  /// The parts before the active one, merged (wholeMap()).
  sdf_tracker::GrowingMerge closed_merge_;
  bool start_over_ = false;  ///< parts were dropped: the next ~mesh_blocks message starts over
  std::function<Eigen::Isometry3d()> T_map_W_;
  std::function<ros::Time()> stamp_;
  std::string map_frame_;
  double cloud_period_s_, mesh_period_s_;  ///< 0: never
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::atomic<bool> resend_mesh_blocks_{true};  ///< a new subscriber needs every chunk
  std::atomic<bool> colour_{false};
  bool dense_shown_ = false;  ///< ~mesh_blocks holds a dense grid's one marker (id 0)
  int next_marker_id_ = 1;    ///< of a chunk; 0 is the dense grid's
  std::thread thread_;
};

}  // namespace sdf_tracker_ros
