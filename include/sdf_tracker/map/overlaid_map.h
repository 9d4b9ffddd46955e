#pragma once

#include <memory>

#include "sdf_tracker/map/sparse_tsdf_map.h"

namespace sdf_tracker {

/// Two sparse maps of one lattice read as one map holding both maps' measurements would be (as
/// mergeMaps() would merge them, voxel by voxel): where both hold a voxel, the weighted average of
/// their distances (as fusing one's frames into the other averages them); where one holds it, that
/// one's. Where `over`'s voxel is settled (its weight at least `settled_weight`, the cap of the
/// running average: a map's new frames then move it little), `over`'s alone; a cell whose eight
/// voxels `over` holds settled does not read `under`.
///
/// What the tracker reads while a new submap is young: the recent submaps (over) keep the ground
/// they hold, the active submap (under) adds what only it has seen and what it sees again. A
/// read-only view: both maps must outlive it and stay unchanged while a sampler of it is in use;
/// the mutating calls throw std::logic_error.
class OverlaidMap final : public TsdfMap {
 public:
  /// Throws std::invalid_argument when the two maps' lattices differ or settled_weight is not
  /// positive.
  OverlaidMap(const SparseTsdfMap& over, const SparseTsdfMap& under, float settled_weight);

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
  class Sampler;
  /// The overlay's rule for the cell around p_W, its voxels read through readOver/readUnder(cell,
  /// corners).
  template <typename ReadOver, typename ReadUnder>
  bool sampleVia(const Eigen::Vector3f& p_W, const ReadOver& readOver, const ReadUnder& readUnder,
                 FieldSample* out) const;

  const SparseTsdfMap& over_;
  const SparseTsdfMap& under_;
  float settled_weight_;
};

}  // namespace sdf_tracker
