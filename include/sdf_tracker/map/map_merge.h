#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/map/sparse_tsdf_map.h"

namespace sdf_tracker {

/// A sparse map and where it lies in the frame a merge builds: T_target_map takes its points
/// there (a submap at its place in the map frame).
struct PlacedMap {
  const SparseTsdfMap* map = nullptr;
  Eigen::Isometry3d T_target_map = Eigen::Isometry3d::Identity();
};

/// Adds `voxel`'s observation to `into` as a fusion of the same measurements would have: the
/// weighted average of the two distances, the weights summed (nothing for an unobserved voxel).
/// The rule by which mergeMaps() and OverlaidMap read two maps as one.
inline void accumulate(const Voxel& voxel, Voxel* into) {
  if (voxel.weight <= 0.0f) return;
  const float weight = into->weight + voxel.weight;
  into->distance_m = (into->distance_m * into->weight + voxel.distance_m * voxel.weight) / weight;
  into->weight = weight;
}

/// One map of the parts, as if every part's measurements had been fused into it: each voxel the
/// weighted average of the parts' distances there, its weight their sum (one surface where two
/// parts overlap, not two). A part at the identity adds its voxels as they are; one moved is
/// resampled (trilinear distance and weight at the voxel's place in the part, where all eight
/// samples around it are observed). The result has the first part's lattice; every part must
/// have the same (throws std::invalid_argument naming the part that differs, or a null one).
/// Throws std::invalid_argument as well for no parts.
SparseTsdfMap mergeMaps(const std::vector<PlacedMap>& parts);

}  // namespace sdf_tracker
