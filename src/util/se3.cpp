#include "sdf_tracker/util/se3.h"

#include <algorithm>
#include <cmath>

namespace sdf_tracker {

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

namespace {

/// The coefficients of R = I + a W + b W^2 and V = I + b W + c W^2 for W = [omega]x, |omega| = theta.
struct RodriguesCoefficients {
  double a, b, c;
  explicit RodriguesCoefficients(double theta) {
    if (theta < 1e-8) {
      a = 1.0 - theta * theta / 6.0;
      b = 0.5 - theta * theta / 24.0;
      c = 1.0 / 6.0 - theta * theta / 120.0;
    } else {
      a = std::sin(theta) / theta;
      b = (1.0 - std::cos(theta)) / (theta * theta);
      c = (theta - std::sin(theta)) / (theta * theta * theta);
    }
  }
};
}  // namespace

Eigen::Isometry3d expSe3(const Twist& xi) {
  const Eigen::Vector3d omega = xi.head<3>();
  const Eigen::Matrix3d W = skew(omega);
  const Eigen::Matrix3d W2 = W * W;
  const RodriguesCoefficients k(omega.norm());
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Matrix3d::Identity() + k.a * W + k.b * W2;
  T.translation() = (Eigen::Matrix3d::Identity() + k.b * W + k.c * W2) * xi.tail<3>();
  return T;
}

Twist logSe3(const Eigen::Isometry3d& T) {
  const Eigen::AngleAxisd rotation(T.linear());
  const Eigen::Vector3d omega = rotation.angle() * rotation.axis();
  const Eigen::Matrix3d W = skew(omega);
  const RodriguesCoefficients k(omega.norm());
  Twist xi;
  xi.head<3>() = omega;
  xi.tail<3>() = (Eigen::Matrix3d::Identity() + k.b * W + k.c * W * W).inverse() * T.translation();
  return xi;
}

double rotationAngle(const Eigen::Isometry3d& T) {
  const double cos_angle = std::clamp((T.linear().trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(cos_angle);
}

}  // namespace sdf_tracker
