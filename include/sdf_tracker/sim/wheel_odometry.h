#pragma once

#include <cstdint>
#include <vector>

#include "sdf_tracker/io/trajectory_file.h"

namespace sdf_tracker::synthetic {

/// How a robot's wheel odometry errs: it sees the true motion, but the distance a little too long
/// (a wheel radius off), the heading turning a little with every metre (wheels of unequal size,
/// slip), and some noise on every step.
struct WheelOdometryModel {
  double distance_error = 0.02;          ///< 2 %: every metre is measured as 1.02 m
  double heading_drift_deg_per_m = 1.0;  ///< about the world's vertical, per metre travelled
  double noise_m_per_sqrt_m = 0.002;     ///< position noise: its variance grows with the distance
  uint32_t seed = 1;
};

/// The camera poses such an odometry reports along `truth` (camera to world, the world's vertical
/// being -y as in every synthetic scene), in its own frame, which starts at the first true pose.
std::vector<io::StampedPose> wheelOdometry(const std::vector<io::StampedPose>& truth, const WheelOdometryModel& model);

}  // namespace sdf_tracker::synthetic
