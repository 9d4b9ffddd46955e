#pragma once

#include <deque>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/ros/odometry.h"
#include "sdf_tracker/ros/parameters.h"

namespace sdf_tracker_ros {

/// The rotation from the tracker's world (the first camera's optical frame: x right, y down,
/// z forward) to the REP 103 map frame (x forward, y left, z up) at the same origin.
Eigen::Isometry3d mapFromOpticalWorld();

/// A map frame whose z axis points against gravity: `up_W` is the measured up direction (the
/// accelerometer's mean reading) in the tracker's world; x stays as close to the first camera's
/// viewing direction as levelling allows. Throws std::invalid_argument for a zero vector or one
/// whose length is not finite.
Eigen::Isometry3d gravityAlignedMapFromOpticalWorld(const Eigen::Vector3d& up_W);

/// What a planar pose request (rviz's "2D Pose Estimate", amcl's /initialpose) means for a body
/// whose pose in the map frame is `T_map_body`: the body moved to `x_m`, `y_m` in the map's
/// horizontal plane and turned about the map's z axis until its heading axis `forward_body`
/// (body x for a robot base, the optical z for a camera) points at `yaw_rad`; its height and its
/// tilt (roll and pitch) are kept. A body whose heading axis is vertical turns its image-up axis
/// `fallback_body` instead.
Eigen::Isometry3d placedOnPlane(const Eigen::Isometry3d& T_map_body, const Eigen::Vector3d& forward_body,
                                const Eigen::Vector3d& fallback_body, double x_m, double y_m, double yaw_rad);

/// Whether an accelerometer reading [m/s^2] can say where up is: finite, and of a magnitude that
/// gravity dominates (kMinGravityReading to kMaxGravityReading). A zero, NaN or absurd reading
/// (a driver's placeholder, a broken sensor) says nothing about gravity.
constexpr double kMinGravityReading = 2.0;
constexpr double kMaxGravityReading = 30.0;
bool isGravityReading(const Eigen::Vector3d& acceleration);

/// What a loaded map brings for the map frame, in words: the frame it was saved with (`saved`),
/// or none, and what the node then publishes in.
std::string describeLoadedMapFrame(bool saved);

/// Puts the tracker's estimate on the tf tree the user already has (REP 105): publishes
/// map -> base, where base is ~base_frame (its mounting base -> camera looked up in tf) or else the
/// camera frame itself, so that map -> camera is the estimate. With ~odom_frame the robot's
/// odometry owns odom -> base, and it publishes the correction map -> odom instead, so that
/// map -> odom -> base -> camera is the estimate. It never gives a frame a
/// second parent: when the frame it would publish already has another parent, it says once which
/// frame, which parent and which parameter to set, and publishes no tf (pose and path go on).
/// Also publishes ~odom (nav_msgs/Odometry of the base, with covariance), and for estimates only
/// (not held poses) ~pose and a bounded ~path. Called from the frame thread only.
class PoseBroadcaster {
 public:
  /// `saved_map_frame`: the frame of a map loaded at start-up that keeps one (see restoreMapFrame).
  PoseBroadcaster(ros::NodeHandle nh, ros::NodeHandle pnh, const NodeOptions& options,
                  const std::optional<Eigen::Isometry3d>& saved_map_frame = std::nullopt);

  /// With ~odom_frame: the camera's pose in the robot's odometry frame at `stamp` (odom -> base
  /// from the robot's odometry, base -> camera its mounting, through tf). While the odometry
  /// flows (tf's latest odom -> base is less than kOdometryStale_s older than the image) it waits
  /// up to kOdometryWait_s for the odometry to catch up with the image; otherwise it does not
  /// wait, so that a missing odometry never holds frames up. None without ~odom_frame, or while
  /// tf lacks it: said in the log when it starts and when it ends, and by odometryProblem().
  std::optional<Eigen::Isometry3d> odometryCameraPose(const ros::Time& stamp, const std::string& image_frame);
  static constexpr double kOdometryWait_s = 0.1;
  static constexpr double kOdometryStale_s = 1.0;
  /// Why the last odometryCameraPose() found no odometry (the transform missing and tf's
  /// reason), or "" when it found one or ~odom_frame is not set.
  const std::string& odometryProblem() const { return odometry_problem_; }

