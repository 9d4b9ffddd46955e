#include "sdf_tracker/relocalisation/relocaliser.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/relocalisation/coarse_field.h"
#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

std::vector<std::string> RelocaliserConfig::validate() const {
  Violations v;
  v.requirePositive("coarse_cell_m", coarse_cell_m);
  v.require(coarse_reach_m > coarse_cell_m && std::isfinite(coarse_reach_m),
            "coarse_reach_m must be finite and > coarse_cell_m (got " + std::to_string(coarse_reach_m) + ")");
  v.requireInRange("candidates_per_frame", candidates_per_frame, 0, 1000);
  v.requireInRange("max_dissimilarity", max_dissimilarity, 0.0, 1.0);
  v.requireInRange("min_overlap", min_overlap, 0.0, 1.0);
  v.requireInRange("max_contradiction", max_contradiction, 0.0, 1.0);
  v.requireInRange("confirm_frames", confirm_frames, 1, 1000);
  return v.list();
}

const char* toString(Relocaliser::Outcome outcome) {
  switch (outcome) {
    case Relocaliser::Outcome::kNotFound: return "not_found";
    case Relocaliser::Outcome::kConfirming: return "confirming";
    case Relocaliser::Outcome::kAmbiguous: return "ambiguous";
    case Relocaliser::Outcome::kAccepted: return "accepted";
  }
  return "unknown";
}

TrackerConfig Relocaliser::coarseTrackerConfig(const TrackerConfig& tracker, const RelocaliserConfig& config) {
  TrackerConfig coarse = tracker;
  coarse.levels = {{8, 20}};
  // The coarse field's distances are good to about half a cell: residuals below that are noise.
  coarse.huber_coefficient = 0.5 * config.coarse_cell_m / config.coarse_reach_m;
  coarse.sensor_weights = false;
  coarse.normalize_by_gradient = false;
  coarse.convergence_threshold = 1e-3;
  coarse.min_overlap = 0.0;
  coarse.solve_constrained_directions = false;
  coarse.max_final_step = 1.0;  // converged or not, its estimate only seeds the refinement
  coarse.max_translation_m = config.coarse_reach_m;
  coarse.max_rotation_rad = std::max(tracker.max_rotation_rad, 0.6);
  return coarse;
}

namespace {

/// The refinement of a candidate: the tracker's own settings on its coarsest level only. That
/// tells a fit from a miss at a fraction of the full schedule's cost; the kept candidate is then
/// tracked with the full schedule.
TrackerConfig screeningConfig(const TrackerConfig& tracker) {
  TrackerConfig screening = tracker;
  screening.levels.resize(1);
  return screening;
}

/// The tracker's settings for candidates: their overlap is judged by the verification
/// (RelocaliserConfig::min_overlap, over what the map has observed), not by the tracker's floor,
/// which is made for frame-to-frame tracking and would refuse a view that is partly new.
TrackerConfig candidateConfig(TrackerConfig tracker) {
  tracker.min_overlap = 0.0;
  return tracker;
}

}  // namespace

Relocaliser::Relocaliser(const RelocaliserConfig& config, const TrackerConfig& tracker)
    : config_(config),
      coarse_tracker_(coarseTrackerConfig(tracker, config)),
      screening_tracker_(screeningConfig(candidateConfig(tracker))),
      tracker_(candidateConfig(tracker)) {
  throwIfInvalid("relocaliser config", config.validate());
}

void Relocaliser::begin(const TsdfMap& map) {
  coarse_field_ = std::make_unique<TsdfVolume>(buildCoarseField(map, config_.coarse_cell_m, config_.coarse_reach_m));
  searching_ = true;
  hypotheses_.clear();
  frames_spent_ = candidates_tried_ = 0;
  next_rank_ = 0;
}

void Relocaliser::cancel() {
  searching_ = false;
  hypotheses_.clear();
  coarse_field_.reset();
}

bool Relocaliser::fits(const TrackResult& track, const DepthImage& depth, const PinholeCamera& camera,
                       const TsdfMap& map, ViewAgreement* agreement) const {
  return track.ok() && agrees(depth, camera, map, track.T_W_C, agreement);
}

bool Relocaliser::agrees(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                         const Eigen::Isometry3d& T_W_C, ViewAgreement* agreement) const {
  *agreement = measureViewAgreement(depth, camera, map, T_W_C, kVerificationStride);
  return agreement->mappedShare() >= config_.min_overlap &&
         agreement->contradictionShare() <= config_.max_contradiction;
}

namespace {

/// Two fitting candidates further apart than this are two places, not one place found twice.
constexpr double kDistinctPlace_m = 0.15;
constexpr double kDistinctPlace_rad = 0.15;

bool samePlace(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return d.translation().norm() <= kDistinctPlace_m && rotationAngle(d) <= kDistinctPlace_rad;
}

std::string describe(const TrackResult& track, const ViewAgreement& agreement) {
  std::ostringstream s;
  s << toString(track.status);
  if (track.ok()) {
    s << ", " << std::lround(100.0 * agreement.mappedShare()) << " % on mapped surfaces, " << std::fixed
      << std::setprecision(1) << 100.0 * agreement.contradictionShare() << " % against what the map saw";
  } else {
    s << ", overlap " << std::setprecision(2) << track.overlap;
  }
  return s.str();
}

}  // namespace

