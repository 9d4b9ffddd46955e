#pragma once

#include <functional>
#include <future>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/camera/depth_undistortion.h"
#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/map/block_swap.h"
#include "sdf_tracker/graph/background_solver.h"
#include "sdf_tracker/graph/pose_graph.h"
#include "sdf_tracker/map/overlaid_map.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/pipeline/loop_closure.h"
#include "sdf_tracker/pipeline/submap_store.h"
#include "sdf_tracker/pipeline/submaps.h"
#include "sdf_tracker/places/place_memory.h"
#include "sdf_tracker/relocalisation/relocaliser.h"
#include "sdf_tracker/surface/raycaster.h"
#include "sdf_tracker/tracking/motion_model.h"
#include "sdf_tracker/tracking/tracker.h"

namespace sdf_tracker {

/// Everything the tracking-and-mapping loop needs, one aggregate per component.
struct PipelineConfig {
  VolumeConfig volume;
  IntegratorConfig integrator;
  TrackerConfig tracker;
  RaycastConfig raycast;
  /// Depths outside [min_depth_m, max_depth_m] are treated as no measurement (the reference
  /// release rejects depth under 0.4 m).
  double min_depth_m = 0.4;
  double max_depth_m = 8.0;
  /// Where the first camera sits in the grid, as a fraction of the grid's extent along each axis
  /// (world axes = the first camera's axes). (0.5, 0.5, 0) puts it at the centre of the grid's
  /// near face, looking in along +z. The grid's origin follows from this: volume.origin_W is
  /// not read.
  Eigen::Vector3d initial_camera_in_grid = Eigen::Vector3d(0.5, 0.5, 0.0);
  /// Fuse a tracked frame only when the camera moved at least this much (|xi| of the motion
  /// since the last fused frame, metres and radians); 0 fuses every frame.
  double min_pose_change_to_fuse = 0.0;
  /// After this many consecutive tracking failures the map is cleared and rebuilt from the next
  /// frame at the held pose; 0 never resets.
  int reset_after_failures = 0;
  /// Start tracking from a constant-velocity prediction (the last motion, scaled to the time
  /// since the last tracked frame, so dropped frames are bridged). When tracking from the
  /// prediction fails, the frame is tracked again from the last pose. Off: from the last pose.
  bool predict_motion = false;
  /// No prediction across a gap longer than this [s]: the last motion says little by then. With
  /// relocalise on, a frame taken longer than this, and than ten of the camera's frame intervals,
  /// after the last tracked one (the view blocked while the camera was carried, a recording cut)
  /// is treated as after a long loss: the camera may be anywhere, and a fit from the held pose
  /// must be confirmed like any candidate, unless another odometry measured the motion.
  double max_prediction_gap_s = 0.5;
  /// How far another odometry (processFrame's T_odom_C) is trusted: the standard deviation of the
  /// motion it measures between two frames, as a fraction of the distance and of the angle
  /// travelled (wheels: a few per cent), no less than kMinOdometrySigma_m / _rad per frame.
  double odometry_error = 0.05;
  /// Sparse map only: above this many MiB, the map's memory is bounded by a swap file on disk; 0
  /// never. One map: blocks away from the camera go to it (MapMemoryBudget), and come back when
  /// seen again. Submaps: whole closed submaps far from the camera go to it (never the active one,
  /// the newest closed one, or one a loop search reads; the recent ones once their merge for
  /// tracking holds them), and are read back while a loop search, a merge, a save or a whole mesh
  /// needs them.
  double max_map_memory_mb = 0.0;
  /// Where the swap file is made; empty: the system's temporary directory.
  std::string swap_directory;
  /// Find the camera in the whole map when tracking from the held pose fails (and at the first
  /// frames in a loaded map): candidates from the place memory, verified and confirmed by the
  /// relocaliser before anything is fused; the place memory is built as the map grows. Off: only
  /// the held pose is tried (the paper), and no place memory is built.
  bool relocalise = false;
  PlaceMemoryConfig places;
  RelocaliserConfig relocaliser;
  /// The map as a sequence of submaps along the path (sparse map only); off by
  /// default: one map.
  SubmapConfig submaps;
  /// Loops between submaps, and the pose graph that places them (needs submaps); off by default.
  LoopClosureConfig loops;
  /// Fuse the colour images processFrame is given (registered to the depth) into the map; off,
  /// they are ignored and the map holds no colour.
  bool fuse_colour = true;

