#include "sdf_tracker/pipeline/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <omp.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/map/overlaid_map.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/relocalisation/view_agreement.h"
#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

/// Failed frames after which a fit from the held pose is no longer taken without confirmation.
constexpr int kBriefLossFrames = 2;
/// No frame for this many of the camera's intervals between tracked frames (and longer than the
/// prediction bridges): frames went missing, and the camera may have been carried anywhere.
constexpr double kMissingFrameIntervals = 10.0;
/// No pose for more than this many of the camera's intervals between tracked frames: a frame (at
/// least) went missing, and the prediction spans more motion than one frame's.
constexpr double kOneFrameMissingIntervals = 1.5;
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

/// MaxMemoryMB in bytes.
size_t budgetBytes(const PipelineConfig& config) {
  return std::max<size_t>(1, static_cast<size_t>(config.max_map_memory_mb * 1048576.0));
}

/// Returns open(directory) for the swap file's directory; a file that cannot be opened there is
/// an invalid config (std::invalid_argument naming the parameters).
template <typename Open>
auto openSwapFile(const PipelineConfig& config, Open open) {
  const std::string directory =
      config.swap_directory.empty() ? std::filesystem::temp_directory_path().string() : config.swap_directory;
  try {
    return open(directory);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(std::string("MaxMemoryMB needs a swap file (SwapDirectory): ") + e.what());
  }
}

/// The budget of one sparse map (blocks swapped), or none.
std::unique_ptr<MapMemoryBudget> makeBudget(const PipelineConfig& config, MapType type) {
  if (config.max_map_memory_mb <= 0.0 || type != MapType::kSparse || config.submaps.enabled()) return nullptr;
  return openSwapFile(config, [&](const std::string& directory) {
    return std::make_unique<MapMemoryBudget>(budgetBytes(config), directory);
  });
}

/// The swap file of whole submaps, or none.
std::unique_ptr<BlockSwapFile> makeSubmapSwapFile(const PipelineConfig& config) {
  if (config.max_map_memory_mb <= 0.0 || !config.submaps.enabled()) return nullptr;
  return openSwapFile(config, [](const std::string& directory) { return std::make_unique<BlockSwapFile>(directory); });
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
  v.merge("submaps.", submaps.validate());
  v.merge("loops.", loops.validate());
  v.require(!loops.enabled || submaps.enabled(), "loop closure needs submaps (submaps.max_distance_m is 0)");
  if (submaps.enabled()) v.require(volume.type == MapType::kSparse, "submaps need the sparse map (volume.type is dense)");
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
  closed_submaps_.reset(makeSubmapSwapFile(config));
  integrator_ = std::make_unique<Integrator>(config.integrator);
  tracker_ = std::make_unique<Tracker>(config.tracker);
  places_ = std::make_unique<PlaceMemory>(config.places);
  relocaliser_ = std::make_unique<Relocaliser>(config.relocaliser, config.tracker);
  if (config.loops.enabled) {
    loop_detector_ = std::make_unique<LoopDetector>(config.loops, config.relocaliser, config.tracker, config.places);
    graph_solver_ = std::make_unique<BackgroundGraphSolver>();
  }
}

void SdfPipeline::clearSubmaps() {
  // First: a loop search may be reading a closed submap.
  if (loop_detector_) loop_detector_->reset();
  endHandover();
  dropRecentSubmaps();
  search_map_.reset();
  search_places_.reset();
  closed_submaps_.clear();
  told_of_submap_swap_ = submaps_over_budget_ = false;
  active_ = SubmapPlace();
  keyframe_submaps_.clear();
  if (graph_solver_) graph_solver_->cancel();
  graph_ = PoseGraph();
  loop_edges_.clear();
  solved_edges_ = 0;
  rejected_edges_.clear();
}

