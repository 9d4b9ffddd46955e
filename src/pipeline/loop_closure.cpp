#include "sdf_tracker/pipeline/loop_closure.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <omp.h>

#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

constexpr double kRadPerDeg = M_PI / 180.0;

/// Three of `first`, then three of `second`: a 6-vector of per-axis values.
Eigen::Matrix<double, 6, 1> threeAndThree(double first, double second) {
  return (Eigen::Matrix<double, 6, 1>() << Eigen::Vector3d::Constant(first), Eigen::Vector3d::Constant(second))
      .finished();
}

PoseInformation diagonalInformation(double sigma_m, double sigma_rad) {
  return threeAndThree(1.0 / (sigma_m * sigma_m), 1.0 / (sigma_rad * sigma_rad)).asDiagonal();
}

/// The drift model's standard deviations over `distance_m` of tracked path [m, rad], without the
/// floors (what a stretch inside one submap adds to a loop, whose own sigma is its floor).
Eigen::Vector2d driftSigma(const LoopClosureConfig& config, double distance_m) {
  return {config.odometry_drift * distance_m, config.odometry_drift_deg_per_m * distance_m * kRadPerDeg};
}

}  // namespace

std::vector<std::string> LoopClosureConfig::validate() const {
  Violations v;
  v.requireInRange("check_interval_frames", check_interval_frames, 1, 100000);
  v.requireInRange("min_submap_age", min_submap_age, 2, 100000);
  v.requireNonNegative("min_path_m", min_path_m);
  v.requirePositive("search_radius_m", search_radius_m);
  v.requirePositive("max_drift_m", max_drift_m);
  v.requireInRange("search_angle_deg", search_angle_deg, 1.0, 180.0);
  v.requireInRange("max_search_frames", max_search_frames, 1, 1000);
  v.requireInRange("retry_after_frames", retry_after_frames, 0, 100000);
  v.requirePositive("loop_sigma_m", loop_sigma_m);
  v.requirePositive("loop_sigma_deg", loop_sigma_deg);
  v.requireNonNegative("odometry_drift", odometry_drift);
  v.requireNonNegative("odometry_drift_deg_per_m", odometry_drift_deg_per_m);
  v.requirePositive("odometry_floor_m", odometry_floor_m);
  v.requirePositive("odometry_floor_deg", odometry_floor_deg);
  return v.list();
}

PoseInformation odometryEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& motion) {
  const Eigen::Vector2d drift = driftSigma(config, motion.translation().norm());
  return diagonalInformation(config.odometry_floor_m + drift(0), config.odometry_floor_deg * kRadPerDeg + drift(1));
}

PoseInformation loopEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& T_S_from,
                                    const Eigen::Isometry3d& T_S_C, const Eigen::Matrix<double, 6, 6>& fit_covariance_S,
                                    const Eigen::Isometry3d& T_S_to) {
  // The old map where the camera was found lies as the tracker's drift from S's anchor placed it:
  // as uncertain as the camera's fit, about its centre.
  const Eigen::Vector2d old_drift = driftSigma(config, (T_S_C.translation() - T_S_from.translation()).norm());
  Eigen::Matrix<double, 6, 6> camera_covariance = fit_covariance_S;
  camera_covariance.diagonal() += threeAndThree(old_drift(1) * old_drift(1), old_drift(0) * old_drift(0));  // [w; v]
  // A small motion xi = [w; v] of the camera about its centre c (along S's axes) moves the `to`
  // node, at (R, t) in S, by R^T w (rotation) and R^T (v + w x (t - c)) (translation), in its own
  // frame: the edge's error, translation first.
  const Eigen::Matrix3d Rt = T_S_to.linear().transpose();
  const Eigen::Vector3d lever = T_S_to.translation() - T_S_C.translation();
  Eigen::Matrix<double, 6, 6> J = Eigen::Matrix<double, 6, 6>::Zero();
  J.block<3, 3>(0, 0) = -Rt * skew(lever);
  J.block<3, 3>(0, 3) = Rt;
  J.block<3, 3>(3, 0) = Rt;
  Eigen::Matrix<double, 6, 6> covariance = J * camera_covariance * J.transpose();
  // The tracked stretch from the camera to its submap's anchor, as an odometry edge holds it.
  const Eigen::Vector2d own_drift = driftSigma(config, lever.norm());
  const double sigma_rad = config.loop_sigma_deg * kRadPerDeg;
  const double sigma2_m = config.loop_sigma_m * config.loop_sigma_m + own_drift(0) * own_drift(0);
  const double sigma2_rad = sigma_rad * sigma_rad + own_drift(1) * own_drift(1);
  covariance.diagonal() += threeAndThree(sigma2_m, sigma2_rad);
  // Inverted through its eigen decomposition: along an unconstrained direction the variance is
  // kUnconstrainedVariance and the information next to zero, without a near-singular solve.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(0.5 * (covariance + covariance.transpose()));
  const PoseInformation information =
      eigen.eigenvectors() * eigen.eigenvalues().cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  return 0.5 * (information + information.transpose());
}

