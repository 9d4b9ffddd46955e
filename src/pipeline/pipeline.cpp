#include "sdf_tracker/pipeline/pipeline.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

/// Failed frames after which a fit from the held pose is no longer taken without confirmation.
constexpr int kBriefLossFrames = 2;
/// No frame for this many of the camera's intervals between tracked frames (and longer than the
/// prediction bridges): frames went missing, and the camera may have been carried anywhere.
constexpr double kMissingFrameIntervals = 10.0;
/// Along directions a degenerate view does not constrain, each such frame keeps this part of the
/// predicted motion: the motion decays (to half in 7 frames) instead of persisting, and all of
/// it adds up to no more than nine frames' worth.
constexpr double kUnobservedMotionKept = 0.9;

double millisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// What the pipeline may read or write of a sparse map around a view: the box of the view up to
/// its furthest depth plus the truncation, widened by the motion a frame may still make.
BlockBox blocksNearView(const SparseTsdfMap& map, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                        float furthest_m, double max_motion_m) {
  const Eigen::AlignedBox3f view = camera.viewBox(T_W_C.cast<float>(), furthest_m + map.positiveTruncation());
  const float margin = static_cast<float>(max_motion_m) + map.blockSize();
  return map.blockRange(Eigen::AlignedBox3f(view.min().array() - margin, view.max().array() + margin));
}

/// The budget for the config, or none.
std::unique_ptr<MapMemoryBudget> makeBudget(const PipelineConfig& config, MapType type) {
  if (config.max_map_memory_mb <= 0.0 || type != MapType::kSparse) return nullptr;
  const std::string directory =
      config.swap_directory.empty() ? std::filesystem::temp_directory_path().string() : config.swap_directory;
  try {
    const size_t bytes = std::max<size_t>(1, static_cast<size_t>(config.max_map_memory_mb * 1048576.0));
    return std::make_unique<MapMemoryBudget>(bytes, directory);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(std::string("MaxMemoryMB needs a swap file (SwapDirectory): ") + e.what());
  }
}

/// The box that holds every voxel the map may have observed: a sparse map's blocks, a dense grid.
Eigen::AlignedBox3f mappedBox(const TsdfMap& map) {
  if (map.type() != MapType::kSparse) return map.holdableRegion();
  Eigen::Vector3i first, dims;
  static_cast<const SparseTsdfMap&>(map).bounds(&first, &dims);
  return Eigen::AlignedBox3f(map.position(first), map.position(first + dims - Eigen::Vector3i::Ones()));
}

/// The grid's geometry with its origin placed for the start pose.
VolumeConfig placedVolume(const PipelineConfig& config) {
  VolumeConfig volume = config.volume;
  volume.origin_W = SdfPipeline::volumeOriginFor(config);
  return volume;
}

}  // namespace

std::vector<std::string> PipelineConfig::validate() const {
  Violations v;
  v.merge("volume.", volume.validate());
  v.merge("integrator.", integrator.validate());
  v.merge("tracker.", tracker.validate());
  v.merge("raycast.", raycast.validate());
  v.merge("places.", places.validate());
  v.merge("relocaliser.", relocaliser.validate());
  v.requireNonNegative("min_depth_m", min_depth_m);
  v.require(max_depth_m > min_depth_m, "max_depth_m must be > min_depth_m (got " + std::to_string(max_depth_m) +
                                           " <= " + std::to_string(min_depth_m) + ")");
  for (int axis = 0; axis < 3; ++axis) {
    v.requireInRange("initial_camera_in_grid[" + std::to_string(axis) + "]", initial_camera_in_grid[axis], -1.0, 2.0);
  }
  v.requireNonNegative("min_pose_change_to_fuse", min_pose_change_to_fuse);
  if (volume.compact_voxels) {
    v.require(integrator.max_weight <= VoxelCodec<CompactVoxel>::kMaxWeight,
              "integrator.max_weight must be <= " + std::to_string(VoxelCodec<CompactVoxel>::kMaxWeight) +
                  " with compact voxels (got " + std::to_string(integrator.max_weight) + ")");
  }
  v.requireNonNegative("reset_after_failures", reset_after_failures);
  v.requirePositive("max_prediction_gap_s", max_prediction_gap_s);
  v.requireInRange("odometry_error", odometry_error, 1e-4, 1.0);
  if (volume.positive_truncation_m > 0.0 && integrator.negative_truncation_m < 0.0) {
    // The tracker needs samples on both sides of the surface: at least one voxel each way.
    std::ostringstream s;
    s << "the truncation band (" << integrator.negative_truncation_m << " .. " << volume.positive_truncation_m
      << " m) must span at least one voxel (" << volume.voxel_size_m << " m) on each side";
    v.require(volume.positive_truncation_m >= volume.voxel_size_m &&
                  -integrator.negative_truncation_m >= volume.voxel_size_m,
              s.str());
  }
  return v.list();
}

