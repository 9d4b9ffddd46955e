#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sdf_tracker/map/sparse_tsdf_map.h"

namespace sdf_tracker {

/// Two sparse maps of one lattice read as one map holding both maps' measurements would be (as
/// mergeMaps() would merge them, voxel by voxel): where both hold a voxel, the weighted average of
/// their distances (as fusing one's frames into the other averages them); where one holds it, that
/// one's. Where `over`'s voxel is settled (its weight at least `settled_weight`, the cap of the
/// running average: a map's new frames then move it little), `over`'s alone.
///
/// What the tracker reads while a new submap is young: the recent submaps (over) keep the ground
/// they hold, the active submap (under) adds what only it has seen and what it sees again. The
/// overlay keeps, for each block both maps hold, the two read as one, and is sampled as one sparse
/// map (its blocks where it has them, else `under`'s, else `over`'s): a sample costs what one
/// map's does, and update() takes in what a frame fused into `under` changed. Both maps
/// must outlive it and stay unchanged while a sampler of the overlay is in use. Sampling after
/// either changed and before update(), and the mutating calls of TsdfMap, throw std::logic_error.
class OverlaidMap final : public TsdfMap {
 public:
  /// Throws std::invalid_argument when the two maps' lattices differ or settled_weight is not
  /// positive.
  OverlaidMap(const SparseTsdfMap& over, const SparseTsdfMap& under, float settled_weight);

  /// Reads `under` again where it changed since the overlay was made or last updated (a frame
  /// fused into it, blocks removed or the map cleared), and all of it when `over` changed (not
  /// expected: the recent submaps are closed); nothing when neither did.
  void update();

  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override;
  Eigen::AlignedBox3f holdableRegion() const override;
  std::unique_ptr<FieldSampler> sampler(const Eigen::AlignedBox3f& region_W) const override;
  void clear() override;
  bool holdsColour() const override { return over_.holdsColour() || under_.holdsColour(); }
  void enableColour() override;
  size_t voxelCount() const override { return over_.voxelCount() + under_.voxelCount(); }
  bool observesNothing() const override { return over_.observesNothing() && under_.observesNothing(); }
  /// Its own blocks (one for each block both maps hold): the two maps' are theirs.
  size_t memoryBytes() const override { return combined_.memoryBytes(); }
  std::unique_ptr<TsdfMap> clone() const override;

 private:
  /// Makes combined_'s `blocks` (indices of blocks `under` holds) under's and over's read as one,
  /// for those over holds too.
  void combine(const std::vector<SparseTsdfMap::BlockIndex>& blocks);
  /// Neither map changed since combined_ took them in.
  bool isCurrent() const;
  /// Throws std::logic_error naming `call` unless isCurrent().
  void requireCurrent(const char* call) const;
  /// What is read where combined_ holds no block, in order: under's block, else over's.
  std::vector<const SparseTsdfMap*> layersBeneath() const;

  const SparseTsdfMap& over_;
  const SparseTsdfMap& under_;
  float settled_weight_;
  /// For each block both maps hold, the two read as one (no colour: only sampled).
  SparseTsdfMap combined_;
  /// The revisions of over_ and under_ that combined_ holds.
  uint64_t over_revision_read_;
  uint64_t under_revision_read_ = 0;
  /// The three read as one through their tables (no region): what sample() reads.
  std::unique_ptr<SparseTsdfMap::RegionReader> tables_;
};

}  // namespace sdf_tracker