  std::vector<std::string> validate() const;
};

/// Another odometry's standard deviation per frame is no less than this: one that says the robot
/// stood still is not believed beyond it, so that the map can still correct the pose.
constexpr double kMinOdometrySigma_m = 5e-4;
constexpr double kMinOdometrySigma_rad = 5e-4;
/// Its heading errs by about a degree per metre driven (wheels of unequal size, slip).
constexpr double kOdometryHeadingDrift_rad_per_m = 0.02;

/// The prior another odometry gives a frame (MotionPrior::Odometry): the pose it predicts, with a
/// standard deviation of `odometry_error` of the distance and angle of the `motion` it measured
/// since the held frame (plus the heading drift over that distance), at least the floors above.
MotionPrior::Odometry odometryPrior(const Eigen::Isometry3d& T_W_C_predicted, const Eigen::Isometry3d& motion,
                                    double odometry_error);

/// A frame's colour image, registered to its depth, or where to get it: `later` is asked once,
/// when the frame is fused, after it is tracked, so that a colour image that arrives while the
/// frame is tracked still colours it (a camera's colour images come a few milliseconds before or
/// after the depth they go with). None: default-constructed, a null image, or `later` returning
/// nothing.
class FrameColour {
 public:
  FrameColour() = default;
  FrameColour(const ColourImage* image) : image_(image) {}  // NOLINT(runtime/explicit): the common case
  explicit FrameColour(std::function<std::optional<ColourImage>()> later) : later_(std::move(later)) {}
  /// The image given, or the one `later` returns now (asked once, then kept); nullptr: none.
  const ColourImage* get();

 private:
  const ColourImage* image_ = nullptr;
  std::function<std::optional<ColourImage>()> later_;
  std::optional<ColourImage> fetched_;
};

/// A frame that went to the relocaliser (FrameReport::relocalisation).
struct RelocalisationReport {
  bool searched = false;  ///< the frame was searched with (the camera's pose was not known)
  Relocaliser::Outcome outcome = Relocaliser::Outcome::kNotFound;
  int candidates_tried = 0;  ///< on this frame
  int frames_spent = 0;      ///< by the search so far, this frame included
  int confirmed = 0;         ///< frames the kept candidate has tracked in a row
  int places_fitting = 0;    ///< distinct places that fit this frame (outcome kAmbiguous: two or more)
  double search_ms = 0.0;
  std::string message;  ///< why nothing was kept, or why no search could run
};

/// A frame's loop closure (FrameReport::loop): the search for a loop, and a pose graph solution
/// that landed (solved off the tracking thread, see SdfPipeline).
struct LoopReport {
  /// A loop search step finished by this frame (it ran in the background, on an earlier frame).
  bool searched = false;
  int submap = -1;        ///< in which older submap
  int frame_submap = -1;  ///< the submap the searched frame was tracked in
  /// The camera was found there: a loop edge joins the two, and the graph is being solved in the
  /// background.
  bool found = false;
  /// A solution landed on this frame: how many loops found since the last one it kept, and how
  /// many it found wrong and left out.
  bool solved = false;
  int closed = 0;
  int rejected = 0;
  /// How far that solution moved the active submap in the map frame [m, degrees].
  double correction_m = 0.0;
  double correction_deg = 0.0;
  double search_ms = 0.0;     ///< the finished search step's time (on its own thread)
  double optimise_ms = 0.0;  ///< the landed solve's time (on its own thread)
  std::string message;       ///< why a search ended without a loop
};

/// What happened to one frame.
struct FrameReport {
  TrackResult track;
  bool initialised_map = false;  ///< the frame started (or restarted) the map
  bool fused = false;
  bool reset = false;  ///< the map was cleared before this frame after repeated failures
  /// The pose was predicted from the other odometry's motion (processFrame's T_odom_C).
  bool predicted_by_odometry = false;
  double tracking_ms = 0.0;
  double fusion_ms = 0.0;
  /// Blocks read back from the swap file before tracking, and written to it after fusion
  /// (MaxMemoryMB, one map).
  size_t blocks_swapped_in = 0;
  size_t blocks_swapped_out = 0;
  /// Closed submaps written to the swap file as this frame started a submap (MaxMemoryMB).
  int submaps_swapped_out = 0;
  /// Set on the frame at which swapping starts: what to tell the user, once.
  std::string swap_notice;
  /// Set on the frame at which the map stays above MaxMemoryMB after swapping, once until it is
  /// back within: why, and what to change.
  std::string swap_warning;
  /// The swap file failed (e.g. the disk is full): what and where. Blocks that could not be
  /// written stay in memory; blocks that could not be read back stay in the file.
  std::string swap_error;
  RelocalisationReport relocalisation;
  /// The frame started a new submap (it is fused into it, and during a handover into the one
  /// before too).
  bool started_submap = false;
  /// The frame was tracked against the submap before the active one (its first frames, see
  /// SubmapConfig::handover_frames), or against the whole map it was just found in.
  bool tracked_in_previous_submap = false;
  /// The submap whose frame the pose is in (SubmapPlace::node; 0 without submaps).
  int submap = 0;
  /// The frame was fused with its colour image.
  bool coloured = false;
  /// Why the colour image given with the frame was not used (its size); the frame was tracked
  /// and fused all the same.
  std::string colour_problem;
  LoopReport loop;
};

/// The on-line loop: track each frame against the map, then fuse it at the tracked pose. Owns the
/// volume and the current pose; no I/O, no ROS. Not thread safe: one caller at a time.
class SdfPipeline {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit SdfPipeline(const PipelineConfig& config);

