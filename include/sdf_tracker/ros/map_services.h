#pragma once

#include <functional>
#include <memory>
#include <string>

#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <std_srvs/Trigger.h>

#include <Eigen/Geometry>

#include "sdf_tracker/SavePath.h"
#include "sdf_tracker/SaveRegion.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/ros/parameters.h"
#include "sdf_tracker/ros/pose_broadcaster.h"
#include "sdf_tracker/ros/tracker_state.h"

namespace sdf_tracker_ros {

/// The node's services (~reset, ~relocalise, ~save_mesh, ~save_volume, ~save_volume_region,
/// ~load_volume) and
/// its files written at shut-down (trajectory, mesh, cloud, OutputTriangles, OutputVolume). Saving
/// copies the map under the lock and extracts from the copy, so tracking waits only for the copy.
class MapServices {
 public:
  /// `poses` gives the map frame (for boxes given in the map frame; saved with a .sdfmap, and
  /// restored from one that keeps it).
  /// Throws std::invalid_argument, naming the parameter and the path, when a file to be written at
  /// shut-down could not be: its folder is missing or not writable (checked now, not after the run).
  MapServices(ros::NodeHandle pnh, TrackerState& state, const NodeOptions& options, PoseBroadcaster& poses);

  /// Writes every file the options ask for and says on stdout what it wrote and on stderr what
  /// failed (rosconsole may be gone at shut-down); never throws. False when a write failed.
  bool writeAtShutdown();

 private:
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  /// Forgets where the camera is: the next frames search the whole map for it.
  bool relocalise(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res);
  bool saveMesh(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  bool saveVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  bool saveVolumeRegion(sdf_tracker::SaveRegion::Request& req, sdf_tracker::SaveRegion::Response& res);
  bool loadVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  /// Runs a service's action; its text (or the exception's) becomes the response's message.
  template <typename Response>
  static bool answer(Response& res, const std::function<std::string()>& action);
  /// A copy of the whole map (the submaps merged where the pose graph places them), and when asked
  /// of the trajectory so far (placedTrajectory()), taken under the lock.
  std::unique_ptr<sdf_tracker::TsdfMap> copyMap(std::vector<sdf_tracker::io::StampedPose>* trajectory);
  /// A copy of the submaps and their graph (SdfPipeline::copySubmaps), the trajectory so far and
  /// the place memory (each keyframe in its submap's frame), taken under the lock: what a .sdfmap
  /// keeps.
  sdf_tracker::SubmapGraph copySubmaps(std::vector<sdf_tracker::io::StampedPose>* trajectory,
                                       sdf_tracker::PlaceMemory* places);
  /// The trajectory so far in ~map_frame, each pose where the pose graph places it now (under the
  /// caller's lock).
  std::vector<sdf_tracker::io::StampedPose> placedTrajectory() const;
  void writeTrajectory(const std::vector<sdf_tracker::io::StampedPose>& trajectory) const;
  std::string outputPath(const std::string& requested, const std::string& default_name) const;

  TrackerState& state_;
  NodeOptions options_;
  PoseBroadcaster& poses_;
  ros::ServiceServer reset_srv_, relocalise_srv_, save_mesh_srv_, save_volume_srv_, save_volume_region_srv_, load_volume_srv_;
};

}  // namespace sdf_tracker_ros