  /// The estimate T_W_C (tracker world <- camera optical frame) for an image of `image_frame`
  /// (its frame_id) at `stamp`, with its covariance (TrackResult::covariance) when the frame was
  /// tracked, none when the pose is held (then it goes on tf and ~odom, with a grown covariance,
  /// but not on ~pose or ~path), and the camera's pose in the robot's odometry frame at that stamp
  /// (odometryCameraPose) when there is one. Returns the camera's pose in the map frame.
  Eigen::Isometry3d publish(const ros::Time& stamp, const std::string& image_frame, const Eigen::Isometry3d& T_W_C,
                            const std::optional<Covariance6d>& covariance_W,
                            const std::optional<Eigen::Isometry3d>& T_odom_C);

  /// The camera pose T_W_C that a pose request on ~initialpose means, for images of `image_frame`
  /// while the tracker holds `T_W_C_held`: x, y and yaw of the request (in its header's frame,
  /// looked up in tf when that is not the map frame) set for ~base_frame (or the camera when
  /// there is none), height, roll and pitch kept from the held pose (placedOnPlane). Throws
  /// std::runtime_error with the reason when it cannot be used (tf missing, values not finite).
  Eigen::Isometry3d requestedCameraPose(const geometry_msgs::PoseWithCovarianceStamped& request,
                                        const std::string& image_frame, const Eigen::Isometry3d& T_W_C_held);

  /// The map frame's pose in the tracker's world, for map products (cloud, mesh).
  Eigen::Isometry3d T_map_W() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return T_map_W_;
  }
  const std::string& mapFrame() const { return frames_.map_frame; }
  /// The map frame once it is fixed (at the first published pose, levelled when an IMU is given,
  /// or restored): what a saved map keeps, so that a later session publishes in the same frame.
  /// None before.
  std::optional<Eigen::Isometry3d> fixedMapFrame() const;
  /// Publishes in `T_map_W` from now on, as the session that saved a loaded map did: it is not
  /// levelled again (levelling from the accelerometer where the camera is found, as it moves,
  /// tilts the frame from the first session's by up to a few degrees, which moves every pose).
  void restoreMapFrame(const Eigen::Isometry3d& T_map_W);
  /// Forgets the path (after ~reset or a loaded map).
  void clearPath();
  /// The path placed anew (a pose graph solution moved it): its last ~path_length poses replace
  /// ~path. `path_W`: the camera's poses T_W_C in the tracker's world, oldest first.
  void republishPath(const std::vector<sdf_tracker::io::StampedPose>& path_W);

 private:
  /// False when `child` already has a parent other than `parent` from another publisher (said
  /// once, then remembered): this node must not publish parent -> child.
  bool mayPublishParentOf(const std::string& child, const std::string& parent);
  /// The camera frame of images of `image_frame` (~camera_frame overrides it).
  std::string cameraFrameOf(const std::string& image_frame) const;
  /// The mounting of the camera on ~base_frame (identity without one); throws
  /// tf2::TransformException while tf does not have it.
  Eigen::Isometry3d T_base_C(const std::string& camera_frame);
  void onImu(const sensor_msgs::ImuConstPtr& imu);
  /// Publishes ~path: the poses kept, stamped as the newest.
  void sendPath();

  FrameOptions frames_;
  int path_length_;
  mutable std::mutex mutex_;  ///< guards T_map_W_, map_frame_fixed_ and the IMU samples
  Eigen::Isometry3d T_map_W_;
  /// Set at the first published pose (after levelling, when an IMU is given; in a loaded map that
  /// keeps no map frame, once the camera has been found in it), or by restoreMapFrame().
  bool map_frame_fixed_ = false;
  std::set<std::string> refused_children_;
  std::string odometry_problem_;
  /// Frames in a row without odometry (odometryCameraPose), for the log.
  size_t frames_without_odometry_ = 0;

  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Publisher pose_pub_, path_pub_, odom_pub_;
  OdometryBuilder odometry_;
  nav_msgs::Path path_;
  std::deque<geometry_msgs::PoseStamped> path_poses_;

  ros::Subscriber imu_sub_;
  /// The latest accelerometer readings (IMU frame), over kLevellingWindow_s: a hand-held camera
  /// moves, so only the readings just before the first frame say where up was then.
  std::deque<std::pair<ros::Time, Eigen::Vector3d>> accelerations_;
  std::string imu_frame_;
  /// Readings refused by isGravityReading() before the first frame, and the last one's magnitude.
  size_t refused_readings_ = 0;
  double last_refused_magnitude_ = 0.0;
};

}  // namespace sdf_tracker_ros