LoopDetector::LoopDetector(const LoopClosureConfig& config, const RelocaliserConfig& relocaliser,
                           const TrackerConfig& tracker, const PlaceMemoryConfig& places)
    : config_(config), relocaliser_(relocaliser, tracker), search_places_(places) {
  const std::vector<std::string> violations = config.validate();
  if (!violations.empty()) throw std::invalid_argument("invalid loop closure config: " + violations.front());
  frames_until_check_ = config_.check_interval_frames;
}

LoopDetector::~LoopDetector() {
  if (running_.valid()) running_.wait();
}

void LoopDetector::reset() {
  if (running_.valid()) running_.wait();
  running_ = std::future<Outcome>();
  relocaliser_.cancel();
  search_submap_ = -1;
  search_map_.reset();
  search_frames_ = 0;
  frames_until_check_ = config_.check_interval_frames;
  joined_.clear();
}

std::optional<int> LoopDetector::candidate(const DepthImage& depth, const Eigen::Isometry3d& T_map_C,
                                           const SubmapPlace& active, const SubmapStore& closed,
                                           const PlaceMemory& places, const std::vector<int>& keyframe_submaps) const {
  const int newest_candidate = active.node - config_.min_submap_age;
  if (newest_candidate < 0 || places.empty()) return std::nullopt;
  const PlaceCode code = places.encoder().encode(depth);
  std::optional<int> best;
  double best_dissimilarity = relocaliser_.config().max_dissimilarity;
  const std::vector<Keyframe>& keyframes = places.keyframes();
  for (size_t k = 0; k < keyframes.size() && k < keyframe_submaps.size(); ++k) {
    const int submap = keyframe_submaps[k];
    if (submap < 0 || submap > newest_candidate || submap >= static_cast<int>(closed.size())) continue;
    if (std::find(joined_.begin(), joined_.end(), submap) != joined_.end()) continue;
    if (active.path_m - closed.place(submap).path_m < config_.min_path_m) continue;
    const Eigen::Isometry3d offset = T_map_C.inverse() * closed.place(submap).T_map_W * keyframes[k].T_W_C;
    if (offset.translation().norm() > config_.search_radius_m ||
        rotationAngle(offset) > config_.search_angle_deg * kRadPerDeg) {
      continue;
    }
    const double dissimilarity = PlaceEncoder::dissimilarity(code, keyframes[k].code);
    if (dissimilarity <= best_dissimilarity) {
      best_dissimilarity = dissimilarity;
      best = submap;
    }
  }
  return best;
}

