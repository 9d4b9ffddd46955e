#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sdf_tracker {

/// One lattice sample of the field: truncated signed distance [m] and the accumulated weight.
/// weight == 0 means "never observed"; its distance then holds the positive truncation.
struct Voxel {
  float distance_m;
  float weight;
};

/// The colour a voxel was seen in, 8 bits a channel: the running average of the pixels that
/// showed it near the surface, one observation a frame, its weight bounded (at most
/// IntegratorConfig::max_colour_weight) so that it follows a change of light. weight == 0: never
/// seen in colour. 4 bytes a voxel, kept beside the voxels (a map without colour holds none).
struct VoxelColour {
  uint8_t r = 0, g = 0, b = 0;
  uint8_t weight = 0;

  bool operator==(const VoxelColour& o) const { return r == o.r && g == o.g && b == o.b && weight == o.weight; }
  bool operator!=(const VoxelColour& o) const { return !(*this == o); }
};

/// The furthest any truncation band reaches from a surface [m], in front of it or behind, and the
/// largest weight a voxel may hold: the bounds of the parameters that set them, and of what a map
/// file may hold.
constexpr double kMaxTruncationDistance_m = 10.0;
constexpr double kMaxVoxelWeight = 1e9;

/// Why `voxel` cannot be one of a map whose positive truncation is `positive_truncation_m`
/// ("distance 1e+30 m is not within [-10, 0.1] m"), or "" when it can: a finite distance within
/// [-kMaxTruncationDistance_m, positive truncation], a finite weight within [0, kMaxVoxelWeight].
std::string voxelProblem(const Voxel& voxel, double positive_truncation_m);

/// How the map stores its voxels.
enum class MapType {
  kDense,   ///< one flat grid of fixed extent (the paper's and the reference release's)
  kSparse,  ///< voxel blocks allocated where surfaces are seen; grows with the scene
};
const char* toString(MapType type);

/// Geometry of the map. The lattice is axis-aligned in the world frame W: sample (i, j, k) sits at
/// origin_W + voxel_size_m * (i, j, k), for any integers with the sparse map and within `dims`
/// with the dense one.
struct VolumeConfig {
  MapType type = MapType::kDense;
  /// The dense grid's size in voxels (not read by the sparse map).
  Eigen::Vector3i dims = Eigen::Vector3i(256, 256, 256);
  double voxel_size_m = 0.01;
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();
  /// Dmax: distances are clamped to at most this; unseen voxels hold it.
  double positive_truncation_m = 0.1;
  /// Dense grid only: store CompactVoxel (4 bytes) instead of Voxel (8 bytes): half the memory,
  /// distances quantised to 2 Dmax / 32767 and weights to 1/256 (so MaxWeight must stay below 256).
  bool compact_voxels = false;

  std::vector<std::string> validate() const;
  /// "dense grid 256x256x256 of 0.02 m" or "sparse map of 0.02 m voxels in blocks of 8^3".
  std::string describe() const;
  Eigen::Vector3d extent_m() const { return dims.cast<double>() * voxel_size_m; }
  /// Same lattice and storage (type, dims, voxel size, positive truncation, voxel format),
  /// wherever placed.
  bool sameLattice(const VolumeConfig& other) const {
    return type == other.type && dims == other.dims && voxel_size_m == other.voxel_size_m &&
           positive_truncation_m == other.positive_truncation_m && compact_voxels == other.compact_voxels;
  }
  /// The same lattice at the same place: voxel i of one is voxel i of the other.
  bool sameGrid(const VolumeConfig& other) const { return sameLattice(other) && origin_W == other.origin_W; }
};

/// Result of sampling the field at a continuous point.
struct FieldSample {
  float distance_m;
  Eigen::Vector3f gradient;  ///< d(distance)/d(position), per metre of world.
};

/// Samples one map many times over one region of space: what a loop over a frame's points uses
/// (see TsdfMap::sampler()). Valid while its map is neither changed nor destroyed; concurrent
/// reads are safe.
class FieldSampler {
 public:
  virtual ~FieldSampler() = default;
  /// As TsdfMap::sample(), with the same result.
  virtual bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const = 0;
};

/// A truncated signed distance field on a lattice, whatever its storage: what tracking, ray
/// casting and surface normals read. Concurrent reads are safe.
class TsdfMap {
 public:
  virtual ~TsdfMap() = default;

  const VolumeConfig& config() const { return config_; }
  MapType type() const { return config_.type; }
  float voxelSize() const { return voxel_size_; }
  float positiveTruncation() const { return positive_truncation_; }

  /// World position of lattice sample (i, j, k).
  Eigen::Vector3f position(int i, int j, int k) const { return origin_ + voxel_size_ * Eigen::Vector3f(i, j, k); }
  Eigen::Vector3f position(const Eigen::Vector3i& voxel) const { return position(voxel.x(), voxel.y(), voxel.z()); }
  /// Continuous lattice coordinates of a world point.
  Eigen::Vector3f toLattice(const Eigen::Vector3f& p_W) const { return (p_W - origin_) * inv_voxel_size_; }
  /// The trilinear value and gradient from the eight corner samples of a cell (corner c at
  /// offset (c & 1, c >> 1 & 1, c >> 2 & 1)) and the fractional position f in it; false when a
  /// corner is unobserved.
  bool interpolate(const Voxel (&corners)[8], const Eigen::Vector3f& f, FieldSample* out) const;