  const PipelineConfig& config() const { return config_; }

  /// Tracks and fuses one depth image (metres) taken at `timestamp_s` (any clock; frames must come
  /// in time order; NaN: evenly spaced frames). Bad input yields a report with kBadInput; the map
  /// and pose are then untouched. The camera must match the image size; its lens distortion, if
  /// any, is removed from the image first. `T_odom_C`, when another odometry runs beside the
  /// tracker (a robot's wheels): the camera's pose in that odometry's frame at this image. The
  /// motion it measured since the frame whose pose the pipeline holds then predicts the pose
  /// (instead of constant velocity), and stays the estimate along the directions the view does not
  /// constrain; on a frame that fails, the held pose moves on by that motion (dead reckoning), so
  /// that pose() follows the robot until the view fits again.
  /// `colour`, when given and fuse_colour is on: the colour image registered to the depth (pixel
  /// for pixel, the same size and lens), fused into the map with the frame; it changes nothing
  /// else (the pose is the same with it and without it).
  FrameReport processFrame(const DepthImage& depth, const PinholeCamera& camera,
                           double timestamp_s = std::numeric_limits<double>::quiet_NaN(),
                           const std::optional<Eigen::Isometry3d>& T_odom_C = std::nullopt,
                           FrameColour colour = FrameColour());

  /// Measures the tracker alone: tracks the frame from the given pose T_W_C (e.g. the true one),
  /// reports where the tracker took it, and then fuses the frame at the given pose, whatever the
  /// tracker did. Fed the true poses, the report's error is the tracker's own against a map fused
  /// at true poses, free of the drift that fusion at estimated poses adds. The first frame's
  /// given pose places the map (sdf_tracker_offline --fuse-ground-truth).
  FrameReport processFrameAtPose(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                                 double timestamp_s = std::numeric_limits<double>::quiet_NaN(),
                                 FrameColour colour = FrameColour());

