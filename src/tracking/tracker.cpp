#include "sdf_tracker/tracking/tracker.h"

#include <cmath>
#include <cstdint>
#include <sstream>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "sdf_tracker/util/parallel.h"
#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// The IRLS normal equations of one iteration, summed over points in double precision.
struct NormalEquations {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double squared_residual_sum = 0.0;
  double weighted_squared_residual_sum = 0.0;  ///< sum w D^2, the IRLS residual variance's numerator
  double squared_lever_sum = 0.0;  ///< sum |p - c|^2, the scale of the rotational columns.
  /// The surface the points cover, in voxel faces (each point's pixel footprint, at most one
  /// face): how many independent residuals there are, as the map holds one value per voxel.
  double covered_voxel_faces = 0.0;
  int count = 0;

  NormalEquations& operator+=(const NormalEquations& other) {
    H += other.H;
    g += other.g;
    squared_residual_sum += other.squared_residual_sum;
    weighted_squared_residual_sum += other.weighted_squared_residual_sum;
    squared_lever_sum += other.squared_lever_sum;
    covered_voxel_faces += other.covered_voxel_faces;
    count += other.count;
    return *this;
  }
};

/// The points are summed in this many stretches (forEachStretch: a thread whose core the system
/// gives to other work delays the sum by a stretch, not by its share of the points), and the
/// stretches' sums are added in order: the sum is the same whichever thread took which stretch,
/// and however many threads there are.
constexpr int kSumStretches = 64;

/// Beside another odometry, directions whose scaled eigenvalue is under this fraction of the
/// largest are left to it (twice the default MinInverseCondition), and the covariance states them
/// unconstrained, as an EKF's other inputs are such odometries. On a plain wall with Kinect
/// noise (bench/odometry_prior.sh, VGA) the weakest direction's ratio, noise alone, is under 9e-4
/// in 90 % of frames but up to 2e-2 in a few. Measured on QVGA drives with wheel odometry (ATE with
/// 2e-3, 3e-3, 5e-3, 1e-2): corridor 1.1, 1.7, 2.0, 21.7 cm; walk, bare walls 1.3, 0.9, 0.7, 0.7 cm;
/// single wall 0.6, 0.9, 0.9, 0.9 cm; furnished walk 0.75 cm throughout. Covariances stated with
/// it rather than MinInverseCondition (frames tracked from their true poses, within the two-sigma
/// ellipsoid): single wall 69 % instead of 32 %, the other drives 96-99 % (95-98 %); no frame of
/// fr1_xyz or redkitchen comes under it (their lowest: 2.6e-3, 3.5e-3).
constexpr double kMinInverseConditionBesideOdometry = 2e-3;

/// Below this the field is flat (truncated or unresolved) and the point says nothing.
constexpr float kMinGradientNorm = 0.2f;

/// How far, in voxels, the box of a frame's points at the guess is widened for the sampler.
constexpr float kSamplerMargin = 8.0f;

/// Huber weight, eq. (20).
inline float huberWeight(float residual, float k) {
  const float a = std::fabs(residual);
  return a <= k ? 1.0f : k / a;
}

/// Back-projects every stride-th pixel that holds a measurement.
std::vector<Eigen::Vector3f> backProjectSubsampled(const DepthImage& depth, const PinholeCamera& camera,
                                                   int stride) {
  std::vector<Eigen::Vector3f> points_C;
  points_C.reserve(static_cast<size_t>(depth.width() / stride + 1) * (depth.height() / stride + 1));
  for (int v = 0; v < depth.height(); v += stride) {
    for (int u = 0; u < depth.width(); u += stride) {
      const float z = depth.at(u, v);
      if (DepthImage::isMeasurement(z)) points_C.push_back(camera.backProject(u, v, z));
    }
  }
  return points_C;
}

/// How many of points_C, moved to the world by T_W_C, land in region_W.
size_t countInside(const std::vector<Eigen::Vector3f>& points_C, const Eigen::Isometry3d& T_W_C,
                   const Eigen::AlignedBox3f& region_W) {
  // All of space (a map that grows): every point is inside, no need to look.
  if (region_W.min().array().isInf().all() && region_W.max().array().isInf().all()) return points_C.size();
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  const int n = static_cast<int>(points_C.size());
  size_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count)
  for (int idx = 0; idx < n; ++idx) count += region_W.contains(T * points_C[idx]);
  return count;
}

