#pragma once

#include <deque>

#include <Eigen/Geometry>

namespace sdf_tracker {

/// Constant-velocity prediction of the camera's next pose from its last two tracked poses: the
/// motion between them, as a constant twist in the camera's frame, scaled to the time since the
/// last one (so that dropped frames are bridged).
///
/// Measured and not adopted (bench/results/2026-11-23_walk_drift.md): a velocity averaged over
/// more frames, meant to keep one poorly constrained frame from setting it; on the house walk it
/// made the drift worse. A Gaussian prior toward the prediction whose strength follows the measured
/// innovation (bench/results/2026-11-23_motion_prior.md): it lowers the walk's translational drift
/// per second but not its ATE, and costs real data once strong.
class MotionModel {
 public:
  /// No prediction across more than max_gap_s.
  explicit MotionModel(double max_gap_s) : max_gap_s_(max_gap_s) {}

  /// A tracked pose at timestamp_s (NaN: frames count as evenly spaced).
  void addTracked(double timestamp_s, const Eigen::Isometry3d& T_W_C);
  /// Forget the history (after a failed frame, a reset or a new map).
  void clear() { history_.clear(); }

  /// The pose at timestamp_s; the last tracked pose when there is only one, when the times do
  /// not increase, or across a gap longer than max_gap_s. Identity before any pose.
  Eigen::Isometry3d predict(double timestamp_s) const;

 private:
  struct TimedPose {
    double timestamp_s;
    Eigen::Isometry3d T_W_C;
  };
  double max_gap_s_;
  std::deque<TimedPose> history_;  ///< oldest first, at most two
};

}  // namespace sdf_tracker
