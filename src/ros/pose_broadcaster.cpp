#include "sdf_tracker/ros/pose_broadcaster.h"

#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <tf2_eigen/tf2_eigen.h>

#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {

namespace {
constexpr double kTfWaitThrottle_s = 5.0;
/// Accelerometer readings this long before the first frame level the map frame.
constexpr double kLevellingWindow_s = 0.2;
}  // namespace

Eigen::Isometry3d mapFromOpticalWorld() {
  Eigen::Matrix3d R;  // rows: map x = optical z, map y = -optical x, map z = -optical y
  R << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  return T;
}

bool isGravityReading(const Eigen::Vector3d& acceleration) {
  const double magnitude = acceleration.norm();  // NaN or infinite for a reading that is not finite
  return magnitude >= kMinGravityReading && magnitude <= kMaxGravityReading;
}

Eigen::Isometry3d gravityAlignedMapFromOpticalWorld(const Eigen::Vector3d& up_W) {
  const double length = up_W.norm();
  if (!(length > 0.0 && std::isfinite(length))) {
    throw std::invalid_argument("gravity: the up direction is zero or not finite");
  }
  const Eigen::Vector3d z = up_W.normalized();
  // Forward: the first camera's viewing direction (optical z) with its vertical part removed;
  // if the camera looked straight up or down, its image "up" (-optical y) instead.
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ() - z * z.z();
  if (forward.norm() < 1e-3) forward = -Eigen::Vector3d::UnitY() - z * -z.y();
  const Eigen::Vector3d x = forward.normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().row(0) = x.transpose();
  T.linear().row(1) = y.transpose();
  T.linear().row(2) = z.transpose();
  return T;
}

Eigen::Isometry3d placedOnPlane(const Eigen::Isometry3d& T_map_body, const Eigen::Vector3d& forward_body,
                                const Eigen::Vector3d& fallback_body, double x_m, double y_m, double yaw_rad) {
  Eigen::Vector3d heading = T_map_body.linear() * forward_body;
  if (heading.head<2>().norm() < 1e-3 * heading.norm()) heading = T_map_body.linear() * fallback_body;
  const double held_yaw_rad = std::atan2(heading.y(), heading.x());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad - held_yaw_rad, Eigen::Vector3d::UnitZ()) * T_map_body.linear();
  T.translation() = Eigen::Vector3d(x_m, y_m, T_map_body.translation().z());
  return T;
}

PoseBroadcaster::PoseBroadcaster(ros::NodeHandle nh, ros::NodeHandle pnh, const NodeOptions& options,
                                 const std::optional<Eigen::Isometry3d>& saved_map_frame)
    : frames_(options.frames),
      path_length_(options.path_length),
      T_map_W_(mapFromOpticalWorld()),
      tf_listener_(tf_buffer_, nh),
      odometry_(options.frames.map_frame) {
  pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  odom_pub_ = pnh.advertise<nav_msgs::Odometry>("odom", 10);
  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  path_.header.frame_id = frames_.map_frame;
  if (saved_map_frame) restoreMapFrame(*saved_map_frame);
  if (!options.imu_topic.empty()) {
    imu_sub_ = nh.subscribe(options.imu_topic, 200, &PoseBroadcaster::onImu, this);
    if (saved_map_frame) {
      ROS_INFO("sdf_tracker: the loaded map keeps the map frame it was saved with: %s (imu_topic) does not level it again",
               imu_sub_.getTopic().c_str());
    } else {
      ROS_INFO("sdf_tracker: levelling the map frame with gravity from %s", imu_sub_.getTopic().c_str());
    }
  }
}

