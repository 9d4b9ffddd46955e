#pragma once

#include <Eigen/Geometry>

namespace sdf_tracker {

/// Twist ordered as in the paper, eq. (5): (omega1 omega2 omega3 v1 v2 v3).
using Twist = Eigen::Matrix<double, 6, 1>;

/// [w]x, the matrix of the cross product: skew(w) * v = w x v.
Eigen::Matrix3d skew(const Eigen::Vector3d& w);

/// exp: se(3) -> SE(3), closed form (Rodrigues for rotation, V matrix for translation).
Eigen::Isometry3d expSe3(const Twist& xi);

/// log: SE(3) -> se(3), the inverse of expSe3 for rotations below pi.
Twist logSe3(const Eigen::Isometry3d& T);

/// Rotation angle [rad] of a rigid transform.
double rotationAngle(const Eigen::Isometry3d& T);

/// The axis-aligned box that holds `box` moved by T (its eight corners'); empty for an empty box.
template <typename Scalar>
Eigen::AlignedBox<Scalar, 3> transformedBox(const Eigen::Transform<Scalar, 3, Eigen::Isometry>& T,
                                            const Eigen::AlignedBox<Scalar, 3>& box) {
  using Box = Eigen::AlignedBox<Scalar, 3>;
  Box moved;
  if (box.isEmpty()) return moved;
  for (int corner = 0; corner < 8; ++corner) moved.extend(T * box.corner(static_cast<typename Box::CornerType>(corner)));
  return moved;
}

}  // namespace sdf_tracker
