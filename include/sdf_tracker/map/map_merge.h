#pragma once

#include <cstdint>
#include <memory>
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

/// mergeMaps() of a sequence of parts that grows at its end (a map's closed submaps, oldest
/// first), kept from one call to the next: when the parts merged before are all still there, as
/// they were (the same map, revision and place), only the parts after them are merged onto the
/// kept result; any other change (a part changed, moved or gone: a pose graph solution) merges
/// every part again.
class GrowingMerge {
 public:
  /// A part, and what tells whether it changed since: its map's identity() and a revision of it
  /// (the revision its content is at).
  struct Part {
    PlacedMap placed;
    uint64_t identity = 0;
    uint64_t revision = 0;
  };
  /// The parts merged, as mergeMaps() of them would be (to float rounding); valid until the next
  /// call. Throws as mergeMaps() does (no parts, a part on another lattice).
  const SparseTsdfMap& update(const std::vector<Part>& parts);
  /// How many parts the last update() merged: all, or those added since the one before.
  size_t partsMerged() const { return parts_merged_; }

 private:
  struct State {
    uint64_t identity;
    uint64_t revision;
    Eigen::Matrix4d T_target_map;
    bool operator==(const State& o) const {
      return identity == o.identity && revision == o.revision && T_target_map == o.T_target_map;
    }
  };
  std::vector<State> merged_states_;  ///< of the parts in merged_, in order
  std::unique_ptr<SparseTsdfMap> merged_;
  size_t parts_merged_ = 0;
};

}  // namespace sdf_tracker