LoopDetector::Step LoopDetector::step(const DepthImage& depth, const PinholeCamera& camera,
                                      const Eigen::Isometry3d& T_W_C, const SubmapPlace& active,
                                      const SubmapStore& closed, const PlaceMemory& places,
                                      const std::vector<int>& keyframe_submaps) {
  Step finished;
  if (running_.valid()) {
    if (running_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return finished;
    finished = conclude(running_.get());
  }
  Job job;
  const Eigen::Isometry3d T_map_C = active.T_map_W * T_W_C;
  if (search_submap_ < 0) {
    if (--frames_until_check_ > 0) return finished;
    frames_until_check_ = config_.check_interval_frames;
    const std::optional<int> submap = candidate(depth, T_map_C, active, closed, places, keyframe_submaps);
    if (!submap) return finished;
    search_places_.clear();
    const std::vector<Keyframe>& keyframes = places.keyframes();
    for (size_t k = 0; k < keyframes.size() && k < keyframe_submaps.size(); ++k) {
      if (keyframe_submaps[k] == *submap) search_places_.add(keyframes[k]);
    }
    search_submap_ = *submap;
    search_frames_ = 0;
    job.begins = true;
  } else {
    job.motion = last_search_T_W_C_.inverse() * T_W_C;
  }
  job.depth = depth;
  job.camera = camera;
  job.map = search_map_;
  job.closed = &closed;
  job.submap = search_submap_;
  // Where the graph puts the camera in the old submap: the first start of the search.
  job.guess = closed.place(search_submap_).T_map_W.inverse() * T_map_C;
  job.T_W_C = T_W_C;
  job.frame_submap = active.node;
  last_search_T_W_C_ = T_W_C;
  running_ = std::async(std::launch::async, [this, job = std::move(job)]() mutable { return search(std::move(job)); });
  return finished;
}

LoopDetector::Outcome LoopDetector::search(Job job) {
  // This thread's own setting: the tracking thread keeps the other cores.
  omp_set_num_threads(1);
  const auto start = std::chrono::steady_clock::now();
  Outcome outcome;
  try {
    if (job.begins) {
      job.map = job.closed->map(job.submap);
      relocaliser_.begin(*job.map);
    }
    outcome.found = relocaliser_.step(job.depth, job.camera, *job.map, search_places_, {job.guess}, job.motion);
  } catch (const std::invalid_argument&) {
    outcome.no_surface = true;  // begin(): a submap without a surface
  } catch (const std::runtime_error& e) {
    outcome.no_surface = true;  // map(): the swap file failed
    outcome.read_error = e.what();
  }
  outcome.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  job.depth = DepthImage();
  outcome.job = std::move(job);
  return outcome;
}

LoopDetector::Step LoopDetector::conclude(Outcome outcome) {
  if (outcome.no_surface) {
    search_submap_ = -1;
    search_map_.reset();
    Step nothing;  // nothing was searched
    nothing.message = outcome.read_error;
    return nothing;
  }
  search_map_ = outcome.job.map;
  Step result;
  result.submap = search_submap_;
  result.search_ms = outcome.ms;
  result.T_W_C = outcome.job.T_W_C;
  result.frame_submap = outcome.job.frame_submap;
  ++search_frames_;
  result.searched = true;
  const Relocaliser::Step& found = outcome.found;
  const bool accepted = found.outcome == Relocaliser::Outcome::kAccepted;
  // However well it fits, a place further from the graph's guess than the drift can have taken
  // the camera is not the one looked for.
  const Eigen::Isometry3d offset = outcome.job.guess.inverse() * found.T_W_C;
  const double drift_m = offset.translation().norm();
  const double drift_deg = rotationAngle(offset) / kRadPerDeg;
  const bool plausible = drift_m <= config_.max_drift_m && drift_deg <= config_.search_angle_deg;
  if (accepted && plausible) {
    result.match = LoopMatch{search_submap_, found.T_W_C, found.track.covariance};
  } else if (accepted) {
    std::ostringstream why;
    // In the parameter's name (frames.csv is read by users); the turn's bound is no parameter.
    why << "found " << drift_m << " m and " << drift_deg << " deg from where the graph puts the camera, beyond LoopMaxDrift ("
        << config_.max_drift_m << " m) or a turn of " << config_.search_angle_deg << " deg";
    result.message = why.str();
  } else if (search_frames_ >= config_.max_search_frames || found.outcome == Relocaliser::Outcome::kAmbiguous) {
    result.message = found.message.empty() ? std::string(toString(found.outcome)) : found.message;
  } else {
    return result;  // still confirming or searching
  }
  relocaliser_.cancel();
  search_submap_ = -1;
  search_map_.reset();
  frames_until_check_ = result.match ? config_.check_interval_frames : std::max(1, config_.retry_after_frames);
  return result;
}

LoopDetector::Step LoopDetector::finish() {
  if (!running_.valid()) return Step();
  return conclude(running_.get());
}

}  // namespace sdf_tracker
