#include "sdf_tracker/relocalisation/relocaliser.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/relocalisation/coarse_field.h"
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
  v.requireInRange("confirm_frames", confirm_frames, 1, 1000);
  return v.list();
}

const char* toString(Relocaliser::Outcome outcome) {
  switch (outcome) {
    case Relocaliser::Outcome::kNotFound: return "not_found";
    case Relocaliser::Outcome::kConfirming: return "confirming";
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

}  // namespace

Relocaliser::Relocaliser(const RelocaliserConfig& config, const TrackerConfig& tracker)
    : config_(config),
      coarse_tracker_(coarseTrackerConfig(tracker, config)),
      screening_tracker_(screeningConfig(tracker)),
      tracker_(tracker) {
  throwIfInvalid("relocaliser config", config.validate());
}

void Relocaliser::begin(const TsdfMap& map) {
  coarse_field_ = std::make_unique<TsdfVolume>(buildCoarseField(map, config_.coarse_cell_m, config_.coarse_reach_m));
  searching_ = true;
  candidate_.reset();
  confirmed_ = frames_spent_ = candidates_tried_ = 0;
  next_rank_ = 0;
}

void Relocaliser::cancel() {
  searching_ = false;
  candidate_.reset();
  coarse_field_.reset();
}

bool Relocaliser::fits(const TrackResult& track) const { return track.ok() && track.overlap >= config_.min_overlap; }

Relocaliser::Step Relocaliser::step(const DepthImage& depth, const PinholeCamera& camera, const TsdfMap& map,
                                    const PlaceMemory& places, const std::vector<Eigen::Isometry3d>& guesses) {
  if (!searching_ || !coarse_field_) throw std::logic_error("Relocaliser::step without begin()");
  ++frames_spent_;
  Step result;
  // A kept candidate is followed: the frame is tracked from its last estimate.
  if (candidate_) {
    result.track = tracker_.track(depth, camera, map, *candidate_);
    if (fits(result.track)) {
      candidate_ = result.track.T_W_C;
      result.T_W_C = *candidate_;
      result.confirmed = ++confirmed_;
      result.outcome = confirmed_ >= config_.confirm_frames ? Outcome::kAccepted : Outcome::kConfirming;
      if (result.outcome == Outcome::kAccepted) searching_ = false;
      return result;
    }
    candidate_.reset();  // it did not hold: search afresh on this frame
    confirmed_ = 0;
  }

  std::vector<Eigen::Isometry3d> starts = guesses;
  if (!places.empty() && config_.candidates_per_frame > 0) {
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
  }
  std::optional<TrackResult> best, closest;  // the best fit, and the best of those that did not fit
  for (const Eigen::Isometry3d& start : starts) {
    ++result.candidates_tried;
    ++candidates_tried_;
    const TrackResult coarse = coarse_tracker_.track(depth, camera, *coarse_field_, start);
    const TrackResult refined =
        screening_tracker_.track(depth, camera, map, coarse.pose_estimated ? coarse.T_W_C : start);
    std::optional<TrackResult>& kept = fits(refined) ? best : closest;
    if (!kept || refined.overlap > kept->overlap) kept = refined;
  }
  if (best) {
    // The best screened candidate, tracked with the full schedule: it must still fit.
    TrackResult full = tracker_.track(depth, camera, map, best->T_W_C);
    if (fits(full)) {
      best = std::move(full);
    } else {
      closest = std::move(full);
      best.reset();
    }
  }
  if (!best) {
    std::ostringstream s;
    s << "no candidate fits (" << result.candidates_tried << " tried";
    if (places.empty()) s << "; the place memory holds no keyframe";
    if (closest) {
      s << "; the closest: " << toString(closest->status) << ", overlap " << std::setprecision(2) << closest->overlap;
    }
    s << ")";
    result.message = s.str();
    return result;
  }
  candidate_ = best->T_W_C;
  confirmed_ = 1;
  result.track = *best;
  result.T_W_C = *candidate_;
  result.confirmed = 1;
  result.outcome = config_.confirm_frames <= 1 ? Outcome::kAccepted : Outcome::kConfirming;
  if (result.outcome == Outcome::kAccepted) searching_ = false;
  return result;
}

}  // namespace sdf_tracker
