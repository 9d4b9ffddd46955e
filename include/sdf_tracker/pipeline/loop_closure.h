#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/graph/pose_graph.h"
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
  /// places them) are the candidates: the drift since must be within it.
  double search_radius_m = 2.0;
  double search_angle_deg = 60.0;
  /// A loop search that has not accepted after this many frames is given up (the relocaliser's
  /// confirmation takes RelocaliserConfig::confirm_frames of them), and the next check waits
  /// retry_after_frames.
  int max_search_frames = 6;
  int retry_after_frames = 30;
  /// The standard deviation of a loop's relative pose (the relocaliser's fit against the old
  /// submap) [m, degrees].
  double loop_sigma_m = 0.02;
  double loop_sigma_deg = 1.0;
  /// The standard deviation of the odometry between consecutive submaps (the tracker's drift over
  /// the stretch): this fraction of the distance between their anchors [m/m], this many degrees per
  /// metre, and no less than the floors.
  double odometry_drift = 0.02;
  double odometry_drift_deg_per_m = 0.5;
  double odometry_floor_m = 0.005;
  double odometry_floor_deg = 0.2;

  std::vector<std::string> validate() const;
};

/// The information of the odometry edge between two consecutive submaps whose anchors are `motion`
/// apart (LoopClosureConfig's drift model).
PoseInformation odometryEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& motion);
/// The information of a loop edge measured by a fit of the camera in the old submap S: the fit's
/// pose T_S_C and its covariance (TrackResult::covariance, about the camera centre along S's
/// axes), carried to the edge's error in the frame of its `to` node, which lies at T_S_to; plus
/// loop_sigma in every direction (what the fit does not see: each submap's own error). Along a
/// direction the view left unconstrained (a corridor's length) the loop holds next to nothing.
PoseInformation loopEdgeInformation(const LoopClosureConfig& config, const Eigen::Isometry3d& T_S_C,
                                    const Eigen::Matrix<double, 6, 6>& fit_covariance_S,
                                    const Eigen::Isometry3d& T_S_to);

/// The camera found in an older submap (LoopDetector::step).
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
/// relocaliser accepted. Not thread safe.
class LoopDetector {
 public:
  /// Throws std::invalid_argument naming every violation of the configs.
  LoopDetector(const LoopClosureConfig& config, const RelocaliserConfig& relocaliser, const TrackerConfig& tracker,
               const PlaceMemoryConfig& places);

  const LoopClosureConfig& config() const { return config_; }

  struct Step {
    bool searched = false;            ///< a loop search ran on this frame
    int submap = -1;                  ///< in which submap
    std::optional<LoopMatch> match;   ///< the camera was found there (accepted)
    std::string message;              ///< why the search ended without a match, when it did
  };
  /// One tracked frame (depth as the tracker takes it, ideal camera) at T_A_C in the active
  /// submap `active`'s frame. `closed`: the submaps before it, oldest first (indices are their
  /// place.node); `places`: every keyframe, `keyframe_submaps[k]` the submap keyframe k was taken
  /// in (its pose is in that submap's frame).
  Step step(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_A_C,
            const SubmapPlace& active, const std::vector<Submap>& closed, const PlaceMemory& places,
            const std::vector<int>& keyframe_submaps);

  /// Ends a search and forgets the submaps already joined to the active one (a cleared or
  /// replaced map).
  void reset();
  /// A new submap is active: every older one may be joined to it.
  void startedSubmap() { joined_.clear(); }
  /// A loop to `submap` from the active one was closed: it is not searched for again while the
  /// active submap stays the same.
  void joined(int submap) { joined_.push_back(submap); }

 private:
  /// The old submap to search, if any keyframe of one is near the camera and alike.
  std::optional<int> candidate(const DepthImage& depth, const Eigen::Isometry3d& T_map_C, const SubmapPlace& active,
                               const std::vector<Submap>& closed, const PlaceMemory& places,
                               const std::vector<int>& keyframe_submaps) const;

  LoopClosureConfig config_;
  Relocaliser relocaliser_;
  /// The searched submap's keyframes (what the relocaliser starts from besides the guess).
  PlaceMemory search_places_;
  int search_submap_ = -1;
  int search_frames_ = 0;
  int frames_until_check_ = 0;
  std::vector<int> joined_;
};

}  // namespace sdf_tracker