void SdfPipeline::clearMap() {
  clearSubmaps();
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

void SdfPipeline::setMap(std::unique_ptr<TsdfMap> map, std::unique_ptr<PlaceMemory> places, bool one_map_for_grid) {
  if (!map) throw std::invalid_argument("setMap: no map");
  if (map->observesNothing()) throw std::invalid_argument("the map holds no observed voxel: nothing to track against");
  const bool grid_in_submaps = config_.submaps.enabled() && map->type() != MapType::kSparse;
  if (grid_in_submaps && !one_map_for_grid) {
    std::ostringstream size;
    size << config_.submaps.max_distance_m;
    throw std::invalid_argument("submaps (SubmapSize=" + size.str() + " m) need a sparse map, and this one is a " +
                                map->config().describe() + ": load a .sdfmap, or start with SubmapSize=0 (one map)");
  }
  clearSubmaps();
  if (grid_in_submaps) {
    loop_detector_.reset();
    graph_solver_.reset();
    config_.submaps.max_distance_m = 0.0;
    config_.loops.enabled = false;
  }
  map_ = std::move(map);
  config_.volume = map_->config();
  budget_ = makeBudget(config_, map_->type());
  closed_submaps_.reset(makeSubmapSwapFile(config_));
  places_ = places ? std::move(places) : std::make_unique<PlaceMemory>(config_.places);
  keyframe_submaps_.assign(places_->keyframes().size(), 0);
  startInLoadedMap(Eigen::Isometry3d::Identity());
}

void SdfPipeline::setSubmaps(SubmapGraph saved, std::unique_ptr<PlaceMemory> places, bool one_map_for_grid) {
  const size_t keyframes = places ? places->keyframes().size() : 0;
  if (!places) saved.keyframe_submaps.clear();
  if (const std::string problem = saved.problem(keyframes); !problem.empty()) {
    throw std::invalid_argument("the saved submaps: " + problem);
  }
  if (!keepsSubmaps(config_, saved)) {
    std::unique_ptr<PlaceMemory> moved = places ? saved.placesInMapFrame(*places) : nullptr;
    return setMap(mergeSubmaps(std::move(saved.submaps)), std::move(moved), one_map_for_grid);
  }
  // The graph first: an edge it refuses changes nothing.
  PoseGraph graph;
  for (const Submap& submap : saved.submaps) graph.addNode(submap.place.T_map_anchor());
  for (const PoseEdge& edge : saved.edges) graph.addEdge(edge);
  if (saved.observesNothing()) throw std::invalid_argument("the saved submaps hold no observed voxel: nothing to track against");
  clearSubmaps();
  map_ = std::move(saved.submaps.back().map);
  active_ = saved.submaps.back().place;
  saved.submaps.pop_back();
  config_.volume = map_->config();
  budget_.reset();  // submaps swap whole (makeBudget)
  closed_submaps_.reset(makeSubmapSwapFile(config_));
  for (Submap& submap : saved.submaps) closed_submaps_.add(std::move(submap));
  graph_ = std::move(graph);
  // The saved session's last solution placed them; loops() and the counts are this session's.
  solved_edges_ = graph_.edges().size();
  places_ = places ? std::move(places) : std::make_unique<PlaceMemory>(config_.places);
  keyframe_submaps_ = std::move(saved.keyframe_submaps);
  // The search starts at the map's start pose: the identity in the map frame.
  startInLoadedMap(active_.T_map_W.inverse());
}

bool SdfPipeline::keepsSubmaps(const PipelineConfig& config, const SubmapGraph& saved) {
  return saved.submaps.size() > 1 && config.submaps.enabled() && config.relocalise;
}

SubmapGraph SdfPipeline::copySubmaps() const {
  SubmapGraph copy;
  if (closed_submaps_.empty()) {
    copy.submaps.push_back(Submap{copyWholeMap(), active_});
  } else {
    for (int node = 0; node < static_cast<int>(closed_submaps_.size()); ++node) {
      copy.submaps.push_back(Submap{closed_submaps_.map(node)->clone(), closed_submaps_.place(node)});
    }
    copy.submaps.push_back(Submap{map_->clone(), active_});
  }
  // The graph as its latest solution placed the submaps: without the loops it rejected, and
  // without those found since (they are sought again in the next session).
  for (size_t edge = 0; edge < graph_.edges().size(); ++edge) {
    const bool loop = std::find(loop_edges_.begin(), loop_edges_.end(), edge) != loop_edges_.end();
    if (loop && (edge >= solved_edges_ || rejectedByTheGraph(edge))) continue;
    copy.edges.push_back(graph_.edges()[edge]);
  }
  copy.keyframe_submaps = keyframe_submaps_;
  return copy;
}

void SdfPipeline::startInLoadedMap(const Eigen::Isometry3d& T_W_start) {
  T_W_C_ = T_W_C_last_fused_ = T_W_start;
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
    // A camera further from every mapped voxel than it sees cannot be in the map: its submaps,
    // each where the graph places it (the guess is in the map frame, where the search looks).
    Eigen::AlignedBox3d box = transformedBox(active_.T_map_W, Eigen::AlignedBox3d(mappedBox(*map_).cast<double>()));
    for (const SubmapPlace& place : closed_submaps_.places()) {
      box.extend(
          transformedBox(place.T_map_W, Eigen::AlignedBox3d(closed_submaps_.mappedBox(place.node).cast<double>())));
    }
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

TrackResult SdfPipeline::trackFrom(const Eigen::Isometry3d& guess, const MotionPrior& prior, const DepthImage& filtered,
                                   const PinholeCamera& camera, double timestamp_s) const {
  TrackResult track = tracker_->track(filtered, camera, trackingMap(), guess, prior);
  const double unseen_s = timestamp_s - held_pose_timestamp_s_;
  // A level ends early only once its step falls below the convergence threshold.
  const bool ran_out = track.final_step >= config_.tracker.convergence_threshold;
  if (!track.ok() || !ran_out || !(unseen_s > kOneFrameMissingIntervals * tracked_interval_s_)) return track;
  ViewAgreement agreement;
  if (relocaliser_->agrees(filtered, camera, trackingMap(), track.T_W_C, &agreement)) return track;
  std::ostringstream s;
  s << "ran out of iterations " << std::setprecision(3) << unseen_s
    << " s after the last tracked frame, and the view does not agree with the map there: "
    << std::lround(100.0 * agreement.mappedShare()) << " % on mapped surfaces (RelocaliseMinOverlap "
    << relocaliser_->config().min_overlap << "), " << std::fixed << std::setprecision(1)
    << 100.0 * agreement.contradictionShare() << " % against what the map saw (RelocaliseMaxContradiction "
    << std::defaultfloat << relocaliser_->config().max_contradiction << ")";
  track.status = TrackStatus::kNotConverged;
  track.T_W_C = guess;
  track.pose_estimated = false;
  track.covariance.setZero();
  track.message = s.str();
  return track;
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

void SdfPipeline::swapOutSubmaps(FrameReport* report) {
  if (!recent_merge_error_.empty()) report->swap_error = std::exchange(recent_merge_error_, std::string());
  if (!closed_submaps_.swaps()) return;
  const size_t budget = budgetBytes(config_);
  size_t bytes = mapMemoryBytes();
  if (bytes > budget) {
    // Farthest first: the centre of what each holds, where the graph places it, from the camera.
    const Eigen::Vector3d camera_map = mapPose().translation();
    const int searched = loop_detector_ ? loop_detector_->searchedSubmap() : -1;
    // The recent ones are held in their merge, once it landed (and read back to merge them again).
    const bool recent_merged = recent_submaps_ && !recent_merge_.valid();
    std::vector<std::pair<double, int>> candidates;
    for (int node = 0; node + 1 < static_cast<int>(closed_submaps_.size()); ++node) {
      if (closed_submaps_.swapped(node) || (isRecent(node) && !recent_merged) || node == searched) continue;
      const Eigen::Vector3d centre = closed_submaps_.mappedBox(node).center().cast<double>();
      candidates.emplace_back((closed_submaps_.place(node).T_map_W * centre - camera_map).norm(), node);
    }
    std::sort(candidates.begin(), candidates.end(), std::greater<>());
    const auto low_water = static_cast<size_t>(MapMemoryBudget::kLowWater * static_cast<double>(budget));
    for (const auto& [distance_m, node] : candidates) {
      if (bytes <= low_water) break;
      const size_t freed = closed_submaps_.inMemory(node)->memoryBytes();
      try {
        closed_submaps_.swapOut(node);
      } catch (const std::runtime_error& e) {
        report->swap_error = e.what();  // it stays in memory; the next frame tries again
        break;
      }
      bytes -= std::min(bytes, freed);
      ++report->submaps_swapped_out;
    }
#ifdef __GLIBC__
    // A submap's blocks are freed one by one, amid the heap: glibc keeps their pages unless asked.
    if (report->submaps_swapped_out > 0) malloc_trim(0);
#endif
  }
  if (report->submaps_swapped_out > 0 && !told_of_submap_swap_) {
    told_of_submap_swap_ = true;
    std::ostringstream notice;
    notice << "the map reached MaxMemoryMB=" << config_.max_map_memory_mb
           << ": closed submaps far from the camera go to a swap file in " << closed_submaps_.swapDirectory()
           << ", and are read back while a loop search, a save or a whole mesh needs them";
    report->swap_notice = notice.str();
  }
  const bool over = bytes > budget;
  if (over && !submaps_over_budget_) {
    std::ostringstream warning;
    warning << std::fixed << std::setprecision(2) << "the map holds " << bytes / 1048576.0
            << " MiB, above MaxMemoryMB=" << std::defaultfloat << config_.max_map_memory_mb
            << ": the active submap, the recent ones tracked with it (SubmapTrackRecent="
            << config_.submaps.track_recent_m
            << " m) merged and overlaid on it for tracking, and one searched for a loop stay in memory, and "
               "need more; raise MaxMemoryMB, or "
               "lower SubmapSize or SubmapTrackRecent";
    report->swap_warning = warning.str();
  }
  submaps_over_budget_ = over;
}

std::unique_ptr<TsdfMap> SdfPipeline::copyWholeMap() const {
  if (!closed_submaps_.empty()) {
    // Each where the graph places it (those in the swap file read back while the merge runs).
    std::vector<std::shared_ptr<const TsdfMap>> held;
    std::vector<PlacedMap> parts;
    for (int node = 0; node < static_cast<int>(closed_submaps_.size()); ++node) {
      held.push_back(closed_submaps_.map(node));
      parts.push_back(placedSubmap(*held.back(), closed_submaps_.place(node).T_map_W));
    }
    parts.push_back(placedSubmap(*map_, active_.T_map_W));
    return std::make_unique<SparseTsdfMap>(mergeMaps(parts));
  }
  if (!budget_ || budget_->swap().size() == 0) return map_->clone();
  return std::make_unique<SparseTsdfMap>(budget_->whole(static_cast<const SparseTsdfMap&>(*map_)));
}

bool SdfPipeline::search(const DepthImage& filtered, const PinholeCamera& camera, FrameReport* report) {
  const auto start = std::chrono::steady_clock::now();
  RelocalisationReport& r = report->relocalisation;
  r.searched = true;
  const std::string tracking_failure = report->track.message;
  if (!relocaliser_->searching()) {
    // A map of several submaps is searched whole: the camera may be in any of them.
    endHandover();
    search_map_ = closed_submaps_.empty() ? nullptr : copyWholeMap();
    search_places_ = closed_submaps_.empty() ? nullptr : placesInMapFrame();
    try {
      relocaliser_->begin(searchMap());
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
    search_guesses_.push_back(mapPose());  // in the merged submaps' frame, the map's
  }
  const Relocaliser::Step step = relocaliser_->step(filtered, camera, searchMap(),
                                                        search_places_ ? *search_places_ : *places_, search_guesses_);
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

size_t SdfPipeline::mapMemoryBytes() const {
  size_t bytes = map_->memoryBytes() + (search_map_ ? search_map_->memoryBytes() : 0) +
                 (recent_submaps_ ? recent_submaps_->memoryBytes() : 0) +
                 (tracked_map_ ? tracked_map_->memoryBytes() : 0);
  return bytes + closed_submaps_.memoryBytes();
}

void SdfPipeline::startSubmap(bool after_search) {
  if (graph_.poses().empty()) graph_.addNode(active_.T_map_anchor());  // the first submap's node
  closed_submaps_.add(Submap{std::move(map_), active_});
  const SubmapPlace& closed = closed_submaps_.newestPlace();
  map_ = makeMap(closed_submaps_.newest().config());
  active_ = SubmapPlace();
  active_.node = closed.node + 1;
  active_.T_W_anchor = T_W_C_;
  if (after_search) {
    // Found in the merged submaps: the pose is in the map frame, and the search's fit joins the
    // new submap to the one nearest it. No odometry ties it to the others (the way there was not
    // walked): the join counts as a long path, so that loops to them are sought at once and they
    // are not tracked with it as recent ones.
    const std::vector<SubmapPlace>& places = closed_submaps_.places();
    const auto nearest =
        std::min_element(places.begin(), places.end(), [&](const SubmapPlace& a, const SubmapPlace& b) {
          return (a.T_map_anchor().translation() - T_W_C_.translation()).norm() <
                 (b.T_map_anchor().translation() - T_W_C_.translation()).norm();
        });
    active_.path_m = closed.path_m + std::max(config_.loops.min_path_m, config_.submaps.track_recent_m);
    graph_.addNode(active_.T_map_anchor());
    // (The search's covariance is not kept: the loop's own sigma and the drift from that anchor.)
    graph_.addEdge(PoseEdge{nearest->node, active_.node, nearest->T_map_anchor().inverse() * T_W_C_,
                            loopEdgeInformation(config_.loops, nearest->T_map_anchor(), T_W_C_,
                                                Eigen::Matrix<double, 6, 6>::Zero(), T_W_C_),
                            PoseEdgeKind::kLoop});
  } else {
    // The tracker goes on in the same frame: the odometry between the two anchors.
    active_.path_m = closed.path_m + (closed.T_W_anchor.inverse() * T_W_C_).translation().norm();
    active_.T_map_W = closed.T_map_W;
    graph_.addNode(active_.T_map_anchor());
    const Eigen::Isometry3d motion = closed.T_W_anchor.inverse() * active_.T_W_anchor;
    graph_.addEdge(PoseEdge{closed.node, active_.node, motion, odometryEdgeInformation(config_.loops, motion),
                            PoseEdgeKind::kOdometry});
  }
  dropRecentSubmaps();
  if (!after_search && config_.submaps.track_recent_m > 0.0) {
    // Until the recent submaps' merge lands, frames are tracked against the one just closed (in
    // the same frame) overlaid by the new one.
    overlayRecent(static_cast<const SparseTsdfMap&>(closed_submaps_.newest()),
                  {{closed.node, Eigen::Isometry3d::Identity()}});
    mergeRecentSubmaps();
  } else {
    handover_fuses_previous_ = !after_search;
    handover_map_ = after_search ? search_map_.get() : &closed_submaps_.newest();
    handover_frames_left_ = handover_map_ ? config_.submaps.handover_frames : 0;
  }
  if (loop_detector_) {
    // After a search the camera's pose jumped into the map frame: a loop search under way would
    // follow its places by a motion the tracker never measured, and ends.
    if (after_search) loop_detector_->reset();
    loop_detector_->startedSubmap();
  }
}

void SdfPipeline::mergeRecentSubmaps() {
  waitForRecentMerge();  // (a merge still running would land after this one)
  RecentPlacements placements;
  const Eigen::Isometry3d T_active_map = active_.T_map_W.inverse();
  for (const SubmapPlace& place : closed_submaps_.places()) {
    if (isRecent(place.node)) placements.emplace_back(place.node, T_active_map * place.T_map_W);
  }
  if (placements.empty()) return;
  // Closed submaps are not written to while they are tracked with recent ones (no handover). Those
  // in the swap file (merged before, moved since by a graph solution) are read back here.
  recent_merge_ = std::async(std::launch::async, [closed = &closed_submaps_, placements = std::move(placements)]() {
    omp_set_num_threads(1);  // this thread's own setting: the tracking keeps the other cores
    RecentMerge merge;
    merge.placements = placements;
    try {
      std::vector<std::shared_ptr<const TsdfMap>> held;
      std::vector<PlacedMap> parts;
      for (const auto& [node, T_active_W] : placements) {
        held.push_back(closed->map(node));
        parts.push_back(placedSubmap(*held.back(), T_active_W));
      }
      merge.map = std::make_unique<SparseTsdfMap>(mergeMaps(parts));
    } catch (const std::runtime_error& e) {
      merge.error = e.what();  // the swap file failed
    }
    return merge;
  });
}

void SdfPipeline::landRecentMerge() {
  if (!recent_merge_.valid() || recent_merge_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  RecentMerge merged = recent_merge_.get();
  if (!merged.map) {
    // Tracked as before (the submap just closed overlaid), and said at the frame's end.
    recent_merge_error_ = "the recent submaps could not be merged for tracking: " + merged.error;
    return;
  }
  recent_submaps_ = std::move(merged.map);
  overlayRecent(*recent_submaps_, std::move(merged.placements));
}

void SdfPipeline::waitForRecentMerge() {
  if (recent_merge_.valid()) recent_merge_.wait();
  landRecentMerge();
}

void SdfPipeline::overlayRecent(const SparseTsdfMap& recent, RecentPlacements placements) {
  // Submaps are sparse maps (Config::validate).
  tracked_map_ = std::make_unique<OverlaidMap>(recent, static_cast<const SparseTsdfMap&>(*map_),
                                               static_cast<float>(config_.submaps.recent_settled_weight));
  recent_placements_ = std::move(placements);
}

void SdfPipeline::dropRecentSubmaps() {
  if (recent_merge_.valid()) recent_merge_.wait();
  recent_merge_ = std::future<RecentMerge>();
  tracked_map_.reset();
  recent_submaps_.reset();
  recent_placements_.clear();
}

bool SdfPipeline::isRecent(int node) const {
  // Where the camera left it: where the next one started.
  const double left_at_m =
      node + 1 < static_cast<int>(closed_submaps_.size()) ? closed_submaps_.place(node + 1).path_m : active_.path_m;
  return active_.path_m - left_at_m <= config_.submaps.track_recent_m;
}

bool SdfPipeline::recentSubmapsMoved() const {
  // A tenth of a voxel at the submap's reach (MaxDepth) is what a merge would change.
  const double voxel_m = config_.volume.voxel_size_m;
  const double reach_m = std::max(config_.max_depth_m, voxel_m);
  for (const auto& [node, placed] : recent_placements_) {
    const Eigen::Isometry3d now = active_.T_map_W.inverse() * submapPlace(node).T_map_W;
    const Eigen::Isometry3d moved = placed.inverse() * now;
    if (moved.translation().norm() + rotationAngle(moved) * reach_m > 0.1 * voxel_m) return true;
  }
  return false;
}

const SubmapPlace& SdfPipeline::submapPlace(int node) const {
  if (node == active_.node) return active_;
  if (node < 0 || node >= static_cast<int>(closed_submaps_.size())) {
    throw std::out_of_range("no submap " + std::to_string(node) + " (there are " + std::to_string(submapCount()) + ")");
  }
  return closed_submaps_.place(node);
}

std::vector<Eigen::Isometry3d> SdfPipeline::submapFrames() const {
  std::vector<Eigen::Isometry3d> frames;
  for (const SubmapPlace& place : closed_submaps_.places()) frames.push_back(place.T_map_W);
  frames.push_back(active_.T_map_W);
  return frames;
}

std::unique_ptr<PlaceMemory> SdfPipeline::placesInMapFrame() const {
  return sdf_tracker::placesInMapFrame(*places_, keyframe_submaps_, submapFrames());
}

void SdfPipeline::closeLoops(const DepthImage& filtered, const PinholeCamera& camera, FrameReport* report) {
  addLoop(loop_detector_->step(filtered, camera, T_W_C_, active_, closed_submaps_, *places_, keyframe_submaps_),
          &report->loop);
}

void SdfPipeline::addLoop(const LoopDetector::Step& step, LoopReport* report) {
  report->search_ms = step.search_ms;
  report->searched = step.searched;
  report->submap = step.submap;
  report->frame_submap = step.frame_submap;
  report->message = step.message;
  if (!step.match) return;
  // Where the anchor of the submap the frame was tracked in lies in the old one, by the camera
  // seen from both.
  const SubmapPlace& old = closed_submaps_.place(step.match->submap);
  const SubmapPlace& tracked_in = submapPlace(step.frame_submap);
  const Eigen::Isometry3d T_S_anchor = step.match->T_S_C * step.T_W_C.inverse() * tracked_in.T_W_anchor;
  const Eigen::Isometry3d T_old_anchor = old.T_W_anchor.inverse() * T_S_anchor;
  loop_edges_.push_back(graph_.edges().size());
  graph_.addEdge(PoseEdge{old.node, tracked_in.node, T_old_anchor,
                          loopEdgeInformation(config_.loops, old.T_W_anchor, step.match->T_S_C,
                                              step.match->covariance_S, T_S_anchor),
                          PoseEdgeKind::kLoop});
  if (tracked_in.node == active_.node) loop_detector_->joined(old.node);
  graph_solver_->solve(graph_);
  report->found = true;
}

void SdfPipeline::applyGraphSolution(const BackgroundGraphSolver::Result& result, LoopReport* report) {
  const PoseGraphSolution& solution = result.solution;
  const size_t solved_before = solved_edges_;
  solved_edges_ = result.graph.edges().size();
  rejected_edges_ = solution.rejected_loops;
  for (size_t edge : loop_edges_) {
    if (edge >= solved_before && edge < solved_edges_) (rejectedByTheGraph(edge) ? report->rejected : report->closed) += 1;
  }
  report->solved = true;
  report->optimise_ms = result.solve_ms;

  const Eigen::Isometry3d active_before = active_.T_map_anchor();
  // Node 0 is held where it is: its frame stays the map's. The submaps started after the graph
  // was handed over move as the newest it holds moved.
  const int solved_nodes = static_cast<int>(solution.poses.size());
  Eigen::Isometry3d newest_moved = Eigen::Isometry3d::Identity();
  for (int node = 1; node < solved_nodes; ++node) {
    SubmapPlace& place = placeOf(node);
    const Eigen::Isometry3d before = place.T_map_W;
    place.T_map_W = solution.poses[node] * place.T_W_anchor.inverse();
    if (node == solved_nodes - 1) newest_moved = place.T_map_W * before.inverse();
  }
  for (int node = std::max(solved_nodes, 1); node < static_cast<int>(submapCount()); ++node) {
    SubmapPlace& place = placeOf(node);
    place.T_map_W = newest_moved * place.T_map_W;
  }
  // The next solve starts from here.
  for (int node = 0; node < static_cast<int>(graph_.poses().size()); ++node) {
    graph_.setPose(node, placeOf(node).T_map_anchor());
  }
  const Eigen::Isometry3d moved = active_before.inverse() * active_.T_map_anchor();
  report->correction_m = moved.translation().norm();
  report->correction_deg = rotationAngle(moved) * 180.0 / M_PI;
  // The recent submaps tracked with the active one lie where the solution now puts them against
  // it: merged again, when that moved them (in the background; tracked as they were until then).
  if (tracked_map_ && recentSubmapsMoved()) {
    mergeRecentSubmaps();
  }
}

bool SdfPipeline::rejectedByTheGraph(size_t edge) const {
  return std::find(rejected_edges_.begin(), rejected_edges_.end(), static_cast<int>(edge)) != rejected_edges_.end();
}

std::vector<SdfPipeline::Loop> SdfPipeline::loops() const {
  std::vector<Loop> loops;
  for (size_t edge : loop_edges_) loops.push_back({graph_.edges()[edge], edge < solved_edges_ && !rejectedByTheGraph(edge)});
  return loops;
}

int SdfPipeline::loopsClosed() const {
  const std::vector<Loop> all = loops();
  return static_cast<int>(std::count_if(all.begin(), all.end(), [](const Loop& loop) { return loop.kept; }));
}

int SdfPipeline::loopsRejected() const {
  return static_cast<int>(std::count_if(loop_edges_.begin(), loop_edges_.end(), [this](size_t edge) {
    return edge < solved_edges_ && rejectedByTheGraph(edge);
  }));
}

LoopReport SdfPipeline::finishLoopClosure() {
  LoopReport report;
  if (!graph_solver_) return report;
  // A search step still running may find a loop: it goes into the graph first.
  addLoop(loop_detector_->finish(), &report);
  if (std::optional<BackgroundGraphSolver::Result> result = graph_solver_->finish()) {
    applyGraphSolution(*result, &report);
  }
  return report;
}

void SdfPipeline::endHandover() {
  handover_map_ = nullptr;
  handover_frames_left_ = 0;
  handover_fuses_previous_ = false;
  dropSearchMap();
}

void SdfPipeline::dropSearchMap() {
  if (search_map_ && handover_map_ != search_map_.get() && !relocaliser_->searching()) search_map_.reset();
}

FrameReport SdfPipeline::processFrame(const DepthImage& depth, const PinholeCamera& camera, double timestamp_s,
                                      const std::optional<Eigen::Isometry3d>& T_odom_C, FrameColour colour) {
  return process(depth, camera, timestamp_s, std::nullopt, T_odom_C, &colour);
}

FrameReport SdfPipeline::processFrameAtPose(const DepthImage& depth, const PinholeCamera& camera,
                                            const Eigen::Isometry3d& T_W_C, double timestamp_s,
                                            FrameColour colour) {
  return process(depth, camera, timestamp_s, T_W_C, std::nullopt, &colour);
}

const ColourImage* FrameColour::get() {
  if (image_ || !later_) return image_;
  fetched_ = later_();
  later_ = nullptr;
  image_ = fetched_ ? &*fetched_ : nullptr;
  return image_;
}

const ColourImage* SdfPipeline::prepareColour(FrameColour* frame_colour, const DepthImage& depth,
                                              const PinholeCamera& camera, FrameReport* report) {
  if (!config_.fuse_colour) return nullptr;
  const ColourImage* colour = frame_colour->get();
  if (!colour) return nullptr;
  if (std::string mismatch = colour->sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
    report->colour_problem = std::move(mismatch);
    return nullptr;
  }
  if (camera.distortion.isZero()) return colour;
  undistortion_->apply(*colour, &colour_buffer_);  // prepareDepth() made the pixel map of this camera
  return &colour_buffer_;
}

FrameReport SdfPipeline::process(const DepthImage& depth, const PinholeCamera& camera, double timestamp_s,
                                 const std::optional<Eigen::Isometry3d>& given_T_W_C,
                                 const std::optional<Eigen::Isometry3d>& T_odom_C, FrameColour* colour) {
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

  landRecentMerge();  // a merge of the recent submaps that finished is tracked against from now
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
    active_.T_W_anchor = T_W_C_;
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
    if (given_T_W_C && pose_unknown_ && !closed_submaps_.empty()) {
      // A given pose in saved submaps (the tracker alone, measured in a loaded map): in the map
      // frame, as a search's would be; the frame starts a submap there, joined to the nearest
      // saved one, and is tracked against them all.
      T_W_C_ = *given_T_W_C;
      pose_unknown_ = false;
      search_map_ = copyWholeMap();
      startSubmap(true);
      report.started_submap = true;
    }
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
    // The overlay takes in what changed in the active submap since the last frame (its fusion).
    if (tracked_map_) tracked_map_->update();
    MotionPrior prior;
    if (report.predicted_by_odometry) {
      prior.odometry = odometryPrior(predicted, T_odom_C_held_->inverse() * *T_odom_C, config_.odometry_error);
    } else if (!given_T_W_C) {
      prior.T_W_C_unconstrained = T_W_C_ * expSe3(kUnobservedMotionKept * logSe3(T_W_C_.inverse() * predicted));
    }
    report.tracked_in_previous_submap = handover_map_ != nullptr;
    report.track = trackFrom(predicted, prior, filtered, ideal_camera, timestamp_s);
    if (!given_T_W_C && !report.track.tracked() && !predicted.isApprox(T_W_C_)) {
      // The prediction may have led astray (the camera stopped or turned): try from the last pose.
      TrackResult from_last = trackFrom(T_W_C_, prior, filtered, ideal_camera, timestamp_s);
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
      dropSearchMap();
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

  if (config_.submaps.enabled() && !report.initialised_map && !report.started_submap) {
    // Found by a search in the merged submaps: the camera may be anywhere in them, and the
    // active submap need not hold its view.
    const bool found_in_merged = report.relocalisation.outcome == Relocaliser::Outcome::kAccepted && search_map_;
    if (found_in_merged ||
        (handover_frames_left_ == 0 && leavesSubmap(config_.submaps, active_.T_W_anchor, T_W_C_))) {
      startSubmap(found_in_merged);
      report.started_submap = true;
    }
  }
  report.submap = active_.node;
  // The place memory serves the search after a loss and the loop detector.
  if ((config_.relocalise || loop_detector_) && places_->offer(filtered, T_W_C_)) {
    keyframe_submaps_.push_back(active_.node);
  }
  if (graph_solver_) {
    if (std::optional<BackgroundGraphSolver::Result> solved = graph_solver_->poll()) {
      applyGraphSolution(*solved, &report.loop);
    }
  }
  if (loop_detector_ && !given_T_W_C && !report.initialised_map && !report.started_submap &&
      handover_frames_left_ == 0 && report.relocalisation.outcome != Relocaliser::Outcome::kAccepted) {
    closeLoops(filtered, ideal_camera, &report);
  }

  const Eigen::Isometry3d motion = T_W_C_last_fused_.inverse() * T_W_C_;
  const double change = std::hypot(motion.translation().norm(), rotationAngle(motion));
  if (report.initialised_map || report.started_submap || change >= config_.min_pose_change_to_fuse) {
    const auto start = std::chrono::steady_clock::now();
    // Fusion must find every block of its view in memory: a swapped one would be made anew.
    restoreNear(T_W_C_, ideal_camera, furthest_m, &report);
    // Asked only now: a colour image that came while the frame was tracked is still used.
    const ColourImage* colour_in = prepareColour(colour, depth, camera, &report);
    integrator_->integrate(filtered, ideal_camera, T_W_C_, map_.get(), colour_in);
    report.coloured = colour_in != nullptr;
    ++active_.frames_fused;
    if (handover_frames_left_ > 0) {
      if (handover_fuses_previous_) {
        integrator_->integrate(filtered, ideal_camera, T_W_C_, &closed_submaps_.newest(), colour_in);
        ++closed_submaps_.newestPlace().frames_fused;
      }
      if (--handover_frames_left_ == 0) endHandover();
    }
    evictAwayFrom(T_W_C_, ideal_camera, furthest_m, &report);
    swapOutSubmaps(&report);
    report.fusion_ms = millisecondsSince(start);
    report.fused = true;
    T_W_C_last_fused_ = T_W_C_;
    map_initialised_ = true;
  }
  return report;
}

}  // namespace sdf_tracker