Eigen::Vector3d SdfPipeline::volumeOriginFor(const PipelineConfig& config) {
  return -config.initial_camera_in_grid.cwiseProduct(config.volume.extent_m());
}

SdfPipeline::SdfPipeline(const PipelineConfig& config)
    : config_(config), motion_(config.max_prediction_gap_s) {
  throwIfInvalid("pipeline config", config.validate());
  map_ = makeMap(placedVolume(config));
  budget_ = makeBudget(config, map_->type());
  integrator_ = std::make_unique<Integrator>(config.integrator);
  tracker_ = std::make_unique<Tracker>(config.tracker);
  places_ = std::make_unique<PlaceMemory>(config.places);
  relocaliser_ = std::make_unique<Relocaliser>(config.relocaliser, config.tracker);
}

void SdfPipeline::clearMap() {
  map_->clear();
  if (budget_) budget_->clear();
  places_->clear();
  relocaliser_->cancel();
  pose_unknown_ = false;
  map_initialised_ = false;
  consecutive_failures_ = 0;
}

void SdfPipeline::reset() {
  clearMap();
  T_W_C_ = T_W_C_last_fused_ = Eigen::Isometry3d::Identity();
  motion_.clear();
  T_odom_C_held_.reset();
  held_pose_timestamp_s_ = tracked_interval_s_ = std::numeric_limits<double>::quiet_NaN();
}

void SdfPipeline::setMap(std::unique_ptr<TsdfMap> map, std::unique_ptr<PlaceMemory> places) {
  if (!map) throw std::invalid_argument("setMap: no map");
  if (map->observesNothing()) throw std::invalid_argument("the map holds no observed voxel: nothing to track against");
  map_ = std::move(map);
  config_.volume = map_->config();
  budget_ = makeBudget(config_, map_->type());
  places_ = places ? std::move(places) : std::make_unique<PlaceMemory>(config_.places);
  T_W_C_ = T_W_C_last_fused_ = Eigen::Isometry3d::Identity();
  map_initialised_ = true;
  consecutive_failures_ = 0;
  motion_.clear();
  T_odom_C_held_.reset();
  held_pose_timestamp_s_ = tracked_interval_s_ = std::numeric_limits<double>::quiet_NaN();
  relocaliser_->cancel();
  pose_unknown_ = config_.relocalise;
  search_guess_.reset();  // the start pose is tried anyway, as the held pose
}

void SdfPipeline::relocalise(const std::optional<Eigen::Isometry3d>& guess) {
  if (!config_.relocalise) throw std::logic_error("relocalisation is off (Relocalise)");
  if (!map_initialised_) throw std::logic_error("nothing is mapped yet: there is nowhere to relocalise in");
  if (guess) {
    // A camera further from every mapped voxel than it sees cannot be in the map.
    const Eigen::AlignedBox3d box = mappedBox(*map_).cast<double>();
    const Eigen::Vector3d position = guess->translation();
    const Eigen::Vector3d outside = (box.min() - position).cwiseMax(position - box.max()).cwiseMax(0.0);
    const double distance_m = position.allFinite() ? outside.stableNorm() : HUGE_VAL;  // no overflow at 1e300
    if (!(distance_m <= config_.max_depth_m)) {
      std::ostringstream s;
      s << std::setprecision(4) << "the camera at (" << position.transpose() << ") m would be " << distance_m
        << " m from the map (its voxels lie within (" << box.min().transpose() << ") .. (" << box.max().transpose()
        << ") m), beyond MaxDepth " << config_.max_depth_m << " m: it could see nothing of it";
      throw std::invalid_argument(s.str());
    }
  }
  relocaliser_->cancel();
  pose_unknown_ = true;
  search_guess_ = guess;
  T_odom_C_held_.reset();
}