std::vector<Eigen::Isometry3d> Relocaliser::startingPoses(const DepthImage& depth, const PlaceMemory& places,
                                                          const std::vector<Eigen::Isometry3d>& guesses) {
  std::vector<Eigen::Isometry3d> starts = guesses;
  if (places.empty() || config_.candidates_per_frame <= 0) return starts;
  // The most alike keyframe, then the next of the others in the order of likeness: the ferns
  // rank well but not perfectly, and over a few frames every alike keyframe gets its turn.
  const PlaceCode code = places.encoder().encode(depth);
  std::vector<PlaceMemory::Match> ranked = places.mostAlike(code, places.keyframes().size());
  while (!ranked.empty() && ranked.back().dissimilarity > config_.max_dissimilarity) ranked.pop_back();
  if (!ranked.empty()) starts.push_back(places.keyframes()[ranked.front().keyframe].T_W_C);
  const size_t others = ranked.size() > 1 ? ranked.size() - 1 : 0;
  const size_t turns = std::min(others, static_cast<size_t>(config_.candidates_per_frame - 1));
  for (size_t n = 0; n < turns; ++n) {
    starts.push_back(places.keyframes()[ranked[1 + (next_rank_ + n) % others].keyframe].T_W_C);
  }
  if (others > 0) next_rank_ = (next_rank_ + turns) % others;
  return starts;
}

Relocaliser::Step Relocaliser::step(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                                    const PlaceMemory& places, const std::vector<Eigen::Isometry3d>& guesses,
                                    const Eigen::Isometry3d& motion) {
  if (!searching_ || !coarse_field_) throw std::logic_error("Relocaliser::step without begin()");
  ++frames_spent_;
  Step result;
  struct Fit {
    TrackResult track;
    ViewAgreement agreement;
    int confirmed = 0;  ///< frames in a row as the only place, before this one
  };
  std::vector<Fit> fitting;    // one per distinct place
  std::optional<Fit> closest;  // the best of the candidates that did not fit, to say why
  auto known = [&](const Eigen::Isometry3d& T) {
    return std::any_of(fitting.begin(), fitting.end(), [&](const Fit& f) { return samePlace(f.track.T_W_C, T); });
  };
  auto consider = [&](TrackResult&& track, const ViewAgreement& agreement, bool fits_here, int confirmed) {
    if (!fits_here) {
      if (!closest || track.overlap > closest->track.overlap) closest = Fit{std::move(track), agreement, 0};
    } else if (!known(track.T_W_C)) {
      fitting.push_back(Fit{std::move(track), agreement, confirmed});
    }
  };

  // The places that fitted so far are followed: each is tracked from its last estimate (moved as
  // the camera moved, when that is known) and must be verified again.
  for (const Hypothesis& h : hypotheses_) {
    TrackResult track = tracker_.track(depth, camera, map, h.T_W_C * motion);
    ViewAgreement agreement;
    const bool holds = fits(track, depth, camera, map, &agreement);
    consider(std::move(track), agreement, holds, h.confirmed);
  }
  // A confirming frame searches too: a second place that fits as well makes the view ambiguous,
  // however well the first goes on fitting. While two or more places still fit, the view is
  // ambiguous already and nothing could be accepted: the frame only follows them.
  const bool still_ambiguous = fitting.size() > 1;
  for (const Eigen::Isometry3d& start :
       still_ambiguous ? std::vector<Eigen::Isometry3d>() : startingPoses(depth, places, guesses)) {
    if (known(start)) continue;
    ++result.candidates_tried;
    ++candidates_tried_;
    const TrackResult coarse = coarse_tracker_.track(depth, camera, *coarse_field_, start);
    TrackResult screened = screening_tracker_.track(depth, camera, map, coarse.pose_estimated ? coarse.T_W_C : start);
    ViewAgreement agreement;
    if (!fits(screened, depth, camera, map, &agreement)) {
      consider(std::move(screened), agreement, false, 0);
      continue;
    }
    if (known(screened.T_W_C)) continue;
    // A screened fit at a new place, tracked with the full schedule: it must still fit.
    TrackResult full = tracker_.track(depth, camera, map, screened.T_W_C);
    const bool fits_here = fits(full, depth, camera, map, &agreement);
    consider(std::move(full), agreement, fits_here, 0);
  }

  // The best fitting places are followed on the next frame.
  std::stable_sort(fitting.begin(), fitting.end(), [](const Fit& a, const Fit& b) {
    return a.agreement.mappedShare() > b.agreement.mappedShare();
  });
  if (fitting.size() > kMaxHypotheses) fitting.resize(kMaxHypotheses);
  hypotheses_.clear();
  for (const Fit& f : fitting) hypotheses_.push_back(Hypothesis{f.track.T_W_C, 0});
  result.places_fitting = static_cast<int>(fitting.size());

  if (fitting.size() > 1) {
    // Two places (two identical rooms, a symmetric one) fit: both are followed, and neither is
    // confirmed until the view tells them apart.
    result.outcome = Outcome::kAmbiguous;
    result.track = fitting.front().track;
    std::ostringstream s;
    s << fitting.size() << " places fit the view alike (" << result.candidates_tried
      << " new candidates tried); nothing is accepted until the view tells them apart";
    result.message = s.str();
    return result;
  }
  if (fitting.empty()) {
    std::ostringstream s;
    s << "no candidate fits (" << result.candidates_tried << " tried";
    if (places.empty()) s << "; the place memory holds no keyframe";
    if (closest) s << "; the closest: " << describe(closest->track, closest->agreement);
    s << ")";
    result.message = s.str();
    return result;
  }
  Fit& fit = fitting.front();
  result.confirmed = hypotheses_.front().confirmed = fit.confirmed + 1;
  result.T_W_C = fit.track.T_W_C;
  result.track = std::move(fit.track);
  result.outcome = result.confirmed >= config_.confirm_frames ? Outcome::kAccepted : Outcome::kConfirming;
  if (result.outcome == Outcome::kAccepted) {
    searching_ = false;
    hypotheses_.clear();
  }
  return result;
}

}  // namespace sdf_tracker
