#include "sdf_tracker/ros/odometry.h"

#include <cmath>

#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/tracking/tracker.h"
#include "sdf_tracker/util/se3.h"

namespace sdf_tracker_ros {

namespace {

template <size_t N>
void toRowMajor(const Covariance6d& covariance, boost::array<double, N>* out) {
  static_assert(N == 36, "a 6x6 covariance");
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) (*out)[6 * r + c] = covariance(r, c);
  }
}

}  // namespace

Covariance6d bodyPoseCovariance(const Covariance6d& camera_covariance_W, const Eigen::Matrix3d& R_map_W,
                                const Eigen::Vector3d& camera_to_body_map) {
  // A small motion [w; v] about the camera centre (world axes) turns the body by R w and moves its
  // origin by R v + (R w) x r = R v - [r]x R w, with r the lever from the camera to the body.
  Covariance6d A = Covariance6d::Zero();
  A.block<3, 3>(0, 0) = -sdf_tracker::skew(camera_to_body_map) * R_map_W;
  A.block<3, 3>(0, 3) = R_map_W;
  A.block<3, 3>(3, 0) = R_map_W;
  return A * camera_covariance_W * A.transpose();
}

Covariance6d rotatedCovariance(const Covariance6d& camera_covariance, const Eigen::Matrix3d& R_to_from) {
  Covariance6d A = Covariance6d::Zero();
  A.block<3, 3>(0, 0) = R_to_from;
  A.block<3, 3>(3, 3) = R_to_from;
  return A * camera_covariance * A.transpose();
}

Covariance6d grownCovariance(const Covariance6d& covariance, double elapsed_s) {
  const double t = std::max(elapsed_s, 0.0);
  Covariance6d grown = covariance;
  for (int i = 0; i < 3; ++i) {
    // Standard deviations add: (sigma + s t)^2 = sigma^2 + 2 sigma s t + (s t)^2.
    const double sigma_t = std::sqrt(std::max(covariance(i, i), 0.0)), sigma_r = std::sqrt(std::max(covariance(i + 3, i + 3), 0.0));
    grown(i, i) += 2 * sigma_t * kHeldSpeed_mps * t + std::pow(kHeldSpeed_mps * t, 2);
    grown(i + 3, i + 3) += 2 * sigma_r * kHeldTurnRate_radps * t + std::pow(kHeldTurnRate_radps * t, 2);
  }
  return grown;
}

nav_msgs::Odometry OdometryBuilder::build(double stamp_s, const std::string& child_frame_id,
                                          const Eigen::Isometry3d& T_map_body,
                                          const std::optional<Covariance6d>& covariance) {
  nav_msgs::Odometry odom;
  odom.header.stamp = ros::Time(stamp_s);
  odom.header.frame_id = frame_id_;
  odom.child_frame_id = child_frame_id;
  odom.pose.pose = toPoseMsg(T_map_body);

  Sample sample{stamp_s, T_map_body, Covariance6d::Zero()};
  if (covariance) {
    sample.covariance = *covariance;
    last_tracked_ = sample;
  } else if (last_tracked_) {
    sample.covariance = grownCovariance(last_tracked_->covariance, stamp_s - last_tracked_->stamp_s);
  } else {
    sample.covariance = sdf_tracker::kUnconstrainedVariance * Covariance6d::Identity();
  }
  toRowMajor(sample.covariance, &odom.pose.covariance);

  Covariance6d twist_covariance = sdf_tracker::kUnconstrainedVariance * Covariance6d::Identity();
  const double dt = previous_ ? stamp_s - previous_->stamp_s : 0.0;
  if (covariance && previous_ && dt > 0.0 && dt <= kMaxTwistInterval_s) {
    // The motion since the previous message, in the body's frame now (REP 105: twist in child_frame_id).
    const Eigen::Matrix3d R_body_map = T_map_body.linear().transpose();
    const Eigen::Vector3d velocity = R_body_map * (T_map_body.translation() - previous_->T_map_body.translation()) / dt;
    const Eigen::AngleAxisd turn(previous_->T_map_body.linear().transpose() * T_map_body.linear());
    const Eigen::Vector3d angular = turn.axis() * turn.angle() / dt;  // in the previous body frame, nearly this one
    odom.twist.twist.linear.x = velocity.x();
    odom.twist.twist.linear.y = velocity.y();
    odom.twist.twist.linear.z = velocity.z();
    odom.twist.twist.angular.x = angular.x();
    odom.twist.twist.angular.y = angular.y();
    odom.twist.twist.angular.z = angular.z();
    Covariance6d rotate = Covariance6d::Zero();
    rotate.block<3, 3>(0, 0) = R_body_map;
    rotate.block<3, 3>(3, 3) = R_body_map;
    twist_covariance = rotate * (sample.covariance + previous_->covariance) * rotate.transpose() / (dt * dt);
  }
  toRowMajor(twist_covariance, &odom.twist.covariance);
  previous_ = sample;
  return odom;
}

}  // namespace sdf_tracker_ros
