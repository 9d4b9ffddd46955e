#pragma once

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// How a depth image placed at a pose agrees with what the map has observed. A point says one of
/// three things: it lies on a mapped surface (for the pose), it lies where the map has seen free
/// space or its ray passes through a mapped surface (against the pose), or it lies where the map
/// never looked (neither way: new ground). A right pose with half its view new has few mapped
/// points but no contradiction; a wrong place that fits part of the view has points in front of
/// mapped surfaces and rays through them. A sparse map knows free space only where it holds blocks,
/// within the truncation band's reach of its surfaces: a point far in front of every surface is
/// unobserved there, as are the samples of a ray through empty space.
struct ViewAgreement {
  int points = 0;         ///< measured points looked at, of those the map could hold
  int mapped = 0;         ///< on a mapped surface: observed, within the positive truncation of it
  int tight = 0;          ///< of those, within kTightFit_voxels of the surface
  int in_free_space = 0;  ///< lie where the map observed free space, well in front of every surface
  int seen_through = 0;   ///< their rays pass through a mapped surface before they reach them

  double mappedShare() const { return points > 0 ? static_cast<double>(mapped) / points : 0.0; }
  double tightShare() const { return mapped > 0 ? static_cast<double>(tight) / mapped : 0.0; }
  int contradicting() const { return in_free_space + seen_through; }
  double contradictionShare() const { return points > 0 ? static_cast<double>(contradicting()) / points : 0.0; }
};

/// A mapped point this close to its surface [voxels] fits tightly.
constexpr double kTightFit_voxels = 1.0;
/// A point whose field value is at least this fraction of the positive truncation lies in free
/// space: the map saw through it, well in front of every surface.
constexpr double kObservedFreeFraction = 0.8;
/// The ray of a point is marched in steps of this many voxels from the camera to the point less
/// the positive truncation (where a right pose's own surface begins); a sample that deep inside a
/// mapped surface (field below minus this many voxels) contradicts the pose. With the step, at
/// least one sample falls that deep in any surface layer of at least two voxels behind the
/// surface (NegativeTruncationDistance is at least a voxel; the presets keep two to three).
constexpr double kRayStep_voxels = 1.0;
constexpr double kInsideSurface_voxels = 0.75;

/// Measures every `stride`-th pixel of `depth` (metres; the ideal camera's image, as the tracker
/// takes it) placed at T_W_C against `map`. Parallel over pixels; reads the map only.
ViewAgreement measureViewAgreement(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                                   const Eigen::Isometry3d& T_W_C, int stride);

}  // namespace sdf_tracker
