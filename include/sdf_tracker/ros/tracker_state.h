#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include <ros/time.h>

#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/pipeline/tracked_path.h"

namespace sdf_tracker_ros {

/// What the frame thread, the map publisher and the services share. Every member is guarded by
/// `mutex`; the frame thread holds it while it tracks and fuses one frame.
struct TrackerState {
  std::mutex mutex;
  /// The only copy of the tracker's configuration is the pipeline's own (config()).
  std::unique_ptr<sdf_tracker::SdfPipeline> pipeline;
  /// The camera's pose at every tracked frame, in the tracker's world (the pose graph's map frame:
  /// PoseBroadcaster::T_map_W() places it in ~map_frame): the trajectory file, ~path.
  sdf_tracker::TrackedPath path;
  ros::Time last_stamp;  ///< of the last processed frame
  /// The map was reset or replaced: the frame thread restarts its path and time checks.
  bool restarted = false;
};

}  // namespace sdf_tracker_ros