  /// Trilinear value and its analytic gradient at p_W. Returns false when any of the 8
  /// surrounding samples is unobserved (or outside a dense grid). Thread safe.
  virtual bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const = 0;
  /// Trilinear value only; same validity rule as sample().
  bool sampleDistance(const Eigen::Vector3f& p_W, float* distance_m) const {
    FieldSample s;
    if (!sample(p_W, &s)) return false;
    *distance_m = s.distance_m;
    return true;
  }

  /// Where this map could ever hold a value: all of space for a map that grows, the lattice's
  /// cells for a dense grid. Points outside say nothing about how well a pose fits.
  virtual Eigen::AlignedBox3f holdableRegion() const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    return Eigen::AlignedBox3f(Eigen::Vector3f::Constant(-kInf), Eigen::Vector3f::Constant(kInf));
  }

  /// A sampler prepared for points in region_W: as fast as the storage allows there (a sparse map
  /// indexes the region's blocks directly instead of hashing per sample); points outside it still
  /// sample correctly, only slower. The map must outlive it and stay unchanged while it is used.
  virtual std::unique_ptr<FieldSampler> sampler(const Eigen::AlignedBox3f& region_W) const;

  /// Forgets everything: every voxel back to (Dmax, 0), and the colour with it.
  virtual void clear() = 0;
  /// The map keeps a colour beside every voxel: since the first image fused in colour (or a file
  /// that held colour), until clear().
  virtual bool holdsColour() const = 0;
  /// Makes room for a colour beside every voxel, none seen yet (nothing when there is room).
  /// Throws std::runtime_error, changing nothing, when the dense grid's colours need more memory
  /// than the process can still allocate.
  virtual void enableColour() = 0;
  /// Voxels stored (observed or not).
  virtual size_t voxelCount() const = 0;
  /// No voxel holds an observation (weight > 0): a new or cleared map, or an empty file's. There
  /// is nothing in it to track against, save or show.
  virtual bool observesNothing() const = 0;
  /// Bytes held by voxel storage.
  virtual size_t memoryBytes() const = 0;
  virtual std::unique_ptr<TsdfMap> clone() const = 0;
  /// Tells maps apart: new for every map constructed (built or loaded), kept by copies and
  /// clone(), so a reader holding a copy can tell a replaced map from a changed one.
  uint64_t identity() const { return identity_; }

 protected:
  /// The config's geometry with `type` for its storage; throws std::invalid_argument naming every
  /// violation of the config.
  TsdfMap(VolumeConfig config, MapType type);
  TsdfMap(const TsdfMap&) = default;
  TsdfMap& operator=(const TsdfMap&) = default;
  TsdfMap(TsdfMap&&) = default;
  TsdfMap& operator=(TsdfMap&&) = default;


  VolumeConfig config_;
  float voxel_size_;
  float inv_voxel_size_;
  float positive_truncation_;
  Eigen::Vector3f origin_;

 private:
  uint64_t identity_;
};

inline bool TsdfMap::interpolate(const Voxel (&c)[8], const Eigen::Vector3f& f, FieldSample* out) const {
  for (const Voxel& v : c) {
    if (v.weight <= 0.0f) return false;
  }
  const float x = f.x(), y = f.y(), z = f.z();
  // Interpolate along x on the four x-edges, then along y, then along z.
  const float d00 = c[0].distance_m + x * (c[1].distance_m - c[0].distance_m);
  const float d10 = c[2].distance_m + x * (c[3].distance_m - c[2].distance_m);
  const float d01 = c[4].distance_m + x * (c[5].distance_m - c[4].distance_m);
  const float d11 = c[6].distance_m + x * (c[7].distance_m - c[6].distance_m);
  const float d0 = d00 + y * (d10 - d00);
  const float d1 = d01 + y * (d11 - d01);
  out->distance_m = d0 + z * (d1 - d0);

  const float gx00 = c[1].distance_m - c[0].distance_m;
  const float gx10 = c[3].distance_m - c[2].distance_m;
  const float gx01 = c[5].distance_m - c[4].distance_m;
  const float gx11 = c[7].distance_m - c[6].distance_m;
  const float gx0 = gx00 + y * (gx10 - gx00);
  const float gx1 = gx01 + y * (gx11 - gx01);
  const float gy0 = d10 - d00;
  const float gy1 = d11 - d01;
  out->gradient = Eigen::Vector3f(gx0 + z * (gx1 - gx0), gy0 + z * (gy1 - gy0), d1 - d0) * inv_voxel_size_;
  return true;
}

/// A new, empty map of config.type.
std::unique_ptr<TsdfMap> makeMap(const VolumeConfig& config);

}  // namespace sdf_tracker