void SdfPipeline::updateConfig(const PipelineConfig& candidate) {
  throwIfInvalid("pipeline config", candidate.validate());
  if (!candidate.volume.sameLattice(config_.volume) ||
      candidate.initial_camera_in_grid != config_.initial_camera_in_grid ||
      candidate.max_map_memory_mb != config_.max_map_memory_mb || candidate.swap_directory != config_.swap_directory) {
    throw std::invalid_argument(
        "the grid (size, cell size, positive truncation, voxel storage, placement, memory bound) cannot change live");
  }
  if (candidate.places.descriptor != config_.places.descriptor) {
    throw std::invalid_argument("the place memory's descriptor cannot change live");
  }
  integrator_ = std::make_unique<Integrator>(candidate.integrator);
  tracker_ = std::make_unique<Tracker>(candidate.tracker);
  // A search under way starts again with the new settings at the next frame that needs one.
  relocaliser_ = std::make_unique<Relocaliser>(candidate.relocaliser, candidate.tracker);
  if (!candidate.relocalise) pose_unknown_ = false;
  if (candidate.max_prediction_gap_s != config_.max_prediction_gap_s) motion_ = MotionModel(candidate.max_prediction_gap_s);
  config_ = candidate;
}

DepthImage SdfPipeline::prepareDepth(const DepthImage& depth, const PinholeCamera& camera) {
  DepthImage filtered;
  if (camera.distortion.isZero()) {
    filtered = depth;
  } else {
    if (!undistortion_ || undistortion_->camera() != camera) undistortion_.emplace(camera);
    filtered = undistortion_->apply(depth);
  }
  const float lo = static_cast<float>(config_.min_depth_m), hi = static_cast<float>(config_.max_depth_m);
  float* z = filtered.data();
  const size_t n = static_cast<size_t>(filtered.width()) * filtered.height();
  for (size_t i = 0; i < n; ++i) {
    if (!(z[i] >= lo && z[i] <= hi)) z[i] = 0.0f;  // NaN fails both comparisons
  }
  return filtered;
}

MotionPrior::Odometry odometryPrior(const Eigen::Isometry3d& T_W_C_predicted, const Eigen::Isometry3d& motion,
                                    double odometry_error) {
  const double distance_m = motion.translation().norm();
  MotionPrior::Odometry prior;
  prior.T_W_C = T_W_C_predicted;
  prior.sigma << Eigen::Vector3d::Constant(
      std::max(odometry_error * rotationAngle(motion) + kOdometryHeadingDrift_rad_per_m * distance_m,
               kMinOdometrySigma_rad)),
      Eigen::Vector3d::Constant(std::max(odometry_error * distance_m, kMinOdometrySigma_m));
  return prior;
}

Eigen::Isometry3d SdfPipeline::predictPose(double timestamp_s) const {
  if (!config_.predict_motion || consecutive_failures_ > 0) return T_W_C_;
  return motion_.predict(timestamp_s);
}

void SdfPipeline::restoreNear(const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera, float furthest_m,
                              FrameReport* report) {
  if (!budget_ || budget_->swap().size() == 0) return;
  auto& sparse = static_cast<SparseTsdfMap&>(*map_);
  try {
    report->blocks_swapped_in +=
        budget_->restore(&sparse, blocksNearView(sparse, camera, T_W_C, furthest_m, config_.tracker.max_translation_m));
  } catch (const std::runtime_error& e) {
    report->swap_error = e.what();
  }
}