/// The normal equations of points_C[begin, end) at pose T_W_C. The increment is expressed about
/// the camera centre c (world axes), so rotation and translation stay decoupled wherever the
/// volume's origin lies: d/dxi D(exp(xi) (p - c) + c) = [ (p - c) x grad D ; grad D ].
/// `footprint_per_depth2` is a pixel's footprint at 1 m over a voxel face, (stride / f / voxel
/// size)^2: a point at depth z covers that times z^2 faces.
NormalEquations sumPoints(const std::vector<Eigen::Vector3f>& points_C, int64_t begin, int64_t end,
                          const FieldSampler& field, float dmax, const Eigen::Isometry3d& T_W_C, float huber_k,
                          const DepthNoiseModel* noise, bool normalize_by_gradient, float footprint_per_depth2) {
  const Eigen::Isometry3f T = T_W_C.cast<float>();
  const Eigen::Vector3f c = T.translation();
  const float reference_sigma = noise ? noise->referenceSigma() : 1.0f;
  NormalEquations sum;
  for (int64_t idx = begin; idx < end; ++idx) {
    const Eigen::Vector3f p_W = T * points_C[idx];
    FieldSample s;
    if (!field.sample(p_W, &s) || !(std::fabs(s.distance_m) < dmax)) continue;
    if (normalize_by_gradient) {
      // A projective field overstates Euclidean distance by 1/cos(viewing angle) and so does
      // its gradient norm: dividing by it makes residuals metric and consistent across views.
      const float gradient_norm = s.gradient.norm();
      if (gradient_norm < kMinGradientNorm) continue;
      s.distance_m /= gradient_norm;
      s.gradient /= gradient_norm;
    }
    const Eigen::Vector3f lever = p_W - c;
    Vector6d J;
    J.head<3>() = lever.cross(s.gradient).cast<double>();
    J.tail<3>() = s.gradient.cast<double>();
    double w;
    if (noise) {
      const float z = points_C[idx].z();
      const float sigma_ratio = noise->sigma(z) / reference_sigma;
      w = huberWeight(s.distance_m, huber_k * std::max(1.0f, sigma_ratio)) *
          DepthNoiseModel::weightForSigmaRatio(sigma_ratio);
    } else {
      w = huberWeight(s.distance_m, huber_k);
    }
    sum.H.noalias() += (w * J) * J.transpose();
    sum.g.noalias() += (w * s.distance_m) * J;
    sum.squared_residual_sum += static_cast<double>(s.distance_m) * s.distance_m;
    sum.weighted_squared_residual_sum += w * s.distance_m * s.distance_m;
    sum.squared_lever_sum += lever.squaredNorm();
    const float z = points_C[idx].z();
    sum.covered_voxel_faces += std::min(1.0f, footprint_per_depth2 * z * z);
    ++sum.count;
  }
  return sum;
}

/// The normal equations of all points_C at pose T_W_C (sumPoints), summed in parallel.
NormalEquations buildNormalEquations(const std::vector<Eigen::Vector3f>& points_C, const FieldSampler& field,
                                     float dmax, const Eigen::Isometry3d& T_W_C, float huber_k,
                                     const DepthNoiseModel* noise, bool normalize_by_gradient,
                                     float footprint_per_depth2) {
  const int64_t n = static_cast<int64_t>(points_C.size());
  std::vector<NormalEquations> stretch_sums(kSumStretches);
  forEachStretch(kSumStretches, [&](int stretch) {
    stretch_sums[stretch] = sumPoints(points_C, n * stretch / kSumStretches, n * (stretch + 1) / kSumStretches, field,
                                      dmax, T_W_C, huber_k, noise, normalize_by_gradient, footprint_per_depth2);
  });
  NormalEquations total;
  for (const NormalEquations& sum : stretch_sums) total += sum;
  return total;
}

