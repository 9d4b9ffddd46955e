#include "sdf_tracker/tracking/motion_model.h"

#include <cmath>

#include "sdf_tracker/util/se3.h"

namespace sdf_tracker {

void MotionModel::addTracked(double timestamp_s, const Eigen::Isometry3d& T_W_C) {
  history_.push_back({timestamp_s, T_W_C});
  if (history_.size() > 2) history_.pop_front();
}

Eigen::Isometry3d MotionModel::predict(double timestamp_s) const {
  if (history_.empty()) return Eigen::Isometry3d::Identity();
  const TimedPose& last = history_.back();
  if (history_.size() < 2) return last.T_W_C;
  const TimedPose& previous = history_.front();
  double ratio = 1.0;  // the time to predict over the time between the last two poses
  if (std::isfinite(timestamp_s) && std::isfinite(previous.timestamp_s) && std::isfinite(last.timestamp_s)) {
    const double gap_s = timestamp_s - last.timestamp_s, last_gap_s = last.timestamp_s - previous.timestamp_s;
    if (!(gap_s > 0.0 && last_gap_s > 0.0) || gap_s > max_gap_s_) return last.T_W_C;
    ratio = gap_s / last_gap_s;
  }
  return last.T_W_C * expSe3(ratio * logSe3(previous.T_W_C.inverse() * last.T_W_C));
}

}  // namespace sdf_tracker
