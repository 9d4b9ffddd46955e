#pragma once

#include <string>
#include <vector>

#include <ros/ros.h>

#include "sdf_tracker/SdfTrackerConfig.h"
#include "sdf_tracker/pipeline/parameters.h"

/// All of the node's ROS parameter and dynamic_reconfigure code: the tracker's settings come
/// through the core's parameter table, the node's own options are read here.
namespace sdf_tracker_ros {

/// Frame names per REP 105, without leading slashes.
struct FrameOptions {
  std::string map_frame = "map";
  /// Optional: the robot's odometry frame (REP 105). The robot's odometry owns odom -> base; its
  /// motion between two images is the tracker's prediction, and the node publishes map -> odom.
  std::string odom_frame;
  std::string base_frame;    ///< optional: the body the tracker moves; base -> camera comes from tf
  std::string camera_frame;  ///< empty: the depth image's frame_id
};

/// The node's own options (ROS plumbing).
struct NodeOptions {
  std::string preset = "default";
  /// The private parameters the user set (names as typed): a rule that leaves what was not typed
  /// to the map (Settings::keepToOneMapWhereNeeded) reads them again when a map is loaded.
  std::vector<std::string> given_parameters;
  std::string camera_name = "camera";  ///< c_name
  bool depth_registered = false;
  /// The colour images the map is coloured from (with Colour on); empty: <c_name>/rgb/image_color.
  std::string colour_topic;
  /// The depth is registered to the colour images, pixel for pixel, though not on a
  /// depth_registered topic (the TUM RGB-D benchmark's bags: TUM registered them). Colour is used
  /// only with this or depth_registered.
  bool colour_registered = false;
  /// Whether the depth is registered to the colour images: stated (colour_registered) or the
  /// driver's depth_registered stream.
  bool colourUsable() const { return depth_registered || colour_registered; }
  FrameOptions frames;
  std::string imu_topic;  ///< optional: level the map frame with gravity from this IMU
  double cloud_rate_hz = 1.0;
  double mesh_rate_hz = 0.2;
  int path_length = 10000;  ///< poses kept in ~path; older ones stay in the trajectory file
  /// A frame stamped this much [s] before the last one restarts the map (a bag played again);
  /// 0: never. Frames that go back less, or with 0, are dropped and counted.
  double time_jump_reset_s = 0.0;
  std::string trajectory_file;
  std::string mesh_file;   ///< PLY mesh written at shut-down
  std::string cloud_file;  ///< PLY surface cloud written at shut-down
  std::string load_volume = "none";  ///< LoadVolume
  bool output_triangles = false;     ///< OutputTriangles: triangles.obj at shut-down
  bool output_volume = false;        ///< OutputVolume: sdf_volume.vti at shut-down
  std::string output_directory = ".";
  /// Intrinsics given explicitly (FocalLengthX/Y, CenterPointX/Y): used instead of camera_info.
  bool intrinsics_from_parameters = false;
  /// A TUM RGB-D benchmark camera ("freiburg1", ...) whose published calibration replaces
  /// camera_info's K and D, which in the benchmark's bags are the OpenNI driver's default; empty:
  /// camera_info as published.
  std::string tum_camera;
};

/// Strips leading slashes ("/openni_depth_optical_frame" -> "openni_depth_optical_frame"), as tf2
/// does; the TUM bags of 2011 carry them.
std::string stripSlash(const std::string& frame_id);

/// Reads every private parameter of `pnh` once. Throws std::invalid_argument listing every
/// invalid, mistyped or out-of-range value by its parameter name ("~CellSize must be in ...");
/// nothing is clamped or replaced by a default. `warnings` receives, for the log, the names nobody
/// reads and the parameters the others leave without effect (Settings::withoutEffect); `notes`
/// (for the log, at info) what the settings left to the preset became for this map
/// (Settings::keepToOneMapWhereNeeded).
void readParameters(const ros::NodeHandle& pnh, sdf_tracker::Settings* settings, NodeOptions* options,
                    std::vector<std::string>* warnings, std::vector<std::string>* notes);

/// dynamic_reconfigure <-> the parameter table, typed (no rounding through text).
std::vector<std::pair<std::string, sdf_tracker::ParameterValue>> reconfigureValues(
    const sdf_tracker::SdfTrackerConfig& config);
sdf_tracker::SdfTrackerConfig toReconfigureConfig(const sdf_tracker::Settings& settings);

}  // namespace sdf_tracker_ros
