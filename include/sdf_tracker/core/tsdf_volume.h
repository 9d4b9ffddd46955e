#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace sdf_tracker {

/// One lattice sample of the field: truncated signed distance [m] and the accumulated weight.
/// weight == 0 means "never observed"; its distance then holds the positive truncation.
struct Voxel {
  float distance_m;
  float weight;
};

/// Geometry of the dense grid. The lattice is axis-aligned in the world frame W: sample (i, j, k)
/// sits at origin_W + voxel_size_m * (i, j, k).
struct VolumeConfig {
  Eigen::Vector3i dims = Eigen::Vector3i(256, 256, 256);
  double voxel_size_m = 0.01;
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();
  /// Dmax: distances are clamped to at most this; unseen voxels hold it.
  double positive_truncation_m = 0.1;

  std::vector<std::string> validate() const;
  Eigen::Vector3d extent_m() const { return dims.cast<double>() * voxel_size_m; }
};

/// Result of sampling the field at a continuous point.
struct FieldSample {
  float distance_m;
  Eigen::Vector3f gradient;  ///< d(distance)/d(position), per metre of world.
};

/// A dense TSDF on one flat buffer (x fastest, then y, then z). Not thread safe for concurrent
/// writes to the same voxel; concurrent reads are safe.
class TsdfVolume {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit TsdfVolume(const VolumeConfig& config);

  const VolumeConfig& config() const { return config_; }
  const Eigen::Vector3i& dims() const { return config_.dims; }
  float voxelSize() const { return voxel_size_; }
  float positiveTruncation() const { return positive_truncation_; }
  size_t voxelCount() const { return voxels_.size(); }

  /// Sets every voxel back to (Dmax, 0): nothing observed.
  void clear();

  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * config_.dims.y() + j) * config_.dims.x() + i;
  }
  Voxel& at(int i, int j, int k) { return voxels_[index(i, j, k)]; }
  const Voxel& at(int i, int j, int k) const { return voxels_[index(i, j, k)]; }
  Voxel* data() { return voxels_.data(); }
  const Voxel* data() const { return voxels_.data(); }

  /// World position of lattice sample (i, j, k).
  Eigen::Vector3f position(int i, int j, int k) const {
    return origin_ + voxel_size_ * Eigen::Vector3f(i, j, k);
  }
  /// Continuous lattice coordinates of a world point.
  Eigen::Vector3f toLattice(const Eigen::Vector3f& p_W) const { return (p_W - origin_) * inv_voxel_size_; }

  /// Trilinear value and its analytic gradient at p_W. Returns false when p_W is outside the
  /// lattice or any of the 8 surrounding samples is unobserved. Thread safe.
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const;
  /// Trilinear value only; same validity rule as sample().
  bool sampleDistance(const Eigen::Vector3f& p_W, float* distance_m) const;

 private:
  /// Finds the cell of p_W and its fractional position; false outside the lattice.
  bool locate(const Eigen::Vector3f& p_W, size_t* base, Eigen::Vector3f* frac) const;

  VolumeConfig config_;
  float voxel_size_;
  float inv_voxel_size_;
  float positive_truncation_;
  Eigen::Vector3f origin_;
  size_t stride_y_;
  size_t stride_z_;
  std::vector<Voxel> voxels_;
};

}  // namespace sdf_tracker
