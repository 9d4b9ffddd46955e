#include "sdf_tracker/cli/odometry_track.h"

#include <algorithm>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace sdf_tracker::tools {

OdometryTrack OdometryTrack::read(const std::string& path) {
  OdometryTrack track;
  track.path_ = path;
  track.poses_ = io::readTrajectory(path);
  if (track.poses_.size() < 2) {
    throw std::invalid_argument("--odometry " + path + ": " + std::to_string(track.poses_.size()) +
                                " poses; an odometry needs two at least");
  }
  for (size_t i = 1; i < track.poses_.size(); ++i) {
    if (!(track.poses_[i].timestamp_s > track.poses_[i - 1].timestamp_s)) {
      throw std::invalid_argument("--odometry " + path + ": the stamps do not increase at pose " + std::to_string(i + 1) +
                                  " (" + std::to_string(track.poses_[i].timestamp_s) + " after " +
                                  std::to_string(track.poses_[i - 1].timestamp_s) + ")");
    }
  }
  size_t jumps = 0;
  double largest_m = 0.0, largest_dt_s = 0.0, largest_at_s = 0.0;
  for (size_t i = 1; i < track.poses_.size(); ++i) {
    const double dt_s = track.poses_[i].timestamp_s - track.poses_[i - 1].timestamp_s;
    const double step_m = (track.poses_[i].T_W_C.translation() - track.poses_[i - 1].T_W_C.translation()).norm();
    if (step_m <= kMaxPlausibleSpeed_mps * dt_s) continue;
    ++jumps;
    if (step_m > largest_m) {
      largest_m = step_m;
      largest_dt_s = dt_s;
      largest_at_s = track.poses_[i].timestamp_s;
    }
  }
  if (jumps > 0) {
    std::ostringstream s;
    s << std::setprecision(4) << "--odometry " << path << ": " << jumps << (jumps == 1 ? " jump" : " jumps")
      << " faster than " << kMaxPlausibleSpeed_mps << " m/s, the largest " << largest_m << " m in " << largest_dt_s
      << " s at " << std::fixed << std::setprecision(3) << largest_at_s
      << " s (a reset or a glitch of the odometry? the tracker takes it as a prediction only)";
    track.jumps_ = s.str();
  }
  return track;
}

size_t OdometryTrack::requireCoverage(const std::vector<double>& timestamps_s) const {
  const size_t covered = static_cast<size_t>(
      std::count_if(timestamps_s.begin(), timestamps_s.end(), [this](double t) { return at(t).has_value(); }));
  if (covered == 0 && !timestamps_s.empty()) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(3) << "--odometry " << path_ << ": its " << poses_.size() << " poses ("
      << poses_.front().timestamp_s << " .. " << poses_.back().timestamp_s << " s) give a pose for none of the "
      << timestamps_s.size() << " frames (" << timestamps_s.front() << " .. " << timestamps_s.back()
      << " s): another clock, or gaps longer than " << kMaxGap_s << " s everywhere";
    throw std::invalid_argument(s.str());
  }
  return covered;
}

std::optional<Eigen::Isometry3d> OdometryTrack::at(double timestamp_s) const {
  const auto after = std::lower_bound(poses_.begin(), poses_.end(), timestamp_s,
                                      [](const io::StampedPose& p, double t) { return p.timestamp_s < t; });
  if (after == poses_.end()) return std::nullopt;
  if (after->timestamp_s == timestamp_s) return after->T_W_C;
  if (after == poses_.begin()) return std::nullopt;
  const io::StampedPose& before = *(after - 1);
  const double gap_s = after->timestamp_s - before.timestamp_s;
  if (gap_s > kMaxGap_s) return std::nullopt;
  const double s = (timestamp_s - before.timestamp_s) / gap_s;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = (1.0 - s) * before.T_W_C.translation() + s * after->T_W_C.translation();
  T.linear() = Eigen::Quaterniond(before.T_W_C.linear()).slerp(s, Eigen::Quaterniond(after->T_W_C.linear()))
                   .toRotationMatrix();
  return T;
}

}  // namespace sdf_tracker::tools
