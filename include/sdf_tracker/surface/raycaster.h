#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

struct RaycastConfig {
  /// Steps per ray when refining a measured depth (MaximumRaycastSteps in the reference).
  int max_refinement_steps = 12;
  double min_depth_m = 0.4;
  double max_depth_m = 8.0;

  std::vector<std::string> validate() const;
};

/// A virtual depth image of the zero level set and its unit normals in the camera frame
/// (NaN where a ray hit nothing).
struct RaycastImage {
  DepthImage depth;
  std::vector<Eigen::Vector3f> normals_C;
};

/// Casts one ray per pixel from the camera at T_W_C into the field.
/// Without a seed, each ray marches from the near plane until the field changes sign (the
/// "virtual sensor"). With a seed depth image, each ray starts at the measured depth and takes at
/// most max_refinement_steps steps towards the zero crossing (the reference release's
/// "image_denoised"); pixels without a measurement stay empty. Thread safe.
RaycastImage raycast(const TsdfMap& map, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                     const RaycastConfig& config, const DepthImage* seed = nullptr);

}  // namespace sdf_tracker