/// The data term in balanced units: the rotational block scaled by the RMS lever arm, so that
/// eigenvalues of rotation and translation compare. xi = scale .* y for y in these units.
struct ScaledEquations {
  Vector6d scale;
  Eigen::SelfAdjointEigenSolver<Matrix6d> eigen;  ///< of diag(scale) H diag(scale), ascending
  /// Directions whose eigenvalue reaches min_inverse_condition times the largest.
  int constrainedRank(double min_inverse_condition) const {
    const Vector6d& ev = eigen.eigenvalues();
    int rank = 0;
    for (int i = 0; i < 6; ++i) rank += ev(5) > 0.0 && ev(i) >= min_inverse_condition * ev(5);
    return rank;
  }
  /// Smallest over largest eigenvalue.
  double inverseCondition() const {
    const Vector6d& ev = eigen.eigenvalues();
    return ev(5) > 0.0 ? std::max(ev(0), 0.0) / ev(5) : 0.0;
  }
};

ScaledEquations scaleEquations(const NormalEquations& eq) {
  const double lever_rms = std::sqrt(eq.squared_lever_sum / std::max(eq.count, 1));
  ScaledEquations scaled;
  scaled.scale << Eigen::Vector3d::Constant(1.0 / std::max(lever_rms, 1e-6)), Eigen::Vector3d::Ones();
  scaled.eigen.compute(scaled.scale.asDiagonal() * eq.H * scaled.scale.asDiagonal());
  return scaled;
}

/// The regularised Gauss-Newton step (H + alpha I) xi = -g restricted to the `rank` best
/// constrained directions of the scaled equations; zero along the others.
Vector6d constrainedStep(const NormalEquations& eq, const ScaledEquations& scaled, int rank, double alpha) {
  if (rank <= 0) return Vector6d::Zero();
  const Eigen::MatrixXd V = scaled.eigen.eigenvectors().rightCols(rank);  // y = V z
  const Matrix6d S = scaled.scale.asDiagonal();
  const Matrix6d A_scaled = S * (eq.H + alpha * Matrix6d::Identity()) * S;
  const Eigen::MatrixXd A = V.transpose() * A_scaled * V;
  const Eigen::VectorXd b = -V.transpose() * (S * eq.g);
  const Eigen::VectorXd z = A.ldlt().solve(b);
  return S * (V * z);
}

/// What the data term's equations are divided by to make them an information matrix: the IRLS
/// residual variance, times the points per independent residual (points closer than a voxel share
/// the map's error there).
double dataVarianceScale(const NormalEquations& eq) {
  const double residual_variance = eq.weighted_squared_residual_sum / std::max(eq.count - 6, 1);
  const double points_per_independent = eq.count / std::max(eq.covered_voxel_faces, 1.0);
  return std::max(residual_variance * std::max(points_per_independent, 1.0), 1e-30);
}

Eigen::Isometry3d applyIncrementAboutCentre(const Vector6d& xi, const Eigen::Isometry3d& T_W_C) {
  const Eigen::Vector3d c = T_W_C.translation();
  return Eigen::Translation3d(c) * expSe3(xi) * Eigen::Translation3d(-c) * T_W_C;
}

/// The increment (about T_W_C's camera centre, as applyIncrementAboutCentre takes it) that moves
/// T_W_C to T_W_C_target.
Vector6d incrementTo(const Eigen::Isometry3d& T_W_C_target, const Eigen::Isometry3d& T_W_C) {
  const Eigen::Vector3d c = T_W_C.translation();
  return logSe3(Eigen::Translation3d(-c) * T_W_C_target * T_W_C.inverse() * Eigen::Translation3d(c));
}