void SdfPipeline::evictAwayFrom(const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera, float furthest_m,
                                FrameReport* report) {
  if (!budget_) return;
  auto& sparse = static_cast<SparseTsdfMap&>(*map_);
  const BlockBox keep = blocksNearView(sparse, camera, T_W_C, furthest_m, config_.tracker.max_translation_m);
  if (keep.empty()) return;  // the view left the map's reach: nothing to go by
  try {
    report->blocks_swapped_out += budget_->evict(&sparse, keep, T_W_C.translation().cast<float>());
    report->swap_notice = budget_->takeStartNotice();
    report->swap_warning = budget_->takeOverrunWarning(sparse);
  } catch (const std::runtime_error& e) {
    report->swap_error = e.what();
  }
}

std::unique_ptr<TsdfMap> SdfPipeline::copyWholeMap() const {
  if (!budget_ || budget_->swap().size() == 0) return map_->clone();
  return std::make_unique<SparseTsdfMap>(budget_->whole(static_cast<const SparseTsdfMap&>(*map_)));
}

bool SdfPipeline::search(const DepthImage& filtered, const PinholeCamera& camera, FrameReport* report) {
  const auto start = std::chrono::steady_clock::now();
  RelocalisationReport& r = report->relocalisation;
  r.searched = true;
  const std::string tracking_failure = report->track.message;
  if (!relocaliser_->searching()) {
    try {
      relocaliser_->begin(*map_);
    } catch (const std::invalid_argument& e) {
      pose_unknown_ = false;  // a map without a surface: the next frame is tracked from the held pose
      r.message = std::string("no search: ") + e.what();
      report->track.status = TrackStatus::kRelocalising;
      report->track.T_W_C = T_W_C_;
      report->track.pose_estimated = false;
      report->track.message = r.message + (tracking_failure.empty() ? "" : " (from the held pose: " + tracking_failure + ")");
      return false;
    }
    // A pose the user gave first, then the one held (the last known, or the map's start pose).
    search_guesses_.clear();
    if (pose_unknown_ && search_guess_) search_guesses_.push_back(*search_guess_);
    search_guesses_.push_back(T_W_C_);
  }
  const Relocaliser::Step step = relocaliser_->step(filtered, camera, *map_, *places_, search_guesses_);
  r.outcome = step.outcome;
  r.candidates_tried = step.candidates_tried;
  r.frames_spent = relocaliser_->framesSpent();
  r.confirmed = step.confirmed;
  r.places_fitting = step.places_fitting;
  r.message = step.message;
  r.search_ms = millisecondsSince(start);
  if (step.outcome == Relocaliser::Outcome::kAccepted) {
    report->track = step.track;
    T_W_C_ = step.T_W_C;
    pose_unknown_ = false;
    return true;
  }
  std::ostringstream s;
  s << r.frames_spent << (r.frames_spent == 1 ? " frame, " : " frames, ")
    << relocaliser_->candidatesTried() << " candidates tried";
  if (step.outcome == Relocaliser::Outcome::kConfirming) {
    s << "; a candidate fits, confirmed on " << step.confirmed << " of " << relocaliser_->config().confirm_frames
      << " frames";
  } else if (!step.message.empty()) {
    s << "; " << step.message;
  }
  if (!tracking_failure.empty()) s << " (from the held pose: " << tracking_failure << ")";
  report->track.status =
      step.outcome == Relocaliser::Outcome::kAmbiguous ? TrackStatus::kAmbiguous : TrackStatus::kRelocalising;
  report->track.T_W_C = T_W_C_;
  report->track.pose_estimated = false;
  report->track.message = s.str();
  return false;
}

FrameReport SdfPipeline::processFrame(const DepthImage& depth, const PinholeCamera& camera, double timestamp_s,
                                      const std::optional<Eigen::Isometry3d>& T_odom_C) {
  return process(depth, camera, timestamp_s, std::nullopt, T_odom_C);
}