void PoseBroadcaster::onImu(const sensor_msgs::ImuConstPtr& imu) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (map_frame_fixed_) return;
  const auto& a = imu->linear_acceleration;
  const Eigen::Vector3d accel(a.x, a.y, a.z);
  if (!isGravityReading(accel)) {
    ++refused_readings_;
    last_refused_magnitude_ = accel.norm();
    return;
  }
  accelerations_.emplace_back(imu->header.stamp, accel);
  while (accelerations_.front().first.toSec() < imu->header.stamp.toSec() - kLevellingWindow_s) {
    accelerations_.pop_front();
  }
  imu_frame_ = stripSlash(imu->header.frame_id);
}

std::string describeLoadedMapFrame(bool saved) {
  if (saved) return "poses go out in the map frame it was saved with";
  return "it keeps no map frame (a .vti, a .sdfmap from an offline run or of format version 2 or older): poses go "
         "out in this node's map frame, which a new session levels where the camera is found, and which may be "
         "tilted from the saving session's";
}

std::optional<Eigen::Isometry3d> PoseBroadcaster::fixedMapFrame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return map_frame_fixed_ ? std::optional<Eigen::Isometry3d>(T_map_W_) : std::nullopt;
}

void PoseBroadcaster::restoreMapFrame(const Eigen::Isometry3d& T_map_W) {
  std::lock_guard<std::mutex> lock(mutex_);
  T_map_W_ = T_map_W;
  map_frame_fixed_ = true;
  accelerations_.clear();
}

void PoseBroadcaster::clearPath() {
  path_poses_.clear();
  path_.poses.clear();
  odometry_.restart();
}

void PoseBroadcaster::republishPath(const std::vector<sdf_tracker::io::StampedPose>& path_W) {
  const Eigen::Isometry3d T_map_W = this->T_map_W();
  path_poses_.clear();
  const size_t first = path_W.size() > static_cast<size_t>(path_length_) ? path_W.size() - path_length_ : 0;
  for (size_t k = first; k < path_W.size(); ++k) {
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = ros::Time(path_W[k].timestamp_s);
    pose.header.frame_id = frames_.map_frame;
    pose.pose = toPoseMsg(T_map_W * path_W[k].T_W_C);
    path_poses_.push_back(pose);
  }
  if (!path_poses_.empty()) sendPath();  // latched: a later subscriber gets it too
}

void PoseBroadcaster::sendPath() {
  path_.header.stamp = path_poses_.back().header.stamp;
  path_.poses.assign(path_poses_.begin(), path_poses_.end());
  path_pub_.publish(path_);
}

bool PoseBroadcaster::mayPublishParentOf(const std::string& child, const std::string& parent) {
  if (refused_children_.count(child)) return false;
  std::string existing;
  if (!tf_buffer_._getParent(child, ros::Time(0), existing) || stripSlash(existing) == parent) return true;
  refused_children_.insert(child);
  existing = stripSlash(existing);
  if (child == frames_.odom_frame) {
    ROS_ERROR("sdf_tracker: frame '%s' (~odom_frame) already has the parent '%s' from another publisher, so this node "
              "will not publish %s -> %s (a frame must have one parent): another localiser (amcl, an EKF in the map "
              "frame) corrects the odometry already. Run one of them, or leave ~odom_frame empty and feed ~odom to "
              "that localiser. Until then the estimate is on ~pose, ~path and ~odom only.",
              child.c_str(), existing.c_str(), parent.c_str(), child.c_str());
    return false;
  }
  ROS_ERROR("sdf_tracker: frame '%s' already has the parent '%s' from another publisher, so this node will not "
            "publish %s -> %s (a frame must have one parent). Set ~base_frame to the frame this tracker moves "
            "(e.g. the root of the camera's own chain, such as a robot's base_link or the camera's mount frame): "
            "the node then publishes %s -> <base_frame> and looks up <base_frame> -> %s in tf; on a robot whose "
            "odometry publishes odom -> base_link, set ~odom_frame too. Until then the estimate is on ~pose and "
            "~path only.",
            child.c_str(), existing.c_str(), parent.c_str(), child.c_str(), parent.c_str(), child.c_str());
  return false;
}