/// The Gauss-Newton step with another odometry's pose as a Gaussian prior: the data term as an
/// information matrix (dataVarianceScale), regularised as always, plus the prior's information
/// pulling towards its pose. All six directions are solved: the prior constrains those the view
/// does not.
Vector6d stepWithOdometry(const NormalEquations& eq, double alpha, const MotionPrior::Odometry& odometry,
                          const Eigen::Isometry3d& T_W_C) {
  // The data term restricted to its constrained directions at kMinInverseConditionBesideOdometry:
  // along weaker ones the noise of a plain surface (and the depth quantisation's stripes, which
  // move with the camera) would pull the pose back to where the map was last fused, against the
  // odometry. In the scaled space the data term is V diag(eigenvalues) V^T.
  const ScaledEquations scaled = scaleEquations(eq);
  const int rank = scaled.constrainedRank(kMinInverseConditionBesideOdometry);
  // At most six columns: no heap allocation per Gauss-Newton iteration.
  const Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6> V = scaled.eigen.eigenvectors().rightCols(rank);
  const Matrix6d S = scaled.scale.asDiagonal(), S_inverse = scaled.scale.cwiseInverse().asDiagonal();
  const Matrix6d H = S_inverse * V * scaled.eigen.eigenvalues().tail(rank).asDiagonal() * V.transpose() * S_inverse;
  const Vector6d g = S_inverse * V * (V.transpose() * (S * eq.g));
  const double scale = dataVarianceScale(eq);
  const Vector6d information = odometry.sigma.array().square().inverse();
  const Matrix6d A = (H + alpha * Matrix6d::Identity()) / scale + Matrix6d(information.asDiagonal());
  const Vector6d b = -g / scale + information.cwiseProduct(incrementTo(odometry.T_W_C, T_W_C));
  return A.ldlt().solve(b);
}

/// T_W_C moved, along the directions outside the `rank` constrained ones of the scaled equations,
/// to where T_W_C_target lies: the constrained directions keep their fit.
Eigen::Isometry3d movedAlongUnconstrained(const ScaledEquations& scaled, int rank, const Eigen::Isometry3d& T_W_C,
                                          const Eigen::Isometry3d& T_W_C_target) {
  const Eigen::MatrixXd V = scaled.eigen.eigenvectors().leftCols(6 - rank);  // ascending: the weakest
  const Vector6d y = scaled.scale.cwiseInverse().cwiseProduct(incrementTo(T_W_C_target, T_W_C));
  return applyIncrementAboutCentre(scaled.scale.cwiseProduct(V * (V.transpose() * y)), T_W_C);
}

/// The estimate's covariance (TrackResult::covariance) from the last iteration's equations: the
/// IRLS residual variance times the inverse of the data term, over the `rank` constrained
/// directions of the scaled equations, widened by points per independent residual (points closer
/// than a voxel share the map's error there) and no smaller than kSurfaceResolution_voxels of
/// `voxel_size_m` along any; kUnconstrainedVariance along the other directions.
Matrix6d estimateCovariance(const NormalEquations& eq, const ScaledEquations& scaled, int rank, double voxel_size_m) {
  const double floor_variance = std::pow(kSurfaceResolution_voxels * voxel_size_m, 2);
  const double scale = dataVarianceScale(eq);
  Vector6d variance_scaled;  // along the scaled equations' eigenvectors, ascending eigenvalues
  for (int i = 0; i < 6; ++i) {
    const double eigenvalue = scaled.eigen.eigenvalues()(i);
    variance_scaled(i) =
        i >= 6 - rank && eigenvalue > 0.0 ? std::max(scale / eigenvalue, floor_variance) : kUnconstrainedVariance;
  }
  const Matrix6d& V = scaled.eigen.eigenvectors();
  const Matrix6d S = scaled.scale.asDiagonal();
  return S * V * variance_scaled.asDiagonal() * V.transpose() * S;
}

/// Where the points can land while the pose is refined from T_W_C: the box around them, widened by
/// `margin_m` for the motion of the iterations.
Eigen::AlignedBox3f regionReached(const std::vector<Eigen::Vector3f>& points_C, const Eigen::Isometry3d& T_W_C,
                                  float margin_m) {
  Eigen::AlignedBox3f box_C;
  for (const Eigen::Vector3f& p : points_C) box_C.extend(p);
  const Eigen::AlignedBox3f box_W = transformedBox(Eigen::Isometry3f(T_W_C.cast<float>()), box_C);
  if (box_W.isEmpty()) return box_W;
  return Eigen::AlignedBox3f(box_W.min().array() - margin_m, box_W.max().array() + margin_m);
}

}  // namespace

const char* toString(TrackStatus status) {
  switch (status) {
    case TrackStatus::kOk: return "ok";
    case TrackStatus::kNotConverged: return "not_converged";
    case TrackStatus::kTooFewPoints: return "too_few_points";
    case TrackStatus::kDegenerate: return "degenerate";
    case TrackStatus::kDiverged: return "diverged";
    case TrackStatus::kBadInput: return "bad_input";
    case TrackStatus::kLowOverlap: return "low_overlap";
    case TrackStatus::kRelocalising: return "relocalising";
    case TrackStatus::kAmbiguous: return "ambiguous";
  }
  return "unknown";
}