  /// Camera to world at the last accepted frame.
  const Eigen::Isometry3d& pose() const { return T_W_C_; }
  /// The map in memory (a TsdfVolume or a SparseTsdfMap, per config().volume.type): with a
  /// memory budget, without the blocks swapped to disk; with submaps, the active one (see
  /// withWholeMap()).
  const TsdfMap& map() const { return *map_; }
  /// A copy of the whole map, swapped blocks included, submaps merged into one: what a whole mesh
  /// or a .vti must read (a .sdfmap keeps the submaps: copySubmaps()).
  std::unique_ptr<TsdfMap> copyWholeMap() const;
  /// Calls fn(const TsdfMap&) with the whole map: the map itself when nothing is swapped out and
  /// it is one submap, else a copy with the swapped blocks read back or the submaps merged (memory
  /// beyond the budget while it runs).
  template <typename Fn>
  void withWholeMap(Fn&& fn) const {
    if ((!budget_ || budget_->swap().size() == 0) && closed_submaps_.empty()) return fn(*map_);
    fn(*copyWholeMap());
  }
  /// The submaps before the active one, oldest first (none without submaps), with a memory budget
  /// some in the swap file.
  const SubmapStore& closedSubmaps() const { return closed_submaps_; }
  /// The submaps, the active one included (1 without submaps).
  size_t submapCount() const { return closed_submaps_.size() + 1; }
  /// Bytes the map's voxels hold in memory, every submap's (and a search's copy of them all, and
  /// the recent submaps merged for tracking).
  size_t mapMemoryBytes() const;
  /// Where the camera was when the active submap started.
  const Eigen::Isometry3d& activeSubmapAnchor() const { return active_.T_W_anchor; }
  /// Where submap `node` lies (closed or active); throws std::out_of_range for no such submap.
  const SubmapPlace& submapPlace(int node) const;
  /// pose() in the map frame: where the pose graph puts the camera (pose() itself without loops).
  Eigen::Isometry3d mapPose() const { return active_.T_map_W * T_W_C_; }
  /// The submaps' pose graph (nodes added as submaps start; empty without submaps).
  const PoseGraph& poseGraph() const { return graph_; }
  /// A loop edge the loop detector added to poseGraph(), and whether the latest solution kept it
  /// (false also while it waits for its first solve).
  struct Loop {
    PoseEdge edge;
    bool kept = false;
  };
  std::vector<Loop> loops() const;
  /// Loops the latest solution kept, and those it found wrong (each solve weighs every loop
  /// again).
  int loopsClosed() const;
  int loopsRejected() const;
  /// Waits for a loop search step still running (a loop it found goes into the graph) and for
  /// the pose graph's solve, if one runs or waits, and applies it: what a run's final trajectory
  /// and map must see. The report says what it found, kept and moved (solved = false: nothing was
  /// pending).
  LoopReport finishLoopClosure();
  /// The memory budget (MaxMemoryMB), or nullptr when there is none.
  const MapMemoryBudget* memoryBudget() const { return budget_.get(); }
  /// Frames in a row that could not be tracked (0 while tracking works).
  int consecutiveFailures() const { return consecutive_failures_; }

  /// Clears the map and the place memory and puts the camera back at the start pose.
  void reset();
  /// Replaces the map (e.g. a loaded .vti) with one of any type, and the place memory with
  /// `places` (none: an empty one). With relocalise on, the camera's place in it is then searched
  /// for, from the start pose first (see relocalise()); off, the next frame is tracked from the
  /// start pose. A dense grid cannot hold submaps: with submaps on it is refused, unless
  /// `one_map_for_grid` (the user left submaps to the preset), which makes the pipeline one map
  /// without loop closure from now on. Throws before changing anything.
  void setMap(std::unique_ptr<TsdfMap> map, std::unique_ptr<PlaceMemory> places = nullptr,
              bool one_map_for_grid = false);
  /// Takes up a saved session (a .sdfmap's submaps, their graph and place memory, each keyframe
  /// in its submap's frame): with submaps on and relocalise on, every submap where the graph
  /// placed it, the last one active, the graph as it was; the camera is searched for in all of
  /// them merged, and the submap started where it is found is joined to the nearest saved one by
  /// an edge: the session adds to the saved graph. Otherwise (one saved submap, submaps off, or
  /// no search to find the camera in several) the submaps merged into one map, as setMap() takes
  /// it. Throws std::invalid_argument (changing nothing) for submaps that cannot be a map's
  /// (SubmapGraph::problem) or an edge the graph refuses.
  void setSubmaps(SubmapGraph saved, std::unique_ptr<PlaceMemory> places = nullptr, bool one_map_for_grid = false);
  /// Whether setSubmaps() keeps `saved` as submaps (else it merges them into one map).
  static bool keepsSubmaps(const PipelineConfig& config, const SubmapGraph& saved);
  /// A copy of the submaps, their places and graph, and each keyframe's submap (without submaps:
  /// the whole map, swapped blocks included, as one): what a .sdfmap keeps, with places().
  SubmapGraph copySubmaps() const;

