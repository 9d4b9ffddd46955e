#pragma once

#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/graph/pose_graph.h"
#include "sdf_tracker/pipeline/submap_store.h"
#include "sdf_tracker/pipeline/submaps.h"
#include "sdf_tracker/places/place_memory.h"
#include "sdf_tracker/relocalisation/relocaliser.h"
#include "sdf_tracker/tracking/tracker.h"

namespace sdf_tracker {

/// Closing loops between submaps (SubmapConfig): the view found again in a submap that is not
/// recent becomes a loop edge of the submaps' pose graph, which then places every submap anew.
struct LoopClosureConfig {
  bool enabled = false;
  /// A tracked frame is looked at for a loop every this many frames (while no loop search runs).
  int check_interval_frames = 15;
  /// A submap is a loop candidate once this many submaps have started after it: the one before
  /// the active submap shares its handover frames, so it is odometry, not a loop.
  int min_submap_age = 2;
  /// ... and once the camera has gone this far since it started [m] (anchor to anchor): a loop
  /// over a shorter path corrects little drift, and joins views the odometry already holds.
  double min_path_m = 4.0;
  /// Keyframes of older submaps within this distance and turn of the camera (where the graph
  /// places them) are the candidates. (4 m, views across a room, found more loops and one of them
  /// false on the 3 % round trip: bench/results/2026-12-07_loop_search_radius.md.)
  double search_radius_m = 2.0;
  double search_angle_deg = 60.0;
  /// A place found further than this from where the graph puts the camera in the old submap (or
  /// turned further than search_angle_deg) is refused, however well it fits: the drift since
  /// must be within it.
  double max_drift_m = 2.0;
  /// A loop search that has not accepted after this many frames is given up (the relocaliser's
  /// confirmation takes RelocaliserConfig::confirm_frames of them), and the next check waits
  /// retry_after_frames.
  int max_search_frames = 6;
  int retry_after_frames = 30;
  /// The standard deviation of a loop's relative pose besides its fit's covariance and the drift
  /// over the stretches it spans (loopEdgeInformation): what neither states [m, degrees].
  double loop_sigma_m = 0.02;
  double loop_sigma_deg = 1.0;
  /// The standard deviation of the odometry between consecutive submaps (the tracker's drift over
  /// the stretch): this fraction of the distance between their anchors [m/m], this many degrees per
  /// metre, and no less than the floors. A loop adds the same drift, without the floors, over the
  /// stretches between its frame and the two anchors it joins.
  double odometry_drift = 0.02;
  double odometry_drift_deg_per_m = 0.5;
  double odometry_floor_m = 0.005;
  double odometry_floor_deg = 0.2;

  std::vector<std::string> validate() const;
};

/// The information of the odometry edge between two consecutive submaps whose anchors are `motion`
/// apart (LoopClosureConfig's drift model).
PoseInformation odometryEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& motion);
/// The information of a loop edge measured by a fit of the camera in the old submap S, from the
/// old submap's anchor (its `from` node, at T_S_from) to the anchor of the submap the frame was
/// tracked in (its `to` node, at T_S_to): the fit's pose T_S_C and its covariance
/// (TrackResult::covariance, about the camera centre along S's axes), carried to the edge's error
/// in the frame of its `to` node; plus loop_sigma in every direction (what the fit does not see);
/// plus the drift model's odometry over the two stretches the edge spans besides the fit (from
/// S's anchor to where the camera is found: the old map there was fused at poses tracked that far;
/// from the camera to its own submap's anchor). Along a direction the view left unconstrained (a
/// corridor's length) the loop holds next to nothing.
PoseInformation loopEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& T_S_from,
                                    const Eigen::Isometry3d& T_S_C,
                                    const Eigen::Matrix<double, 6, 6>& fit_covariance_S,
                                    const Eigen::Isometry3d& T_S_to);

/// The camera found in an older submap (LoopDetector::Step).
struct LoopMatch {
  int submap = -1;                                          ///< index of the old submap
  Eigen::Isometry3d T_S_C = Eigen::Isometry3d::Identity();  ///< the camera in that submap's frame
  /// The fit's covariance of T_S_C (TrackResult::covariance).
  Eigen::Matrix<double, 6, 6> covariance_S = Eigen::Matrix<double, 6, 6>::Zero();
};

