#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/camera/sensor_model.h"
#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// One coarse-to-fine level: use every `stride`-th pixel in u and v, for at most `max_iterations`.
struct PyramidLevel {
  int stride;
  int max_iterations;
};

struct TrackerConfig {
  /// Coarse-to-fine schedule as data: the paper's 4/2/1 x 12/6/2 by default.
  std::vector<PyramidLevel> levels = {{4, 12}, {2, 6}, {1, 2}};
  /// Huber threshold k = huber_coefficient * Dmax (RobustStatisticCoefficient).
  double huber_coefficient = 0.02;
  /// Weight each point by the inverse variance of its depth (noise model) on top of Huber, and
  /// widen its Huber threshold by the same noise ratio. Off: the paper's plain IRLS.
  bool sensor_weights = false;
  DepthNoiseModel noise;
  /// Divide each residual and its gradient by the gradient norm, turning projective distances
  /// (too long by 1/cos of the angle between ray and surface normal) into metric ones. Off: the
  /// paper's plain D(Tp).
  bool normalize_by_gradient = false;
  /// alpha = regularization * (iteration within the level, from 1), eq. (21).
  double regularization = 0.01;
  /// A level ends early when |delta xi| falls below this (ConvergenceCondition).
  double convergence_threshold = 1e-4;
  /// Fewer valid points than this at any iteration: kTooFewPoints.
  int min_valid_points = 200;
  /// An eigenvalue of the scaled normal equations below this fraction of the largest marks a
  /// direction the geometry does not constrain (e.g. sliding along a wall): kDegenerate.
  double min_inverse_condition = 1e-4;
  /// What a degenerate frame does. false (the paper): it fails, the pose is held and nothing is
  /// fused. true: each Gauss-Newton step solves only the directions the geometry constrains (the
  /// eigenvectors above min_inverse_condition), the others keep the guess, i.e. the motion model's
  /// prediction; the frame is still reported kDegenerate with its constrained rank, but its pose
  /// is used and fused.
  bool solve_constrained_directions = false;
  /// A final step |delta xi| larger than this: kNotConverged.
  double max_final_step = 5e-3;
  /// At the estimate, fewer than this fraction of the last (finest) level's points (of those the
  /// map could hold) lie in the truncation band of a mapped surface: kLowOverlap. Tracking that
  /// converged in the wrong place (typically when it resumes after a loss) fits only a part of the
  /// image; frame-to-frame overlap keeps tracked frames above 0.75 on real sequences, above 0.55
  /// on the synthetic house walk (bench/results/2026-11-23_real_data_limits.md). 0: off (the paper).
  double min_overlap = 0.0;
  /// Motion from the guess beyond either limit: kDiverged (larger than a hand-held camera moves
  /// between two frames at 30 Hz, and beyond the truncation band's basin of convergence).
  double max_translation_m = 0.25;
  double max_rotation_rad = 0.5;

  std::vector<std::string> validate() const;
};

enum class TrackStatus {
  kOk,
  kNotConverged,  ///< iterations ran out with the pose still moving; or (set by the pipeline) they
                  ///< ran out after missing frames at a pose the map contradicts (the guess is
                  ///< handed back then, not estimated).
  kTooFewPoints,  ///< too few points landed in observed parts of the field.
  kDegenerate,    ///< the geometry does not constrain all six degrees of freedom (e.g. one plane).
                  ///< With solve_constrained_directions the pose is still estimated (see tracked()).
  kDiverged,      ///< the solution ran away or became non-finite.
  kBadInput,      ///< the depth image is empty, of the wrong size, or holds no measurement.
  kLowOverlap,    ///< at the estimate, too few of the image's points lie near mapped surfaces.
  kRelocalising,  ///< set by the pipeline, never the tracker: the camera's pose is not known and
                  ///< the map is being searched for it (nothing is fused meanwhile).
  kAmbiguous,     ///< set by the pipeline: as kRelocalising, and two or more places of the map fit
                  ///< the view alike, so none is accepted until it tells them apart.
};

const char* toString(TrackStatus status);

