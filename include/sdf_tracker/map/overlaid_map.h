#pragma once

#include <memory>

#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// Two maps of one lattice read as one map holding both maps' measurements would be: where both
/// hold a value, their weighted average (by the samples' weights, as fusing one's frames into the
/// other averages them); where one holds a value, that one's. Where `over`'s value is settled (its
/// weight at least `settled_weight`, the cap of the running average: a map's new frames then move
/// it little), `over`'s alone, and `under` is not read there.
///
/// What the tracker reads while a new submap is young: the recent submaps (over) keep the ground
/// they hold, the active submap (under) adds what only it has seen and what it sees again. A
/// read-only view: both maps must outlive it and stay unchanged while a sampler of it is in use;
/// the mutating calls throw std::logic_error.
class OverlaidMap final : public TsdfMap {
 public:
  /// Throws std::invalid_argument when the two maps' lattices differ or settled_weight is not
  /// positive.
  OverlaidMap(const TsdfMap& over, const TsdfMap& under, float settled_weight);

  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override;
  Eigen::AlignedBox3f holdableRegion() const override;
  std::unique_ptr<FieldSampler> sampler(const Eigen::AlignedBox3f& region_W) const override;
  void clear() override;
  bool holdsColour() const override { return over_.holdsColour() || under_.holdsColour(); }
  void enableColour() override;
  size_t voxelCount() const override { return over_.voxelCount() + under_.voxelCount(); }
  bool observesNothing() const override { return over_.observesNothing() && under_.observesNothing(); }
  size_t memoryBytes() const override { return 0; }  ///< a view: it holds no voxels of its own
  std::unique_ptr<TsdfMap> clone() const override;

 private:
  const TsdfMap& over_;
  const TsdfMap& under_;
  float settled_weight_;
};

}  // namespace sdf_tracker
