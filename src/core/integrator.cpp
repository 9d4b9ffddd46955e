#include "sdf_tracker/core/integrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

std::vector<std::string> IntegratorConfig::validate() const {
  Violations v;
  v.requireNegative("negative_truncation_m", negative_truncation_m);
  v.requirePositive("max_weight", max_weight);
  v.merge("noise.", noise.validate());
  return v.list();
}

Integrator::Integrator(const IntegratorConfig& config) : config_(config) {
  throwIfInvalid("integrator config", config.validate());
}

size_t Integrator::integrate(const DepthImage& depth, const PinholeCamera& camera,
                             const Eigen::Isometry3d& T_W_C, TsdfVolume* volume) const {
  if (depth.width() != camera.width || depth.height() != camera.height) {
    std::ostringstream msg;
    msg << "depth image is " << depth.width() << "x" << depth.height() << " but the camera is "
        << camera.width << "x" << camera.height;
    throw std::invalid_argument(msg.str());
  }
  const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
  const Eigen::Vector3i dims = volume->dims();
  const float dmax = volume->positiveTruncation();
  const float dmin = static_cast<float>(config_.negative_truncation_m);
  const float wmax = static_cast<float>(config_.max_weight);
  const bool sensor_weights = config_.weighting == MeasurementWeighting::kSensorNoise;
  const DepthNoiseModel& noise = config_.noise;
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const int width = camera.width, height = camera.height;
  // Moving one voxel along x moves the point in the camera frame by this much.
  const Eigen::Vector3f step_x_C = T_C_W.linear().col(0) * volume->voxelSize();
  Voxel* voxels = volume->data();
  const float* depth_m = depth.data();

  size_t updated = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : updated)
  for (int k = 0; k < dims.z(); ++k) {
    for (int j = 0; j < dims.y(); ++j) {
      Eigen::Vector3f p_C = T_C_W * volume->position(0, j, k);
      Voxel* row = voxels + volume->index(0, j, k);
      for (int i = 0; i < dims.x(); ++i, p_C += step_x_C) {
        if (p_C.z() <= 0.0f) continue;
        const float inv_z = 1.0f / p_C.z();
        const int u = static_cast<int>(std::lround(fx * p_C.x() * inv_z + cx));
        const int v = static_cast<int>(std::lround(fy * p_C.y() * inv_z + cy));
        if (u < 0 || v < 0 || u >= width || v >= height) continue;
        const float z_measured = depth_m[static_cast<size_t>(v) * width + u];
        if (!DepthImage::isMeasurement(z_measured)) continue;
        const float d = z_measured - p_C.z();
        if (d < dmin) continue;
        const float d_clamped = std::min(d, dmax);
        const float w_new = sensor_weights ? noise.weight(z_measured) : 1.0f;
        Voxel& voxel = row[i];
        const float w_sum = voxel.weight + w_new;
        voxel.distance_m = (voxel.distance_m * voxel.weight + d_clamped * w_new) / w_sum;
        voxel.weight = std::min(w_sum, wmax);
        ++updated;
      }
    }
  }
  return updated;
}

}  // namespace sdf_tracker