  /// Forgets where the camera is: the next frames search the map for it (needs relocalise on),
  /// trying `guess` first when given (a pose the user knows), and fuse nothing until a candidate
  /// is confirmed. A guess is verified like any candidate. Throws std::logic_error with
  /// relocalise off or before the map holds anything, and std::invalid_argument (changing
  /// nothing) for a guess further than max_depth_m from every voxel of the map.
  void relocalise(const std::optional<Eigen::Isometry3d>& guess = std::nullopt);
  /// The camera's pose is being searched for (after a loss with relocalise on, in a loaded map,
  /// after relocalise()).
  bool relocalising() const { return pose_unknown_ || relocaliser_->searching(); }
  /// pose() is where the camera is, or was last seen (held during a loss); false while the
  /// camera is searched for in a loaded map or after relocalise(), when pose() is only the start
  /// pose.
  bool poseKnown() const { return !pose_unknown_; }
  /// The keyframes the map was built from, each in its submap's frame (see placesInMapFrame()).
  const PlaceMemory& places() const { return *places_; }
  /// The keyframes where the pose graph now places their submaps, in the map frame: what a search
  /// in the merged submaps reads, and what a saved map (with copyWholeMap()) must hold.
  std::unique_ptr<PlaceMemory> placesInMapFrame() const;

  /// Live-changeable settings (dynamic reconfigure): everything but the grid geometry. Throws
  /// std::invalid_argument (leaving the pipeline unchanged) when the candidate is invalid or
  /// changes the grid.
  void updateConfig(const PipelineConfig& candidate);

  /// The start pose: identity, with the volume placed around it per initial_camera_in_grid.
  static Eigen::Vector3d volumeOriginFor(const PipelineConfig& config);

