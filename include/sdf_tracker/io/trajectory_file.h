#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace sdf_tracker::io {

/// A timestamped camera-to-world pose.
struct StampedPose {
  double timestamp_s;
  Eigen::Isometry3d T_W_C;
};

/// TUM trajectory format: "timestamp tx ty tz qx qy qz qw" per line, '#' comments.
void writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses);
std::vector<StampedPose> readTrajectory(const std::string& path);

}  // namespace sdf_tracker::io
