#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/places/place_memory.h"
#include "sdf_tracker/relocalisation/view_agreement.h"
#include "sdf_tracker/tracking/tracker.h"

namespace sdf_tracker {

struct RelocaliserConfig {
  /// The wide-basin field candidates are first aligned with (buildCoarseField).
  double coarse_cell_m = 0.08;
  double coarse_reach_m = 0.6;
  /// Keyframes tried per frame: the most alike, and the others in turn by likeness; keyframes
  /// whose codes differ from the frame's in more than max_dissimilarity of the ferns are not tried.
  int candidates_per_frame = 3;
  double max_dissimilarity = 0.95;
  /// What a candidate must show, refined against the map, to be kept (measureViewAgreement): the
  /// tracker's kOk (all six directions constrained, converged), at least min_overlap of its points
  /// on mapped surfaces (the rest may be new ground), and at most max_contradiction of them in
  /// space the map observed as free or seen through a mapped surface. Measured over every converged
  /// candidate of the later parts of redkitchen and fr1_xyz and of the house walk that never comes
  /// back (bench/relocalisation.sh): right ones (within 5 cm, 5 degrees) contradict 0-2.9 %, wrong
  /// ones (beyond 10 cm or 10 degrees) 9.2-48 %, whatever their share on mapped surfaces (right
  /// 0.50-0.99, wrong 0.46-0.84): the default sits between, with a margin of 1.7 either way.
  double min_overlap = 0.4;
  double max_contradiction = 0.05;
  /// Frames in a row a kept candidate must go on tracking (from its own estimate, nothing fused)
  /// before it is accepted; 1 accepts on the frame that found it.
  int confirm_frames = 3;

  std::vector<std::string> validate() const;
};

/// Finds the camera in a map when the tracker does not know where it is (after a loss, or at the
/// first frame of a session in a loaded map). Each frame it tries a few starting poses (given
/// ones, then the place memory's most alike keyframes): aligned with the map's wide-basin field,
/// then refined by the tracker against the map (its coarsest level; a fit at a new place then
/// with the full schedule), and verified by what the map knows (see RelocaliserConfig). A
/// candidate that fits is followed, tracked frame to frame and verified again, over
/// confirm_frames frames before it is accepted; those frames go on searching, and a second place
/// that fits as well makes the view ambiguous: nothing is kept until it tells them apart (while
/// two or more fit, frames only follow them, without searching). It
/// never writes into the map: fusing is the caller's, after acceptance. Not thread safe.
class Relocaliser {
 public:
  /// `tracker` is the configuration the refinement and confirmation track with (the pipeline's).
  /// Throws std::invalid_argument naming every violation of either config.
  Relocaliser(const RelocaliserConfig& config, const TrackerConfig& tracker);

  const RelocaliserConfig& config() const { return config_; }

  /// Starts a search in `map` (its wide-basin field is built here, once per search): forgets any
  /// candidate. Throws std::invalid_argument when the map holds no surface.
  void begin(const TsdfMap& map);
  bool searching() const { return searching_; }
  /// Ends a search without a result (the map was replaced or cleared).
  void cancel();

  enum class Outcome {
    kNotFound,    ///< no candidate fits this frame
    kConfirming,  ///< a candidate fits and is being followed (confirmations so far in `confirmed`)
    kAccepted,    ///< a candidate was followed over confirm_frames frames: T_W_C is the pose
    kAmbiguous,   ///< two or more distinct places fit this frame: none is kept
  };
  struct Step {
    Outcome outcome = Outcome::kNotFound;
    Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();  ///< the candidate's pose (kConfirming, kAccepted)
    TrackResult track;                                        ///< the frame tracked from the candidate
    int candidates_tried = 0;                                 ///< this frame
    int confirmed = 0;
    int places_fitting = 0;  ///< distinct places that fit this frame (kAmbiguous: two or more)
    std::string message;  ///< what was tried and why nothing was kept, in words
  };
  /// One frame of the search (depth as the tracker takes it, ideal camera). `guesses` are tried
  /// before the keyframes (a pose the user gave, the last known one). `map` must be the one
  /// begin() was given, unchanged. `motion`: how the camera moved since the previous step's frame
  /// (T_previous_this), when something measured it (a loop search's frames are tracked); the
  /// places followed are moved by it before they are tracked. Identity: not known.
  Step step(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map, const PlaceMemory& places,
            const std::vector<Eigen::Isometry3d>& guesses,
            const Eigen::Isometry3d& motion = Eigen::Isometry3d::Identity());

  /// Whether a view placed at T_W_C agrees with what the map observed as a kept candidate must (at
  /// least min_overlap of its points on mapped surfaces, at most max_contradiction against what
  /// the map saw); `agreement` gets the measure. Reads the map only.
  bool agrees(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map, const Eigen::Isometry3d& T_W_C,
              ViewAgreement* agreement) const;

  /// Frames and candidates the current (or last) search has spent.
  int framesSpent() const { return frames_spent_; }
  int candidatesTried() const { return candidates_tried_; }

  /// The tracker configuration of the wide-basin alignment: the pipeline's with a schedule on
  /// the coarse lattice, a Huber threshold of its scale and the reach as the motion limit.
  static TrackerConfig coarseTrackerConfig(const TrackerConfig& tracker, const RelocaliserConfig& config);

 private:
  /// Whether a refined track fits well enough to keep its candidate; `agreement` is measured when
  /// the track is ok.
  bool fits(const TrackResult& track, const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
            ViewAgreement* agreement) const;

  /// The poses this frame's search starts from: `guesses`, then the place memory's keyframes.
  std::vector<Eigen::Isometry3d> startingPoses(const DepthImage& depth, const PlaceMemory& places,
                                               const std::vector<Eigen::Isometry3d>& guesses);

  /// Every this many pixels a candidate's view is verified (measureViewAgreement).
  static constexpr int kVerificationStride = 8;
  /// At most this many places are followed at once (the best fitting are kept): what bounds a
  /// searching frame's cost in a map of many alike places.
  static constexpr size_t kMaxHypotheses = 3;

  RelocaliserConfig config_;
  Tracker coarse_tracker_;
  Tracker screening_tracker_;
  Tracker tracker_;
  std::unique_ptr<TsdfVolume> coarse_field_;
  bool searching_ = false;
  /// The places that fit: each followed from frame to frame while it goes on fitting, with the
  /// frames in a row it has been the only one (reset while two or more fit).
  struct Hypothesis {
    Eigen::Isometry3d T_W_C;
    int confirmed = 0;
  };
  std::vector<Hypothesis> hypotheses_;
  int frames_spent_ = 0;
  int candidates_tried_ = 0;
  /// Where the keyframes after the most alike one take up their turns (see step()).
  size_t next_rank_ = 0;
};

const char* toString(Relocaliser::Outcome outcome);

}  // namespace sdf_tracker
