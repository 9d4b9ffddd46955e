#include "sdf_tracker/relocalisation/view_agreement.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace sdf_tracker {

namespace {

ViewAgreement& operator+=(ViewAgreement& sum, const ViewAgreement& other) {
  sum.points += other.points;
  sum.mapped += other.mapped;
  sum.tight += other.tight;
  sum.in_free_space += other.in_free_space;
  sum.seen_through += other.seen_through;
  return sum;
}

#pragma omp declare reduction(sumAgreement : ViewAgreement : omp_out += omp_in) initializer(omp_priv = ViewAgreement())

/// Nearer than this to the camera a ray is not marched: a hand-held camera is never inside a surface.
constexpr float kRayStart_m = 0.1f;

}  // namespace

ViewAgreement measureViewAgreement(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                                   const Eigen::Isometry3d& T_W_C, int stride) {
  if (stride < 1) throw std::invalid_argument("measureViewAgreement: stride must be >= 1 (got " + std::to_string(stride) + ")");
  if (depth.width() != camera.width || depth.height() != camera.height) {
    throw std::invalid_argument("measureViewAgreement: the depth image is not of the camera's size");
  }
  float furthest_m = 0.0f;
  for (int v = 0; v < depth.height(); v += stride) {
    for (int u = 0; u < depth.width(); u += stride) {
      const float z = depth.at(u, v);
      if (DepthImage::isMeasurement(z)) furthest_m = std::max(furthest_m, z);
    }
  }
  ViewAgreement sum;
  if (furthest_m <= 0.0f) return sum;

  const Eigen::Isometry3f T = T_W_C.cast<float>();
  const Eigen::Vector3f centre_W = T.translation();
  const std::unique_ptr<FieldSampler> field = map.sampler(camera.viewBox(T, furthest_m));
  const Eigen::AlignedBox3f holdable = map.holdableRegion();
  const float dmax = map.positiveTruncation();
  const float voxel = map.voxelSize();
  const float free_from = static_cast<float>(kObservedFreeFraction) * dmax;
  const float tight = static_cast<float>(kTightFit_voxels) * voxel;
  const float inside = -static_cast<float>(kInsideSurface_voxels) * voxel;
  const float step = static_cast<float>(kRayStep_voxels) * voxel;
  const int columns = (depth.width() + stride - 1) / stride;
  const int cells = columns * ((depth.height() + stride - 1) / stride);
#pragma omp parallel for schedule(dynamic, 16) reduction(sumAgreement : sum)
  for (int cell = 0; cell < cells; ++cell) {
    const int u = (cell % columns) * stride, v = (cell / columns) * stride;
    const float z = depth.at(u, v);
    if (!DepthImage::isMeasurement(z)) continue;
    const Eigen::Vector3f ray_W = T.linear() * camera.backProject(u, v, 1.0f);  // per metre of depth
    const Eigen::Vector3f p_W = centre_W + z * ray_W;
    if (!holdable.contains(p_W)) continue;
    ++sum.points;
    FieldSample s;
    if (field->sample(p_W, &s)) {
      if (s.distance_m >= free_from) {
        ++sum.in_free_space;
        continue;
      }
      if (std::fabs(s.distance_m) < dmax) {
        ++sum.mapped;
        sum.tight += std::fabs(s.distance_m) <= tight;
      }
    }
    // Does its ray pass through a mapped surface on the way (a point on a mapped surface too: a
    // wrong place can fit a wall seen through another one)? Marched up to where a right pose's own
    // surface band begins.
    const float ray_length = ray_W.norm();
    const float depth_step = step / ray_length;
    for (float t = kRayStart_m / ray_length; t < z - dmax; t += depth_step) {
      if (field->sample(centre_W + t * ray_W, &s) && s.distance_m < inside) {
        ++sum.seen_through;
        break;
      }
    }
  }
  return sum;
}

}  // namespace sdf_tracker
