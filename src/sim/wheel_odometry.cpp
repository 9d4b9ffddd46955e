#include "sdf_tracker/sim/wheel_odometry.h"

#include <cmath>
#include <random>

namespace sdf_tracker::synthetic {

std::vector<io::StampedPose> wheelOdometry(const std::vector<io::StampedPose>& truth, const WheelOdometryModel& model) {
  std::vector<io::StampedPose> odometry;
  if (truth.empty()) return odometry;
  std::mt19937 rng(model.seed * 2246822519u + 7u);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const Eigen::Vector3d up = -Eigen::Vector3d::UnitY();
  const double drift_rad_per_m = model.heading_drift_deg_per_m * M_PI / 180.0;
  double heading_error_rad = 0.0;
  Eigen::Vector3d position = truth.front().T_W_C.translation();
  odometry.push_back(truth.front());
  for (size_t k = 1; k < truth.size(); ++k) {
    const Eigen::Vector3d step = truth[k].T_W_C.translation() - truth[k - 1].T_W_C.translation();
    const double distance_m = step.norm();
    heading_error_rad += drift_rad_per_m * distance_m;
    const Eigen::AngleAxisd heading_error(heading_error_rad, up);
    const double sigma_m = model.noise_m_per_sqrt_m * std::sqrt(distance_m);
    const Eigen::Vector3d noise(gaussian(rng), gaussian(rng), gaussian(rng));
    position += heading_error * ((1.0 + model.distance_error) * step) + sigma_m * noise;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = heading_error * truth[k].T_W_C.linear();
    T.translation() = position;
    odometry.push_back({truth[k].timestamp_s, T});
  }
  return odometry;
}

}  // namespace sdf_tracker::synthetic