 private:
  /// processFrame, or with given_T_W_C processFrameAtPose.
  FrameReport process(const DepthImage& depth, const PinholeCamera& camera, double timestamp_s,
                      const std::optional<Eigen::Isometry3d>& given_T_W_C,
                      const std::optional<Eigen::Isometry3d>& T_odom_C, FrameColour* colour);
  /// The frame's colour image as the integrator takes it (undistorted as the depth, in
  /// colour_buffer_), or nullptr when colour is off (`colour` is then not asked), there is none,
  /// or it does not fit the depth (said in the report).
  const ColourImage* prepareColour(FrameColour* colour, const DepthImage& depth, const PinholeCamera& camera,
                                   FrameReport* report);
  /// The image as the tracker and integrator take it: undistorted, depths out of range removed.
  DepthImage prepareDepth(const DepthImage& depth, const PinholeCamera& camera);
  /// Where the camera should be at `timestamp_s` if it kept its last motion; the last pose when
  /// prediction is off or there is no motion to go by.
  Eigen::Isometry3d predictPose(double timestamp_s) const;
  /// Tracks the frame from `guess` against trackingMap(). After frames went missing (no pose for
  /// longer than the camera's interval allows) the guess may be far off, and Gauss-Newton can
  /// settle in a wrong place that fits much of the view: a fit there that ran out of iterations at
  /// the finest level must agree with the map as a relocalisation candidate must, or the frame
  /// fails (kNotConverged) and nothing wrong is fused.
  TrackResult trackFrom(const Eigen::Isometry3d& guess, const MotionPrior& prior, const DepthImage& filtered,
                        const PinholeCamera& camera, double timestamp_s) const;
  /// With a memory budget: reads back the swapped blocks near the view from T_W_C up to
  /// furthest_m (what tracking or fusion there may touch), counted in the report.
  void restoreNear(const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera, float furthest_m, FrameReport* report);
  /// With submaps and a memory budget, while the map is over the budget: swaps out closed
  /// submaps, farthest from the camera first, but not the newest, nor one searched for a loop,
  /// nor the recent ones until their merge for tracking has landed (which holds them then).
  void swapOutSubmaps(FrameReport* report);
  /// With a memory budget and the map over it: swaps out blocks away from that view.
  void evictAwayFrom(const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera, float furthest_m,
                     FrameReport* report);
  /// Empties the map and its swap file; the next frame starts a new map. The pose is left to the
  /// caller.
  void clearMap();
  /// The relocaliser's step on a frame whose pose is not known; fills report->relocalisation and,
  /// once a candidate is accepted, report->track and the pose. Returns whether it was accepted.
  bool search(const DepthImage& filtered, const PinholeCamera& camera, FrameReport* report);
  /// What frames are tracked against: the active submap (with the recent ones overlaid), or during
  /// a handover the map before it.
  const TsdfMap& trackingMap() const {
    return handover_map_ ? *handover_map_ : tracked_map_ ? *tracked_map_ : *map_;
  }
  /// What a search looks in: the whole map (submaps merged while it runs), or the active one.
  const TsdfMap& searchMap() const { return search_map_ ? *search_map_ : *map_; }
  /// Closes the active submap (when it holds anything) and starts a new one at T_W_C_, tracked
  /// against with the recent submaps overlaid (SubmapConfig::track_recent_m) or, without them, its
  /// first frames tracked against the closed one and fused into both; `after_search`, its first
  /// frames tracked against the whole map the camera was found in.
  void startSubmap(bool after_search);
  /// The recent submaps' nodes and where they were placed in the active one's frame.
  using RecentPlacements = std::vector<std::pair<int, Eigen::Isometry3d>>;
  /// With SubmapConfig::track_recent_m: merges the submaps the camera left within that path (the
  /// one before always) in the active one's frame, on a thread of its own; once it lands
  /// (landRecentMerge), they are overlaid on the active one for tracking.
  void mergeRecentSubmaps();
  /// Overlays the merge that finished, if one did; never waits.
  void landRecentMerge();
  /// Waits for a merge still running and overlays it.
  void waitForRecentMerge();
  /// Frames are tracked against `recent` (placed as `placements` say) overlaid by the active one.
  void overlayRecent(const SparseTsdfMap& recent, RecentPlacements placements);
  /// Frees them (waiting for a merge still running): frames are tracked against the active submap
  /// alone (or a handover's map).
  void dropRecentSubmaps();
  /// Whether closed submap `node` is one of the recent ones (SubmapConfig::track_recent_m): the
  /// camera left it within that much path before the active one started.
  bool isRecent(int node) const;
  /// Whether a graph solution moved any merged recent submap against the active one by more than a
  /// tenth of a voxel (within the camera's reach): then they are merged again.
  bool recentSubmapsMoved() const;
  /// Ends a handover (or none): frames are tracked against the active submap alone.
  void endHandover();
  /// Frees a search's copy of the whole map unless a handover still tracks against it.
  void dropSearchMap();
  /// Back to one empty submap (and no graph), for a cleared or replaced map.
  void clearSubmaps();
  /// After a map was loaded: the pose, its history and the search as at the start in it (the
  /// camera at `T_W_start`; searched for with relocalise on).
  void startInLoadedMap(const Eigen::Isometry3d& T_W_start);
  /// T_map_W of every submap, by node.
  std::vector<Eigen::Isometry3d> submapFrames() const;
  /// The loop detector's step on a tracked frame (a search in the background; what finished
  /// since the last frame is reported); a loop found goes into the graph (addLoop).
  void closeLoops(const DepthImage& filtered, const PinholeCamera& camera, FrameReport* report);
  /// A finished loop search step, said in `report`; a loop it found joins the submap its frame was
  /// tracked in to the old one, and the graph is handed to the background solver.
  void addLoop(const LoopDetector::Step& step, LoopReport* report);
  /// Places every submap where a solution of the graph puts it (those started since it was
  /// handed over move with the newest it holds) and says so in `report`.
  void applyGraphSolution(const BackgroundGraphSolver::Result& result, LoopReport* report);
  SubmapPlace& placeOf(int node) { return const_cast<SubmapPlace&>(submapPlace(node)); }
  /// Whether the latest solution left loop edge `edge` (an index into the graph's edges) out.
  bool rejectedByTheGraph(size_t edge) const;

