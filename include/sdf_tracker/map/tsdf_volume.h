#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// The optional 4-byte voxel: distance as a fraction of +-2 Dmax in 16 bits (6 um steps for
/// Dmax = 0.1 m) and weight in 1/256 steps up to 255.99.
struct CompactVoxel {
  int16_t distance;
  uint16_t weight;
};

/// Converts between a storage type and Voxel; the identity for Voxel itself.
template <typename Stored>
struct VoxelCodec;

template <>
struct VoxelCodec<Voxel> {
  explicit VoxelCodec(float /*positive_truncation_m*/) {}
  Voxel decode(const Voxel& v) const { return v; }
  Voxel encode(const Voxel& v) const { return v; }
};

template <>
struct VoxelCodec<CompactVoxel> {
  static constexpr float kMaxWeight = 65535.0f / 256.0f;
  explicit VoxelCodec(float positive_truncation_m)
      : to_metres(2.0f * positive_truncation_m / 32767.0f), to_units(32767.0f / (2.0f * positive_truncation_m)) {}
  Voxel decode(const CompactVoxel& v) const { return {v.distance * to_metres, v.weight * (1.0f / 256.0f)}; }
  CompactVoxel encode(const Voxel& v) const {
    const float d = std::max(-32767.0f, std::min(32767.0f, v.distance_m * to_units));
    // Any positive weight keeps at least one step, or a lightly weighted voxel would read as unseen.
    const float w = v.weight <= 0.0f ? 0.0f : std::max(1.0f, std::min(65535.0f, v.weight * 256.0f + 0.5f));
    return {static_cast<int16_t>(std::lround(d)), static_cast<uint16_t>(w)};
  }
  float to_metres;
  float to_units;
};

/// A dense TSDF on one flat buffer (x fastest, then y, then z) of Voxel or CompactVoxel. Not thread
/// safe for concurrent writes to the same voxel; concurrent reads are safe.
class TsdfVolume : public TsdfMap {
 public:
  /// Throws std::invalid_argument naming every violation of the config (of any type: a dense
  /// grid of the config's geometry), and std::runtime_error when the grid needs more memory than
  /// the process can still allocate (requireMemory), before allocating it.
  explicit TsdfVolume(const VolumeConfig& config);

  const Eigen::Vector3i& dims() const { return config_.dims; }
  size_t voxelCount() const override { return voxel_count_; }
  bool observesNothing() const override;
  bool compact() const { return config_.compact_voxels; }
  size_t memoryBytes() const override {
    return (compact() ? compact_.size() * sizeof(CompactVoxel) : voxels_.size() * sizeof(Voxel)) +
           colours_.size() * sizeof(VoxelColour);
  }
  std::unique_ptr<TsdfMap> clone() const override { return std::make_unique<TsdfVolume>(*this); }
  /// The lattice's cells, where a trilinear sample can exist.
  Eigen::AlignedBox3f holdableRegion() const override {
    return Eigen::AlignedBox3f(position(0, 0, 0), position(config_.dims - Eigen::Vector3i::Ones()));
  }

  /// Sets every voxel back to (Dmax, 0): nothing observed, and no colour.
  void clear() override;
  bool holdsColour() const override { return !colours_.empty(); }
  void enableColour() override;
  /// The colours, one per voxel in the voxels' order; nullptr when the grid holds no colour.
  VoxelColour* colours() { return colours_.empty() ? nullptr : colours_.data(); }
  const VoxelColour* colours() const { return colours_.empty() ? nullptr : colours_.data(); }
  /// A voxel's colour (none seen when the grid holds no colour).
  VoxelColour colour(size_t index) const { return colours_.empty() ? VoxelColour{} : colours_[index]; }
  VoxelColour colour(int i, int j, int k) const { return colour(index(i, j, k)); }
  /// Sets a voxel's colour; the grid must hold colour (enableColour()).
  void setColour(size_t index, const VoxelColour& colour) { colours_[index] = colour; }
  void setColour(int i, int j, int k, const VoxelColour& c) { setColour(index(i, j, k), c); }

  /// Copies the z-slabs [k_begin, k_end) of `source` (their colours too), which must have this volume's config
  /// (std::invalid_argument otherwise). Lets a reader take a snapshot of a live map in short
  /// pieces, holding the writer's lock only for one piece at a time.
  void copySlabsFrom(const TsdfVolume& source, int k_begin, int k_end);

  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * config_.dims.y() + j) * config_.dims.x() + i;
  }
  /// Decoded voxel (exact for the float format). Not for hot loops: see withStorage().
  Voxel voxel(size_t index) const {
    return compact() ? VoxelCodec<CompactVoxel>(positive_truncation_).decode(compact_[index]) : voxels_[index];
  }
  Voxel voxel(int i, int j, int k) const { return voxel(index(i, j, k)); }
  void setVoxel(size_t index, const Voxel& v) {
    if (compact()) compact_[index] = VoxelCodec<CompactVoxel>(positive_truncation_).encode(v);
    else voxels_[index] = v;
  }
  void setVoxel(int i, int j, int k, const Voxel& v) { setVoxel(index(i, j, k), v); }

  /// Calls fn(storage pointer, codec) with the typed buffer, so kernels compile once per format.
  template <typename Fn>
  decltype(auto) withStorage(Fn&& fn) {
    return compact() ? fn(compact_.data(), VoxelCodec<CompactVoxel>(positive_truncation_))
                     : fn(voxels_.data(), VoxelCodec<Voxel>(positive_truncation_));
  }
  template <typename Fn>
  decltype(auto) withStorage(Fn&& fn) const {
    return compact() ? fn(static_cast<const CompactVoxel*>(compact_.data()), VoxelCodec<CompactVoxel>(positive_truncation_))
                     : fn(static_cast<const Voxel*>(voxels_.data()), VoxelCodec<Voxel>(positive_truncation_));
  }

  /// Trilinear value and its analytic gradient at p_W; false outside the grid or next to an
  /// unobserved sample. Thread safe.
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override;

 private:
  /// Finds the cell of p_W and its fractional position; false outside the lattice.
  bool locate(const Eigen::Vector3f& p_W, size_t* base, Eigen::Vector3f* frac) const;
  template <typename Stored>
  bool sampleFrom(const Stored* voxels, const VoxelCodec<Stored>& codec, const Eigen::Vector3f& p_W,
                  FieldSample* out) const;

  size_t stride_y_;
  size_t stride_z_;
  size_t voxel_count_;
  std::vector<Voxel> voxels_;           ///< used unless compact
  std::vector<CompactVoxel> compact_;  ///< used when compact
  std::vector<VoxelColour> colours_;  ///< empty: no colour; else one per voxel
};

}  // namespace sdf_tracker
