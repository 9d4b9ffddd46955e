#pragma once

#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include "sdf_tracker/TrackingStatus.h"

namespace sdf_tracker_ros {

/// The node's health on /diagnostics (diagnostic_updater, read by rqt_robot_monitor and
/// diagnostic_aggregator), once a second:
/// - "<node>: frames": frames processed per second against those the camera sent, dropped, the
///   latency from an image's stamp to its pose; ERROR when no frame came for kStaleAfter_s, WARN
///   while more than half of the camera's frames are dropped.
/// - "<node>: tracking": the last status and failures in a row, at the level the log uses: OK
///   when tracked (a degenerate view too, when the robot's odometry gave what it leaves open),
///   WARN for a frame that failed, a degenerate one without odometry, or a search under way,
///   ERROR once tracking is lost (~status's `lost`).
/// - "<node>: odometry", with ~odom_frame only: OK while each frame finds the robot's odometry in
///   tf, WARN naming the missing transform and tf's reason while frames come without it.
/// - "<node>: colour", with Colour on at start: OK while frames are fused in colour, and for a
///   camera that sends no colour images (the map is then made without); WARN when colour images
///   come but cannot be used (the depth is not registered to them, a wrong encoding or size).
/// - "<node>: loop closure", with LoopClosure on at start: the active submap, loops kept, and
///   how far the last pose graph solution moved the camera and when; OK, WARN once the graph has
///   found a loop wrong and left it out (a place match that was not what it seemed).
class NodeDiagnostics {
 public:
  static constexpr double kStaleAfter_s = 3.0;
  /// Seconds of frames the rates are measured over.
  static constexpr double kRateWindow_s = 5.0;

  /// `hardware_id`: the depth topic the node listens on. `odometry_transform`: the robot's
  /// odometry the node reads ("odom -> base_link"), or empty for none (no odometry task).
  NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id,
                  const std::string& odometry_transform = "", const std::string& colour_topic = "",
                  bool loop_closure = false);

  /// A frame's ~status, and the seconds from its image's stamp to its outputs. Frame thread.
  void frameProcessed(const sdf_tracker::TrackingStatus& status, double latency_s);
  /// A frame's odometry lookup: `problem` is why none was found (PoseBroadcaster::
  /// odometryProblem()), empty when it was. Frame thread.
  void odometryLookedUp(const std::string& problem);
  /// A colour image came; `problem`: why it cannot be used at all (empty when it can). Any thread.
  void colourReceived(const std::string& problem);
  /// A frame was fused with colour or without; `problem`: why its colour image was not used
  /// (empty: it was, or none came near it). Frame thread.
  void frameColoured(bool coloured, const std::string& problem);

 private:
  void frames(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void tracking(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void odometry(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void colour(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void loopClosure(diagnostic_updater::DiagnosticStatusWrapper& stat);
  /// Forgets the processed frames older than the rate window.
  void trim(const ros::WallTime& now);

  diagnostic_updater::Updater updater_;
  ros::Timer timer_;
  std::mutex mutex_;  ///< guards the members below
  struct Processed {
    ros::WallTime wall;
    uint32_t frames_received;  ///< the node's count when it was processed
    uint32_t frames_dropped;
    double latency_s;
  };
  std::deque<Processed> window_;
  sdf_tracker::TrackingStatus last_;
  bool any_ = false;
  std::string odometry_transform_;
  std::string odometry_problem_;  ///< the last frame's
  uint32_t frames_with_odometry_ = 0, frames_without_odometry_ = 0, without_odometry_in_a_row_ = 0;
  bool odometry_looked_up_ = false;
  std::string colour_topic_;
  std::string colour_problem_;  ///< the last colour image's or frame's
  uint32_t colour_images_ = 0, frames_coloured_ = 0, frames_uncoloured_ = 0;
  /// The last frame with which a pose graph solution landed (loop_solved), and when.
  std::optional<sdf_tracker::TrackingStatus> last_solution_;
  ros::WallTime last_solution_wall_;
};

}  // namespace sdf_tracker_ros