  PipelineConfig config_;
  std::unique_ptr<TsdfMap> map_;
  std::unique_ptr<Integrator> integrator_;
  std::unique_ptr<Tracker> tracker_;
  /// The pixel map of the last distorted camera seen (made again when the camera changes).
  std::optional<DepthUndistortion> undistortion_;
  /// The last colour image undistorted (its memory reused).
  ColourImage colour_buffer_;
  /// Present with a sparse map and max_map_memory_mb > 0.
  std::unique_ptr<MapMemoryBudget> budget_;
  Eigen::Isometry3d T_W_C_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_W_C_last_fused_ = Eigen::Isometry3d::Identity();
  bool map_initialised_ = false;
  int consecutive_failures_ = 0;
  /// The last tracked poses, for the prediction; cleared by a failed frame.
  MotionModel motion_;
  /// When the frame whose pose T_W_C_ holds was taken (NaN: unknown, or frames without times).
  double held_pose_timestamp_s_ = std::numeric_limits<double>::quiet_NaN();
  /// From the tracked frame before that one to it (the camera's rate, as frames get tracked).
  double tracked_interval_s_ = std::numeric_limits<double>::quiet_NaN();
  /// The other odometry's camera pose (processFrame's T_odom_C) at the frame whose pose T_W_C_
  /// holds; none when that frame came without one.
  std::optional<Eigen::Isometry3d> T_odom_C_held_;
  std::unique_ptr<PlaceMemory> places_;
  std::unique_ptr<Relocaliser> relocaliser_;
  /// The pose is not known at all (loaded map, relocalise()): every frame goes to the search, which
  /// tries search_guess_ first, until a candidate is accepted; tracking from the held pose alone
  /// does not end it (as it ends a search after a loss).
  bool pose_unknown_ = false;
  std::optional<Eigen::Isometry3d> search_guess_;
  /// The poses the current search tries first on every frame.
  std::vector<Eigen::Isometry3d> search_guesses_;
  /// The whole map while a search runs in a map of several submaps, and after it found the
  /// camera until the new submap's handover ends.
  std::unique_ptr<TsdfMap> search_map_;
  SubmapStore closed_submaps_;
  /// With submaps and a memory budget: the budget [bytes], and whether the user was told that
  /// submaps go to the swap file, and that the map stays over the budget (until it is back within).
  size_t submap_budget_bytes_ = 0;
  bool told_of_submap_swap_ = false;
  bool submaps_over_budget_ = false;
  /// With SubmapConfig::track_recent_m: the submaps the camera left within that path, merged in
  /// the active one's frame when it started (and again when a graph solution moves them against
  /// it), and the overlay of them on the active submap that frames are tracked against (until the
  /// merge lands, the overlay of the submap just closed).
  std::unique_ptr<SparseTsdfMap> recent_submaps_;
  std::unique_ptr<OverlaidMap> tracked_map_;
  /// What the overlay holds, placed in the active one's frame.
  RecentPlacements recent_placements_;
  /// A merge of the recent submaps running in the background (it reads closed submaps: declared
  /// after them, so that it ends before they go).
  struct RecentMerge {
    std::unique_ptr<SparseTsdfMap> map;  ///< none when a submap could not be read back
    RecentPlacements placements;
    std::string error;
  };
  std::future<RecentMerge> recent_merge_;
  /// Why the last merge failed, until a frame's report says it.
  std::string recent_merge_error_;
  /// Where the active submap (map_) lies.
  SubmapPlace active_;
  /// The keyframes while a search runs in the merged submaps, at their places in the map frame.
  std::unique_ptr<PlaceMemory> search_places_;
  /// The submap each keyframe of places_ was taken in (its pose is in that submap's frame).
  std::vector<int> keyframe_submaps_;
  PoseGraph graph_;
  std::unique_ptr<LoopDetector> loop_detector_;
  std::unique_ptr<BackgroundGraphSolver> graph_solver_;
  /// The graph's edges that closeLoops() added (the one after a search in the merged map joins a
  /// submap, but is no loop found), and how many edges the last solution applied held.
  std::vector<size_t> loop_edges_;
  size_t solved_edges_ = 0;
  std::vector<int> rejected_edges_;  ///< the latest solution's rejected loops
  /// During a handover: the map frames are tracked against, the frames left, and whether they
  /// are fused into it too (the closed submap; not a search's merged copy).
  const TsdfMap* handover_map_ = nullptr;
  int handover_frames_left_ = 0;
  bool handover_fuses_previous_ = false;
};

}  // namespace sdf_tracker
