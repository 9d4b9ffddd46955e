#pragma once

#include <Eigen/Geometry>

namespace sdf_tracker {

/// Twist ordered as in the paper, eq. (5): (omega1 omega2 omega3 v1 v2 v3).
using Twist = Eigen::Matrix<double, 6, 1>;

/// exp: se(3) -> SE(3), closed form (Rodrigues for rotation, V matrix for translation).
Eigen::Isometry3d expSe3(const Twist& xi);

/// log: SE(3) -> se(3), the inverse of expSe3 for rotations below pi.
Twist logSe3(const Eigen::Isometry3d& T);

/// Rotation angle [rad] of a rigid transform.
double rotationAngle(const Eigen::Isometry3d& T);

}  // namespace sdf_tracker
