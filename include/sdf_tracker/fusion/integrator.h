#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
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
  /// The most a voxel's colour weighs (each frame that shows it adds one, up to this; at most
  /// 255): lower follows a change of light sooner, higher averages more frames.
  int max_colour_weight = 16;

  std::vector<std::string> validate() const;
};

/// Voxels within this many voxel sizes of the measured surface (along the ray) take its pixel's
/// colour: those a mesh vertex between them is coloured from, even where the surface is seen
/// at a slant, and not those in front of it, which the ray passes on its way.
constexpr float kColourBandVoxels = 2.0f;

/// Projective fusion of depth images into a map, parallel over voxels (each voxel is written by
/// exactly one thread). The dense grid is swept row by row within the viewing frustum; the sparse
/// map first adds the blocks the truncation band reaches, then fuses every block in the frustum.
class Integrator {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit Integrator(const IntegratorConfig& config);

  const IntegratorConfig& config() const { return config_; }

  /// Fuses `depth` seen by `camera` from pose T_W_C (camera to world) into `map`, and with
  /// `colour` (registered to the depth) its colours into the voxels near the surface (the map
  /// makes room for colour at the first such image). Distances and weights do not depend on the
  /// colour. Both images must match the camera's size (std::invalid_argument otherwise, changing
  /// nothing). Returns the number of voxels updated.
  size_t integrate(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C, TsdfMap* map,
                   const ColourImage* colour = nullptr) const;

 private:
  IntegratorConfig config_;
};

}  // namespace sdf_tracker