std::vector<std::string> TrackerConfig::validate() const {
  Violations v;
  v.require(!levels.empty(), "levels must not be empty");
  for (size_t i = 0; i < levels.size(); ++i) {
    const std::string name = "levels[" + std::to_string(i) + "]";
    v.requireInRange(name + ".stride", levels[i].stride, 1, 64);
    v.requireInRange(name + ".max_iterations", levels[i].max_iterations, 0, 1000);
  }
  v.requirePositive("huber_coefficient", huber_coefficient);
  v.requireNonNegative("regularization", regularization);
  v.requireNonNegative("convergence_threshold", convergence_threshold);
  v.requireInRange("min_valid_points", min_valid_points, 6, 100000000);
  v.requireInRange("min_inverse_condition", min_inverse_condition, 0.0, 1.0);
  v.requirePositive("max_final_step", max_final_step);
  v.merge("noise.", noise.validate());
  v.requireInRange("min_overlap", min_overlap, 0.0, 1.0);
  v.requirePositive("max_translation_m", max_translation_m);
  v.requirePositive("max_rotation_rad", max_rotation_rad);
  return v.list();
}

Tracker::Tracker(const TrackerConfig& config) : config_(config) {
  throwIfInvalid("tracker config", config.validate());
}

TrackResult Tracker::track(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                           const Eigen::Isometry3d& T_W_C_guess, const MotionPrior& prior) const {
  TrackResult result;
  result.T_W_C = T_W_C_guess;
  auto fail = [&result, &T_W_C_guess](TrackStatus status, const std::string& message) {
    result.status = status;
    result.message = message;
    result.T_W_C = T_W_C_guess;
    return result;
  };
  if (const std::string mismatch = camera.sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
    return fail(TrackStatus::kBadInput, mismatch);
  }
  if (depth.countMeasurements() == 0) return fail(TrackStatus::kBadInput, "depth image holds no valid measurement");
  if (!T_W_C_guess.matrix().allFinite()) return fail(TrackStatus::kBadInput, "pose guess is not finite");

  const float huber_k = static_cast<float>(config_.huber_coefficient * map.positiveTruncation());
  Eigen::Isometry3d T_W_C = T_W_C_guess;
  NormalEquations last;
  Eigen::Isometry3d T_W_C_of_last = T_W_C;  // where `last` was built
  std::vector<Eigen::Vector3f> points_C;  // the current level's
  std::unique_ptr<FieldSampler> field;
  for (const PyramidLevel& level : config_.levels) {
    points_C = backProjectSubsampled(depth, camera, level.stride);
    const float pixels_per_voxel_at_1m = static_cast<float>(map.voxelSize() * std::sqrt(camera.fx * camera.fy));
    const float footprint_per_depth2 =
        static_cast<float>(level.stride * level.stride) / (pixels_per_voxel_at_1m * pixels_per_voxel_at_1m);
    // The first level's points span the image; a few centimetres cover the motion of a frame.
    if (!field) field = map.sampler(regionReached(points_C, T_W_C_guess, kSamplerMargin * map.voxelSize()));
    int iterations = 0;
    for (int it = 1; it <= level.max_iterations; ++it) {
      T_W_C_of_last = T_W_C;
      last = buildNormalEquations(points_C, *field, map.positiveTruncation(), T_W_C, huber_k,
                                  config_.sensor_weights ? &config_.noise : nullptr, config_.normalize_by_gradient,
                                  footprint_per_depth2);
      if (last.count < config_.min_valid_points) {
        std::ostringstream msg;
        msg << "only " << last.count << " points at stride " << level.stride
            << " fell on observed parts of the volume (need " << config_.min_valid_points << ")";
        result.valid_points = last.count;
        return fail(TrackStatus::kTooFewPoints, msg.str());
      }
      // Sums, not means: alpha only matters along directions the points barely constrain.
      const double alpha = config_.regularization * it;
      Vector6d xi;
      if (prior.odometry) {
        xi = stepWithOdometry(last, alpha, *prior.odometry, T_W_C);
      } else if (config_.solve_constrained_directions) {
        const ScaledEquations scaled = scaleEquations(last);
        xi = constrainedStep(last, scaled, scaled.constrainedRank(config_.min_inverse_condition), alpha);
      } else {
        xi = (last.H + alpha * Matrix6d::Identity()).ldlt().solve(-last.g);
      }
      ++iterations;
      result.final_step = xi.norm();
      if (!xi.allFinite()) return fail(TrackStatus::kDiverged, "the Gauss-Newton step is not finite");
      T_W_C = applyIncrementAboutCentre(xi, T_W_C);
      if (result.final_step < config_.convergence_threshold) break;
    }
    result.iterations_per_level.push_back(iterations);
  }

  result.T_W_C = T_W_C;
  result.valid_points = last.count;
  result.rms_residual_m = last.count > 0 ? std::sqrt(last.squared_residual_sum / last.count) : 0.0;
  // Points beyond what the map could hold (outside a dense grid) are left out of the share.
  const size_t holdable = countInside(points_C, T_W_C_of_last, map.holdableRegion());
  result.overlap = holdable > 0 ? static_cast<double>(last.count) / holdable : 0.0;
  const bool move_unconstrained =
      !prior.odometry && prior.T_W_C_unconstrained && config_.solve_constrained_directions;
  if (last.count > 0) {
    const ScaledEquations scaled = scaleEquations(last);
    result.inverse_condition = scaled.inverseCondition();
    result.constrained_rank = scaled.constrainedRank(config_.min_inverse_condition);
    const int covariance_rank =
        scaled.constrainedRank(std::max(config_.min_inverse_condition, kMinInverseConditionBesideOdometry));
    result.covariance = estimateCovariance(last, scaled, covariance_rank, map.voxelSize());
    if (move_unconstrained && result.constrained_rank < 6) {
      T_W_C = result.T_W_C =
          movedAlongUnconstrained(scaled, result.constrained_rank, T_W_C, *prior.T_W_C_unconstrained);
    }
  }

  const Eigen::Isometry3d motion = T_W_C_guess.inverse() * T_W_C;
  std::ostringstream msg;
  if (!T_W_C.matrix().allFinite()) return fail(TrackStatus::kDiverged, "the pose became non-finite");
  if (motion.translation().norm() > config_.max_translation_m || rotationAngle(motion) > config_.max_rotation_rad) {
    msg << "the pose moved " << motion.translation().norm() << " m and " << rotationAngle(motion)
        << " rad from the guess (limits " << config_.max_translation_m << " m, " << config_.max_rotation_rad
        << " rad)";
    return fail(TrackStatus::kDiverged, msg.str());
  }
  if (result.overlap < config_.min_overlap) {
    msg << "at the estimate only " << std::lround(100.0 * result.overlap) << " % of the image's points lie near a "
        << "mapped surface (need " << std::lround(100.0 * config_.min_overlap) << " %): converged in the wrong place, "
        << "or the view is mostly new";
    return fail(TrackStatus::kLowOverlap, msg.str());
  }
  if (result.constrained_rank < 6) {
    msg << "the geometry constrains " << result.constrained_rank << " of six degrees of freedom (inverse condition "
        << result.inverse_condition << " < " << config_.min_inverse_condition << ")";
    if (!config_.solve_constrained_directions && !prior.odometry) return fail(TrackStatus::kDegenerate, msg.str());
    msg << (prior.odometry ? "; the others follow the odometry"
                           : move_unconstrained ? "; the others keep a decaying part of the predicted motion"
                                                : "; the others follow the guess");
    result.status = TrackStatus::kDegenerate;
    result.message = msg.str();
    result.pose_estimated = true;
    return result;
  }
  if (result.final_step > config_.max_final_step) {
    msg << "still moving after the last iteration (|delta xi| = " << result.final_step << " > "
        << config_.max_final_step << ")";
    result.status = TrackStatus::kNotConverged;
    result.message = msg.str();
    result.pose_estimated = true;
    return result;
  }
  result.status = TrackStatus::kOk;
  result.pose_estimated = true;
  return result;
}

}  // namespace sdf_tracker