/// Looks for the camera's view in submaps that are not recent, where the pose graph places them
/// near the camera: every check_interval_frames frames, the keyframes of such submaps near the
/// camera are ranked by how alike their views are to this frame's, and the submap of the most alike
/// becomes a loop search: the relocaliser (its alignment, verification against what the submap has
/// observed, and confirmation over several frames, with ambiguity refused), started from where the
/// graph puts the camera in that submap and from its keyframes. A match is only what the
/// relocaliser accepted.
///
/// The search runs on a thread of its own, one frame at a time, with one OpenMP thread (the
/// tracking keeps the others): the tracking thread hands it a copy of a frame when it is free, and
/// takes the outcome at a later frame. Tracking never waits for a search; a search looks at the
/// frames it has time for, following the places it tries by the camera's tracked motion between
/// them. Not thread safe itself: one caller.
class LoopDetector {
 public:
  /// Throws std::invalid_argument naming every violation of the configs.
  LoopDetector(const LoopClosureConfig& config, const RelocaliserConfig& relocaliser, const TrackerConfig& tracker,
               const PlaceMemoryConfig& places);
  /// Waits for a search step still running (its outcome is dropped).
  ~LoopDetector();
  LoopDetector(const LoopDetector&) = delete;
  LoopDetector& operator=(const LoopDetector&) = delete;

  const LoopClosureConfig& config() const { return config_; }

  /// A search step that finished: the frame it looked at, and what it found there.
  struct Step {
    bool searched = false;            ///< a search step finished (none: nothing else is set)
    int submap = -1;                  ///< in which submap it searched
    std::optional<LoopMatch> match;   ///< the camera was found there (accepted)
    std::string message;              ///< why the search ended without a match, when it did
    double search_ms = 0.0;           ///< the step's time on the search thread
    /// The frame it looked at: the camera in the tracker's frame W then, and the submap (its
    /// place.node) that frame was tracked in.
    Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
    int frame_submap = -1;
  };
  /// One tracked frame (depth as the tracker takes it, ideal camera) at T_W_C in the active submap
  /// `active`. `closed`: the submaps before it, oldest first (indices are their place.node);
  /// `places`: every keyframe, `keyframe_submaps[k]` the submap keyframe k was taken in (its pose
  /// is in that submap's frame). Returns the search step that finished since the last call, if
  /// any (it looked at an earlier frame); when the search thread is free, hands it this frame
  /// (a copy), if a search runs or one is due. Never waits. A search holds the map of the submap
  /// it searches (read back on its thread when it is in the swap file), which must not change
  /// meanwhile (only the newest may still be fused into); `closed` must last until reset().
  Step step(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
            const SubmapPlace& active, const SubmapStore& closed, const PlaceMemory& places,
            const std::vector<int>& keyframe_submaps);
  /// Waits for the search step running, if any, and returns it (what a run's end must see).
  Step finish();

  /// Ends a search (waiting for its running step, which is dropped) and forgets the submaps
  /// already joined to the active one: before the submaps are cleared or replaced.
  void reset();
  /// A new submap is active: every older one may be joined to it.
  void startedSubmap() { joined_.clear(); }
  /// A loop to `submap` from the active one was closed: it is not searched for again while the
  /// active submap stays the same.
  void joined(int submap) { joined_.push_back(submap); }
  /// The submap a search runs in (-1: none).
  int searchedSubmap() const { return search_submap_; }

 private:
  /// The old submap to search, if any keyframe of one is near the camera and alike.
  std::optional<int> candidate(const DepthImage& depth, const Eigen::Isometry3d& T_map_C, const SubmapPlace& active,
                               const SubmapStore& closed, const PlaceMemory& places,
                               const std::vector<int>& keyframe_submaps) const;
  /// What the search thread is given: a frame, and where the graph puts it in the searched submap.
  struct Job {
    DepthImage depth;
    PinholeCamera camera;
    /// The searched submap's map; at the search's first frame, none yet: the search thread reads
    /// it from `closed` (from the swap file when it is there).
    std::shared_ptr<const TsdfMap> map;
    const SubmapStore* closed = nullptr;
    int submap = -1;
    bool begins = false;  ///< the search's first frame: its field is built first
    Eigen::Isometry3d guess = Eigen::Isometry3d::Identity();   ///< T_S_C by the graph
    Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();  ///< tracked, since its last frame
    Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
    int frame_submap = -1;
  };
  struct Outcome {
    Job job;  ///< its depth released
    Relocaliser::Step found;
    /// Nothing to find there: the submap holds no surface, or could not be read back (why).
    bool no_surface = false;
    std::string read_error;
    double ms = 0.0;
  };
  /// The search thread's work on one frame.
  Outcome search(Job job);
  /// Ends or goes on with the search by a finished step's outcome.
  Step conclude(Outcome outcome);

  LoopClosureConfig config_;
  /// The search thread's alone while a step runs (running_), the caller's otherwise.
  Relocaliser relocaliser_;
  /// The searched submap's keyframes (what the relocaliser starts from besides the guess).
  PlaceMemory search_places_;
  std::future<Outcome> running_;
  int search_submap_ = -1;
  /// The searched submap's map while the search goes on.
  std::shared_ptr<const TsdfMap> search_map_;
  int search_frames_ = 0;
  /// The pose of the last frame handed to the search (its motion to the next one).
  Eigen::Isometry3d last_search_T_W_C_ = Eigen::Isometry3d::Identity();
  int frames_until_check_ = 0;
  std::vector<int> joined_;
};

}  // namespace sdf_tracker