/// A fitted surface is placed no better than this fraction of a voxel (the map's resolution, its
/// interpolation and the sensor's quantisation): the floor of a pose's standard deviation along
/// each constrained direction, in the balanced units (metres at the RMS lever arm for rotations).
/// On exact synthetic depth the equations alone claim tens of micrometres; the errors measured
/// there are a millimetre (test_tracker).
constexpr double kSurfaceResolution_voxels = 0.1;

/// The variance a pose's covariance states along a direction the view does not constrain: nothing
/// is known there (in the tracker's balanced units: metres, and radians times the RMS lever arm).
constexpr double kUnconstrainedVariance = 1e6;

struct TrackResult {
  TrackStatus status = TrackStatus::kBadInput;
  /// The estimate (camera to world). For kOk and kNotConverged it is the optimised pose (unless the
  /// pipeline refused it: pose_estimated false); for any other status it is the guess, unchanged.
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  std::vector<int> iterations_per_level;
  double rms_residual_m = 0.0;  ///< RMS of D at the valid points of the last iteration.
  int valid_points = 0;         ///< points used in the last iteration.
  /// valid_points over the points of the last (finest) level that land, at the estimate, where
  /// the map could hold a value (inside a dense grid; anywhere for the sparse map).
  double overlap = 0.0;
  double inverse_condition = 0.0;
  /// How many of the six directions the geometry constrained in the last iteration.
  int constrained_rank = 0;
  /// T_W_C is an estimate (ok, not converged, or degenerate solved in its constrained
  /// directions), not the guess handed back.
  bool pose_estimated = false;
  double final_step = 0.0;  ///< |delta xi| of the last iteration.
  /// The covariance of T_W_C, for a pose estimated: of a small motion xi = [rotation; translation]
  /// about the camera centre along the world's axes (rad^2, m^2; T = Tr(c) exp(xi) Tr(-c) T_W_C),
  /// from the last iteration's normal equations scaled by their residual variance, at least a
  /// tenth of a voxel of standard deviation along every constrained direction. Along
  /// directions the view does not constrain (constrained_rank < 6), and along those too weak to
  /// hold against another odometry (a plain wall's noise), the variance is
  /// kUnconstrainedVariance. Zero when nothing was estimated.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  std::string message;      ///< why, in words, when status != kOk.

  bool ok() const { return status == TrackStatus::kOk; }
  /// The frame's pose can be used and the frame fused: ok, or degenerate with its constrained
  /// directions solved and the rest predicted.
  bool tracked() const { return ok() || (status == TrackStatus::kDegenerate && pose_estimated); }
};

/// What is known of the frame's pose besides its image.
struct MotionPrior {
  /// Another odometry's pose for this frame (a robot's wheels) with its standard deviations
  /// [rotation (rad); translation (m)] about the camera centre along the world's axes: a Gaussian
  /// prior that each Gauss-Newton step weighs against the map's normal equations (those scaled by
  /// their residual variance). Where the view constrains the pose the map wins; along a bare wall
  /// or a corridor the odometry does.
  struct Odometry {
    Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
    Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Ones();
  };
  std::optional<Odometry> odometry;
  /// Without odometry: where the estimate goes along the directions a degenerate view does not
  /// constrain, instead of following the guess (SdfPipeline: the last pose moved on by a part of
  /// the constant-velocity prediction that shrinks with every such frame, so that the motion along
  /// directions nothing observes decays instead of persisting).
  std::optional<Eigen::Isometry3d> T_W_C_unconstrained;
};

/// Registers a depth image directly against the TSDF (Section III): Gauss-Newton on the sum of
/// squared field values at the transformed points, Huber IRLS, growing Tikhonov regularisation,
/// coarse-to-fine pixel strides. Stateless apart from its config; thread safe.
class Tracker {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit Tracker(const TrackerConfig& config);

  const TrackerConfig& config() const { return config_; }

  TrackResult track(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                    const Eigen::Isometry3d& T_W_C_guess, const MotionPrior& prior = {}) const;

 private:
  TrackerConfig config_;
};

}  // namespace sdf_tracker