FrameReport SdfPipeline::processFrameAtPose(const DepthImage& depth, const PinholeCamera& camera,
                                            const Eigen::Isometry3d& T_W_C, double timestamp_s) {
  return process(depth, camera, timestamp_s, T_W_C, std::nullopt);
}

FrameReport SdfPipeline::process(const DepthImage& depth, const PinholeCamera& camera, double timestamp_s,
                                 const std::optional<Eigen::Isometry3d>& given_T_W_C,
                                 const std::optional<Eigen::Isometry3d>& T_odom_C) {
  FrameReport report;
  report.track.T_W_C = T_W_C_;
  const std::string mismatch = camera.sizeMismatch(depth.width(), depth.height());
  if (!mismatch.empty() || depth.empty()) {
    report.track.status = TrackStatus::kBadInput;
    report.track.message = mismatch.empty() ? "the depth image is empty" : mismatch;
    return report;
  }
  const DepthImage filtered = prepareDepth(depth, camera);
  const PinholeCamera ideal_camera = camera.withoutDistortion();  // the camera of the prepared image
  if (filtered.countMeasurements() == 0) {
    report.track.status = TrackStatus::kBadInput;
    report.track.message = "no pixel holds a depth within [" + std::to_string(config_.min_depth_m) + ", " +
                           std::to_string(config_.max_depth_m) + "] m";
    return report;
  }

  const float furthest_m = budget_ ? filtered.maxMeasurement() : 0.0f;  // only swapping needs it

  if (config_.reset_after_failures > 0 && consecutive_failures_ >= config_.reset_after_failures) {
    clearMap();
    T_W_C_last_fused_ = T_W_C_;  // the new map starts where the camera was last
    report.reset = true;
  }

  if (!map_initialised_) {
    if (given_T_W_C) T_W_C_ = T_W_C_last_fused_ = *given_T_W_C;
    report.track.status = TrackStatus::kOk;
    report.track.T_W_C = T_W_C_;
    report.track.message = "first frame: map initialised at the start pose";
    // The map is anchored at this pose: it is known as well as the map can place anything (in
    // rad for rotations, as about a lever arm of 1 m).
    report.track.covariance = Eigen::Matrix<double, 6, 6>::Identity() *
                              std::pow(kSurfaceResolution_voxels * map_->voxelSize(), 2);
    report.initialised_map = true;
  } else if (!given_T_W_C && pose_unknown_) {
    // The pose is not known at all (a loaded map, relocalise()): only a confirmed candidate
    // tells where the camera is.
    const auto start = std::chrono::steady_clock::now();
    restoreNear(T_W_C_, ideal_camera, furthest_m, &report);
    const bool found = search(filtered, ideal_camera, &report);
    report.tracking_ms = millisecondsSince(start);
    if (!found) {
      ++consecutive_failures_;
      motion_.clear();
      return report;
    }
    consecutive_failures_ = 0;
  } else {
    const auto start = std::chrono::steady_clock::now();
    // The other odometry's motion since the held pose, else constant velocity.
    report.predicted_by_odometry = !given_T_W_C && T_odom_C && T_odom_C_held_;
    const Eigen::Isometry3d predicted = given_T_W_C ? *given_T_W_C
                                        : report.predicted_by_odometry
                                            ? T_W_C_ * (T_odom_C_held_->inverse() * *T_odom_C)
                                            : predictPose(timestamp_s);
    // Swapped blocks the frame may see come back first; the held pose's too, for the retry below.
    restoreNear(predicted, ideal_camera, furthest_m, &report);
    restoreNear(T_W_C_, ideal_camera, furthest_m, &report);
    MotionPrior prior;
    if (report.predicted_by_odometry) {
      prior.odometry = odometryPrior(predicted, T_odom_C_held_->inverse() * *T_odom_C, config_.odometry_error);
    } else if (!given_T_W_C) {
      prior.T_W_C_unconstrained = T_W_C_ * expSe3(kUnobservedMotionKept * logSe3(T_W_C_.inverse() * predicted));
    }
    report.track = tracker_->track(filtered, ideal_camera, *map_, predicted, prior);
    if (!given_T_W_C && !report.track.tracked() && !predicted.isApprox(T_W_C_)) {
      // The prediction may have led astray (the camera stopped or turned): try from the last pose.
      TrackResult from_last = tracker_->track(filtered, ideal_camera, *map_, T_W_C_, prior);
      if (from_last.tracked()) report.track = std::move(from_last);
    }
    report.tracking_ms = millisecondsSince(start);
    // In a brief loss the camera cannot have gone far: a fit from the held pose is taken at once.
    // After a longer one the camera may be anywhere (carried with its view blocked), and a fit
    // there must be confirmed like any candidate: the held pose stays until then.
    // Frames missing for longer than the prediction bridges, and for many of the camera's frame
    // intervals (a camera at 1 Hz misses none), count as such a loss too (NaN times, or no
    // interval known yet: no gap), unless the other odometry measured the motion across them.
    const double unseen_s = timestamp_s - held_pose_timestamp_s_;
    const bool unseen_gap = !report.predicted_by_odometry && unseen_s > config_.max_prediction_gap_s &&
                            unseen_s > kMissingFrameIntervals * tracked_interval_s_;
    const bool brief_loss = (consecutive_failures_ <= kBriefLossFrames && !unseen_gap) || !config_.relocalise;
    if (unseen_gap && report.track.tracked() && config_.relocalise) {
      std::ostringstream s;
      s << std::setprecision(3) << unseen_s << " s since the last tracked frame: the held pose's fit must be confirmed";
      report.track.message = s.str();
    }
    if (given_T_W_C) {
      T_W_C_ = *given_T_W_C;  // the estimate is reported; the given pose is fused
    } else if (report.track.pose_estimated && brief_loss) {
      T_W_C_ = report.track.T_W_C;
    }
    bool found = false;
    if (given_T_W_C) {
      relocaliser_->cancel();
    } else if (report.track.tracked() && brief_loss) {
      relocaliser_->cancel();  // back from the held pose: the search, if any, is over
    } else if (config_.relocalise) {
      // Not from the prediction, nor from the held pose: search the whole map.
      found = search(filtered, ideal_camera, &report);
      report.tracking_ms = millisecondsSince(start);
    }
    if (!given_T_W_C && !found && (!report.track.tracked() || !brief_loss)) {
      ++consecutive_failures_;
      motion_.clear();
      if (report.predicted_by_odometry) {
        // The other odometry carries the held pose on (dead reckoning) until the view fits again.
        T_W_C_ = predicted;
        T_odom_C_held_ = T_odom_C;
      }
      return report;  // never fuse on a failed frame
    }
    consecutive_failures_ = 0;
  }
  motion_.addTracked(timestamp_s, T_W_C_);
  tracked_interval_s_ = timestamp_s - held_pose_timestamp_s_;
  held_pose_timestamp_s_ = timestamp_s;
  T_odom_C_held_ = T_odom_C;
  if (config_.relocalise) places_->offer(filtered, T_W_C_);

  const Eigen::Isometry3d motion = T_W_C_last_fused_.inverse() * T_W_C_;
  const double change = std::hypot(motion.translation().norm(), rotationAngle(motion));
  if (report.initialised_map || change >= config_.min_pose_change_to_fuse) {
    const auto start = std::chrono::steady_clock::now();
    // Fusion must find every block of its view in memory: a swapped one would be made anew.
    restoreNear(T_W_C_, ideal_camera, furthest_m, &report);
    integrator_->integrate(filtered, ideal_camera, T_W_C_, map_.get());
    evictAwayFrom(T_W_C_, ideal_camera, furthest_m, &report);
    report.fusion_ms = millisecondsSince(start);
    report.fused = true;
    T_W_C_last_fused_ = T_W_C_;
    map_initialised_ = true;
  }
  return report;
}

}  // namespace sdf_tracker
