#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/camera/sensor_model.h"
#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// How much one new measurement counts in the running average, eq. (1)-(2).
enum class MeasurementWeighting {
  kConstant,      ///< w_hat = 1: a rolling average (the paper and the reference release).
  kSensorNoise,  ///< w_hat = inverse variance of the depth noise model: far, noisier depth counts less.
};

struct IntegratorConfig {
  /// Dmin (< 0): voxels further than this behind the measured surface are not updated at all.
  double negative_truncation_m = -0.04;
  /// Wmax: the weight cap, so the map keeps adapting.
  double max_weight = 64.0;
  MeasurementWeighting weighting = MeasurementWeighting::kConstant;
  DepthNoiseModel noise;

  std::vector<std::string> validate() const;
};

/// Projective fusion of depth images into a map, parallel over voxels (each voxel is written by
/// exactly one thread). The dense grid is swept row by row within the viewing frustum; the sparse
/// map first adds the blocks the truncation band reaches, then fuses every block in the frustum.
class Integrator {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit Integrator(const IntegratorConfig& config);

  const IntegratorConfig& config() const { return config_; }

  /// Fuses `depth` seen by `camera` from pose T_W_C (camera to world) into `map`.
  /// The depth image must match the camera's size (std::invalid_argument otherwise).
  /// Returns the number of voxels updated.
  size_t integrate(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                   TsdfMap* map) const;

 private:
  IntegratorConfig config_;
};

}  // namespace sdf_tracker