std::string PoseBroadcaster::cameraFrameOf(const std::string& image_frame) const {
  return frames_.camera_frame.empty() ? stripSlash(image_frame) : frames_.camera_frame;
}

Eigen::Isometry3d PoseBroadcaster::T_base_C(const std::string& camera_frame) {
  if (frames_.base_frame.empty() || frames_.base_frame == camera_frame) return Eigen::Isometry3d::Identity();
  return tf2::transformToEigen(tf_buffer_.lookupTransform(frames_.base_frame, camera_frame, ros::Time(0)));
}

std::optional<Eigen::Isometry3d> PoseBroadcaster::odometryCameraPose(const ros::Time& stamp,
                                                                     const std::string& image_frame) {
  if (frames_.odom_frame.empty()) return std::nullopt;
  const std::string camera_frame = cameraFrameOf(image_frame);
  const std::string base = frames_.base_frame.empty() ? camera_frame : frames_.base_frame;
  const std::string missing = frames_.odom_frame + " -> " + base + " -> " + camera_frame;
  try {
    // An odometry that flows may lag the image by a little: wait for it. One that stopped, or never
    // came, is not waited for.
    ros::Duration wait(0.0);
    try {
      const ros::Time latest = tf_buffer_.lookupTransform(frames_.odom_frame, base, ros::Time(0)).header.stamp;
      if ((stamp - latest).toSec() < kOdometryStale_s) wait = ros::Duration(kOdometryWait_s);
    } catch (const tf2::TransformException&) {
      // Never had it: the lookup below says why.
    }
    // The odometry at the image's stamp; the camera's mounting as tf has it last (it is rigid,
    // and chains re-published at the camera's rate would make every frame wait for the next).
    const Eigen::Isometry3d T_odom_C =
        tf2::transformToEigen(tf_buffer_.lookupTransform(frames_.odom_frame, base, stamp, wait)) *
        T_base_C(camera_frame);
    if (frames_without_odometry_ > 0) {
      ROS_INFO("sdf_tracker: odometry back (%s) after %zu frames without it", missing.c_str(), frames_without_odometry_);
    }
    frames_without_odometry_ = 0;
    odometry_problem_.clear();
    return T_odom_C;
  } catch (const tf2::TransformException& e) {
    odometry_problem_ = "no " + missing + " in tf at the image's stamp: " + e.what();
    if (frames_without_odometry_++ == 0) {
      ROS_WARN("sdf_tracker: no odometry for the frame stamped %.3f: tf has no %s then (~odom_frame names the "
               "robot's odometry, which must publish %s -> %s; without one leave ~odom_frame empty): %s. Until it "
               "comes, frames are predicted at constant velocity, not waited for, and %s -> %s is not published.",
               stamp.toSec(), missing.c_str(), frames_.odom_frame.c_str(), base.c_str(), e.what(),
               frames_.map_frame.c_str(), frames_.odom_frame.c_str());
    } else {
      ROS_WARN_THROTTLE(30.0, "sdf_tracker: still no odometry (%s): %zu frames in a row without it",
                        missing.c_str(), frames_without_odometry_);
    }
    return std::nullopt;
  }
}

