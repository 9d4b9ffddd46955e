#pragma once

#include <optional>
#include <string>
#include <utility>

#include <Eigen/Geometry>
#include <nav_msgs/Odometry.h>

/// The tracker's estimate as nav_msgs/Odometry (~odom), as robot_localization's EKF and the
/// navigation stack read it: the pose of the child frame in the header frame, its covariance
/// row-major over (x, y, z, rotation about x, y, z of the header frame); the twist in the child
/// frame, over the same axes of the child frame.
namespace sdf_tracker_ros {

using Covariance6d = Eigen::Matrix<double, 6, 6>;

/// How fast a camera whose tracking failed may be moving away from its held pose: the pose's
/// standard deviation grows by this much per second without a tracked frame (a hand-held camera,
/// or a robot at walking speed).
constexpr double kHeldSpeed_mps = 1.0;
constexpr double kHeldTurnRate_radps = 1.0;
/// Two messages further apart than this (frames dropped as bad input, blank depth) say nothing of
/// the velocity now: the twist between them is stated unknown, not averaged over the gap.
constexpr double kMaxTwistInterval_s = 0.5;

/// The tracker's covariance of the camera pose (TrackResult::covariance: [rotation; translation]
/// about the camera centre along the tracker's world axes) as the covariance of the pose of a
/// body rigidly attached to the camera, in ROS order (translation, then rotation) along the axes
/// of the map frame: `R_map_W` turns the world's axes into the map's, `camera_to_body_map` is the
/// body's origin minus the camera centre, in the map frame.
Covariance6d bodyPoseCovariance(const Covariance6d& camera_covariance_W, const Eigen::Matrix3d& R_map_W,
                                const Eigen::Vector3d& camera_to_body_map);

/// The tracker's covariance of the camera pose (as above, about the camera centre) along the axes
/// of another world: `R_to_from` turns the axes it is given in into the new ones.
Covariance6d rotatedCovariance(const Covariance6d& camera_covariance, const Eigen::Matrix3d& R_to_from);

/// A covariance (ROS order) after `elapsed_s` without a measurement: kHeldSpeed_mps and
/// kHeldTurnRate_radps of standard deviation added per second.
Covariance6d grownCovariance(const Covariance6d& covariance, double elapsed_s);

/// Builds ~odom from successive poses of the body in the map frame.
class OdometryBuilder {
 public:
  /// `frame_id`: the map frame the poses are in.
  explicit OdometryBuilder(std::string frame_id) : frame_id_(std::move(frame_id)) {}

  /// The message for the body `child_frame_id` at `T_map_body` at `stamp_s`. `covariance` (ROS order, map axes)
  /// for a tracked frame; none for a frame whose pose is held (tracking failed): the last tracked
  /// frame's covariance grown by the time since (grownCovariance). The twist is the motion since
  /// the previous message (its covariance the two poses' summed over the time squared); the first
  /// message's, a held frame's, or one more than kMaxTwistInterval_s after the previous message
  /// says nothing (kUnconstrainedVariance).
  nav_msgs::Odometry build(double stamp_s, const std::string& child_frame_id, const Eigen::Isometry3d& T_map_body,
                           const std::optional<Covariance6d>& covariance);
  /// Forgets the previous poses (after ~reset or a loaded map).
  void restart() { previous_.reset(); last_tracked_.reset(); }

 private:
  struct Sample {
    double stamp_s;
    Eigen::Isometry3d T_map_body;
    Covariance6d covariance;
  };
  std::string frame_id_;
  std::optional<Sample> previous_;      ///< the last message's
  std::optional<Sample> last_tracked_;  ///< the last tracked frame's
};

}  // namespace sdf_tracker_ros
