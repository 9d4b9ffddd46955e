#include "sdf_tracker/cli/odometry_track.h"

#include <algorithm>
#include <stdexcept>

namespace sdf_tracker::tools {

OdometryTrack OdometryTrack::read(const std::string& path) {
  OdometryTrack track;
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
  return track;
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