Eigen::Isometry3d PoseBroadcaster::requestedCameraPose(const geometry_msgs::PoseWithCovarianceStamped& request,
                                                       const std::string& image_frame,
                                                       const Eigen::Isometry3d& T_W_C_held) {
  const geometry_msgs::Pose& pose = request.pose.pose;
  const Eigen::Vector3d position(pose.position.x, pose.position.y, pose.position.z);
  const Eigen::Vector4d quaternion(pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w);
  if (!position.allFinite() || !quaternion.allFinite() || quaternion.norm() < 1e-6) {
    std::ostringstream msg;
    msg << "its position (" << position.transpose() << ") or orientation (quaternion " << quaternion.transpose()
        << ") is not a pose";
    throw std::runtime_error(msg.str());
  }
  const std::string frame = request.header.frame_id.empty() ? frames_.map_frame : stripSlash(request.header.frame_id);
  Eigen::Isometry3d T_map_frame = Eigen::Isometry3d::Identity();
  if (frame != frames_.map_frame) {
    try {
      T_map_frame = tf2::transformToEigen(tf_buffer_.lookupTransform(frames_.map_frame, frame, ros::Time(0)));
    } catch (const tf2::TransformException& e) {
      throw std::runtime_error("it is given in the frame '" + frame + "', and tf has no transform from it to ~map_frame '" +
                               frames_.map_frame + "' (" + e.what() + ")");
    }
  }
  const Eigen::Isometry3d T_map_requested = T_map_frame * fromPoseMsg(pose);
  const Eigen::Vector3d heading = T_map_requested.linear().col(0);  // the body's x: rviz's arrow
  const double yaw_rad = std::atan2(heading.y(), heading.x());
  const std::string camera_frame = cameraFrameOf(image_frame);
  const bool on_base = !frames_.base_frame.empty() && frames_.base_frame != camera_frame;
  Eigen::Isometry3d T_base_cam;
  try {
    T_base_cam = T_base_C(camera_frame);
  } catch (const tf2::TransformException& e) {
    throw std::runtime_error("tf has no " + frames_.base_frame + " -> " + camera_frame +
                             " (the camera's mounting on ~base_frame): " + e.what());
  }
  std::lock_guard<std::mutex> lock(mutex_);
  const Eigen::Isometry3d T_map_body_held = T_map_W_ * T_W_C_held * T_base_cam.inverse();
  // A base heads along its x with z up; a camera along its optical z with -y up.
  const Eigen::Vector3d forward = on_base ? Eigen::Vector3d(1, 0, 0) : Eigen::Vector3d(0, 0, 1);
  const Eigen::Vector3d up = on_base ? Eigen::Vector3d(0, 0, 1) : Eigen::Vector3d(0, -1, 0);
  const Eigen::Isometry3d T_map_body = placedOnPlane(T_map_body_held, forward, up, T_map_requested.translation().x(),
                                                     T_map_requested.translation().y(), yaw_rad);
  return T_map_W_.inverse() * T_map_body * T_base_cam;
}

