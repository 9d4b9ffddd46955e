#pragma once

#include <Eigen/Geometry>

namespace sdf_tracker {

/// A timestamped camera-to-world pose.
struct StampedPose {
  double timestamp_s;
  Eigen::Isometry3d T_W_C;
};

}  // namespace sdf_tracker
