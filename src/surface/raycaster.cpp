#include "sdf_tracker/surface/raycaster.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

/// Depth (along the optical axis) at which the ray p(z) = o + z * dir crosses zero, marching from
/// z_near to z_far; NaN if it does not. dir has unit z component in the camera frame.
float marchToSurface(const TsdfMap& map, const Eigen::Vector3f& origin_W, const Eigen::Vector3f& dir_W,
                     float z_near, float z_far) {
  const float ray_scale = dir_W.norm();  // metres of ray per metre of depth
  const float min_step = 0.5f * map.voxelSize() / ray_scale;
  float z = z_near;
  float previous_d = kNaN;
  float previous_z = z;
  while (z < z_far) {
    float d;
    if (map.sampleDistance(origin_W + z * dir_W, &d)) {
      if (d < 0.0f && previous_d > 0.0f) {
        return previous_z + (z - previous_z) * previous_d / (previous_d - d);
      }
      previous_d = d;
      previous_z = z;
      z += std::max(0.8f * d / ray_scale, min_step);
    } else {
      previous_d = kNaN;
      z += min_step;
    }
  }
  return kNaN;
}

/// Starts at a measured depth and walks towards the zero crossing by the field's own distances.
float refineFromSeed(const TsdfMap& map, const Eigen::Vector3f& origin_W, const Eigen::Vector3f& dir_W,
                     float z_seed, int max_steps) {
  const float ray_scale = dir_W.norm();
  const float tolerance = 0.01f * map.voxelSize();
  float z = z_seed;
  for (int step = 0; step < max_steps; ++step) {
    float d;
    if (!map.sampleDistance(origin_W + z * dir_W, &d)) return kNaN;
    if (std::fabs(d) < tolerance) break;
    z += d / ray_scale;
  }
  return z;
}

}  // namespace

std::vector<std::string> RaycastConfig::validate() const {
  Violations v;
  v.requireInRange("max_refinement_steps", max_refinement_steps, 0, 10000);
  v.requirePositive("min_depth_m", min_depth_m);
  v.require(max_depth_m > min_depth_m, "max_depth_m must be > min_depth_m (got " + std::to_string(max_depth_m) +
                                           " <= " + std::to_string(min_depth_m) + ")");
  return v.list();
}

RaycastImage raycast(const TsdfMap& map, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                     const RaycastConfig& config, const DepthImage* seed) {
  throwIfInvalid("raycast config", config.validate());
  RaycastImage out;
  out.depth = DepthImage(camera.width, camera.height, kNaN);
  out.normals_C.assign(static_cast<size_t>(camera.width) * camera.height, Eigen::Vector3f::Constant(kNaN));
  if (seed && (seed->width() != camera.width || seed->height() != camera.height)) {
    throw std::invalid_argument("raycast seed image size differs from the camera's");
  }
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  const Eigen::Vector3f origin_W = T.translation();
  const Eigen::Matrix3f R_W_C = T.linear();
  const float z_near = static_cast<float>(config.min_depth_m);
  const float z_far = static_cast<float>(config.max_depth_m);

#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3f dir_W = R_W_C * camera.backProject(u, v, 1.0f);
      float z;
      if (seed) {
        const float z_seed = seed->at(u, v);
        z = DepthImage::isMeasurement(z_seed)
                ? refineFromSeed(map, origin_W, dir_W, z_seed, config.max_refinement_steps)
                : kNaN;
      } else {
        z = marchToSurface(map, origin_W, dir_W, z_near, z_far);
      }
      FieldSample s;
      if (!std::isfinite(z) || !map.sample(origin_W + z * dir_W, &s)) continue;
      out.depth.at(u, v) = z;
      const float g = s.gradient.norm();
      if (g > 0.0f) out.normals_C[static_cast<size_t>(v) * camera.width + u] = R_W_C.transpose() * s.gradient / g;
    }
  }
  return out;
}

}  // namespace sdf_tracker