Eigen::Isometry3d PoseBroadcaster::publish(const ros::Time& stamp, const std::string& image_frame,
                                           const Eigen::Isometry3d& T_W_C,
                                           const std::optional<Covariance6d>& covariance_W,
                                           const std::optional<Eigen::Isometry3d>& T_odom_C) {
  const std::string camera_frame = cameraFrameOf(image_frame);
  std::unique_lock<std::mutex> lock(mutex_);
  if (!map_frame_fixed_) {
    if (imu_sub_ && accelerations_.empty() && refused_readings_ > 0) {
      ROS_WARN("sdf_tracker: none of the %zu messages on %s before the first frame reads like gravity "
               "(|linear_acceleration| must lie within %.0f-%.0f m/s^2; the last: %g m/s^2): the map frame is not "
               "levelled",
               refused_readings_, imu_sub_.getTopic().c_str(), kMinGravityReading, kMaxGravityReading,
               last_refused_magnitude_);
    } else if (imu_sub_ && accelerations_.empty()) {
      ROS_WARN("sdf_tracker: no message on %s before the first frame: the map frame is not levelled",
               imu_sub_.getTopic().c_str());
    } else if (imu_sub_) {
      std::optional<Eigen::Isometry3d> T_C_I;
      try {
        T_C_I = tf2::transformToEigen(tf_buffer_.lookupTransform(camera_frame, imu_frame_, ros::Time(0)));
      } catch (const tf2::TransformException& e) {
        ROS_WARN("sdf_tracker: cannot level the map frame: no tf from the IMU's frame '%s' to the camera frame "
                 "'%s' (%s); the map frame is the first camera pose in REP 103 axes",
                 imu_frame_.c_str(), camera_frame.c_str(), e.what());
      }
      if (T_C_I) {
        // Up in the tracker's world, through the camera's pose (the identity at a new map's first
        // frame; where the camera was found in a loaded one).
        Eigen::Vector3d mean_I = Eigen::Vector3d::Zero();
        for (const auto& sample : accelerations_) mean_I += sample.second;
        mean_I /= static_cast<double>(accelerations_.size());
        const Eigen::Vector3d up_W = T_W_C.linear() * T_C_I->linear() * mean_I;
        if (isGravityReading(up_W)) {
          T_map_W_ = gravityAlignedMapFromOpticalWorld(up_W);
          ROS_INFO("sdf_tracker: map frame levelled with the %zu IMU samples of the last %.1f s",
                   accelerations_.size(), kLevellingWindow_s);
        } else {  // readings that cancel out: a camera shaken, not held
          ROS_WARN("sdf_tracker: the %zu IMU samples of the last %.1f s average to %g m/s^2, not gravity: the map "
                   "frame is not levelled",
                   accelerations_.size(), kLevellingWindow_s, up_W.norm());
        }
      }
    }
    map_frame_fixed_ = true;
  }
  const Eigen::Isometry3d T_map_C = T_map_W_ * T_W_C;
  const Eigen::Matrix3d R_map_W = T_map_W_.linear();
  lock.unlock();

  if (covariance_W) {  // an estimate: a held pose has no place on ~pose or ~path
    geometry_msgs::PoseStamped pose;
    pose.header.stamp = stamp;
    pose.header.frame_id = frames_.map_frame;
    pose.pose = toPoseMsg(T_map_C);
    pose_pub_.publish(pose);
    path_poses_.push_back(pose);
    while (static_cast<int>(path_poses_.size()) > path_length_) path_poses_.pop_front();
    if (path_pub_.getNumSubscribers() > 0) sendPath();
  }

  // map -> [odom ->] base, such that map -> camera is the estimate.
  Eigen::Isometry3d T_map_base = T_map_C;
  std::string base = camera_frame;
  if (!frames_.base_frame.empty() && frames_.base_frame != camera_frame) {
    base = frames_.base_frame;
    try {
      T_map_base = T_map_C * T_base_C(camera_frame).inverse();
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(kTfWaitThrottle_s, "sdf_tracker: waiting for tf %s -> %s (the camera's mounting on ~base_frame): %s",
                        base.c_str(), camera_frame.c_str(), e.what());
      return T_map_C;
    }
  }
  std::optional<Covariance6d> covariance;
  if (covariance_W) {
    covariance = bodyPoseCovariance(*covariance_W, R_map_W, T_map_base.translation() - T_map_C.translation());
  }
  odom_pub_.publish(odometry_.build(stamp.toSec(), base, T_map_base, covariance));

  // REP 105 on a robot: its odometry owns odom -> base; the correction map -> odom makes
  // map -> odom -> base -> camera the estimate.
  std::string child = base;
  Eigen::Isometry3d T_map_child = T_map_base;
  if (!frames_.odom_frame.empty()) {
    if (!T_odom_C) return T_map_C;  // odometryCameraPose said why
    child = frames_.odom_frame;
    T_map_child = T_map_C * T_odom_C->inverse();
  } else if (base == frames_.map_frame) {
    ROS_ERROR_ONCE("sdf_tracker: the image's frame '%s' is also ~map_frame: a frame cannot be its own parent, so this "
                   "node publishes no tf (pose and path go on). Set ~map_frame to a frame of its own.",
                   base.c_str());
    return T_map_C;
  }
  if (!mayPublishParentOf(child, frames_.map_frame)) return T_map_C;
  geometry_msgs::TransformStamped transform = tf2::eigenToTransform(T_map_child);
  transform.header.stamp = stamp;
  transform.header.frame_id = frames_.map_frame;
  transform.child_frame_id = child;
  tf_broadcaster_.sendTransform(transform);
  return T_map_C;
}

}  // namespace sdf_tracker_ros
