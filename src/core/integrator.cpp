#include "sdf_tracker/core/integrator.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

namespace {

/// Narrows [*lo, *hi] to the i for which a + b * i >= 0.
inline void clipToHalfLine(double a, double b, double* lo, double* hi) {
  if (b > 0.0) {
    *lo = std::max(*lo, -a / b);
  } else if (b < 0.0) {
    *hi = std::min(*hi, -a / b);
  } else if (a < 0.0) {
    *hi = -1.0, *lo = 1.0;  // empty
  }
}

}  // namespace

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
  if (const std::string mismatch = camera.sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
    throw std::invalid_argument(mismatch);
  }
  const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
  const Eigen::Vector3i dims = volume->dims();
  const float dmax = volume->positiveTruncation();
  const float dmin = static_cast<float>(config_.negative_truncation_m);
  const float wmax = static_cast<float>(config_.max_weight);
  const bool sensor_weights = config_.weighting == MeasurementWeighting::kSensorNoise;
  const DepthNoiseModel& noise = config_.noise;
  const float reference_sigma = noise.referenceSigma();
  const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const int width = camera.width, height = camera.height;
  // Moving one voxel along x moves the point in the camera frame by this much.
  const Eigen::Vector3f step_x_C = T_C_W.linear().col(0) * volume->voxelSize();
  const float* depth_m = depth.data();
  // Beyond the furthest measurement (plus the negative band) every voxel is too far behind.
  float max_depth_m = 0.0f;
  for (int n = 0; n < width * height; ++n) {
    if (DepthImage::isMeasurement(depth_m[n])) max_depth_m = std::max(max_depth_m, depth_m[n]);
  }
  if (max_depth_m <= 0.0f) return 0;
  const double z_far = max_depth_m - dmin;
  const double z_near = 1e-6;

  return volume->withStorage([&](auto* voxels, const auto& codec) {
    size_t updated = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : updated)
    for (int k = 0; k < dims.z(); ++k) {
      for (int j = 0; j < dims.y(); ++j) {
        const Eigen::Vector3f p0_C = T_C_W * volume->position(0, j, k);
        // Only voxels of this row inside the viewing frustum can change: each frustum plane is a
        // linear constraint on i. The per-voxel tests below stay; this only skips the rest.
        const Eigen::Vector3d a = p0_C.cast<double>(), b = step_x_C.cast<double>();
        double lo = 0.0, hi = dims.x() - 1.0;
        clipToHalfLine(a.z() - z_near, b.z(), &lo, &hi);
        clipToHalfLine(z_far - a.z(), -b.z(), &lo, &hi);
        clipToHalfLine(fx * a.x() + (cx + 0.5) * a.z(), fx * b.x() + (cx + 0.5) * b.z(), &lo, &hi);
        clipToHalfLine((width - 0.5 - cx) * a.z() - fx * a.x(), (width - 0.5 - cx) * b.z() - fx * b.x(), &lo, &hi);
        clipToHalfLine(fy * a.y() + (cy + 0.5) * a.z(), fy * b.y() + (cy + 0.5) * b.z(), &lo, &hi);
        clipToHalfLine((height - 0.5 - cy) * a.z() - fy * a.y(), (height - 0.5 - cy) * b.z() - fy * b.y(), &lo, &hi);
        if (lo > hi) continue;
        const int i_begin = std::max(0, static_cast<int>(std::ceil(lo)) - 1);
        const int i_end = std::min(dims.x(), static_cast<int>(std::floor(hi)) + 2);
        Eigen::Vector3f p_C = p0_C + static_cast<float>(i_begin) * step_x_C;
        auto* row = voxels + volume->index(0, j, k);
        for (int i = i_begin; i < i_end; ++i, p_C += step_x_C) {
          if (p_C.z() <= 0.0f) continue;
          const float inv_z = 1.0f / p_C.z();
          // Nearest pixel; the range test comes before the conversion so rounding is exact.
          const float u_shifted = fx * p_C.x() * inv_z + cx + 0.5f;
          const float v_shifted = fy * p_C.y() * inv_z + cy + 0.5f;
          if (!(u_shifted >= 0.0f && v_shifted >= 0.0f && u_shifted < width && v_shifted < height)) continue;
          const int u = static_cast<int>(u_shifted), v = static_cast<int>(v_shifted);
          const float z_measured = depth_m[static_cast<size_t>(v) * width + u];
          if (!DepthImage::isMeasurement(z_measured)) continue;
          const float d = z_measured - p_C.z();
          if (d < dmin) continue;
          const float d_clamped = std::min(d, dmax);
          const float w_new = sensor_weights ? noise.weight(z_measured, reference_sigma) : 1.0f;
          Voxel voxel = codec.decode(row[i]);
          const float w_sum = voxel.weight + w_new;
          voxel.distance_m = (voxel.distance_m * voxel.weight + d_clamped * w_new) / w_sum;
          voxel.weight = std::min(w_sum, wmax);
          row[i] = codec.encode(voxel);
          ++updated;
        }
      }
    }
    return updated;
  });
}

}  // namespace sdf_tracker
