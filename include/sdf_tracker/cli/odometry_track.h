#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sdf_tracker/io/trajectory_file.h"

namespace sdf_tracker::tools {

/// Another odometry beside the tracker for the offline runner (--odometry): the camera's poses in
/// that odometry's frame, a TUM trajectory (e.g. a sequence's odometry.txt, written by
/// sdf_tracker_synth --odometry), looked up at each frame's stamp.
class OdometryTrack {
 public:
  /// The poses of `path` (io::readTrajectory); throws std::invalid_argument naming the file when
  /// it holds fewer than two poses or stamps that do not increase.
  static OdometryTrack read(const std::string& path);

  /// The pose at `timestamp_s`, between the two poses around it (position linear, rotation
  /// slerp); none outside the track or across a gap longer than kMaxGap_s.
  std::optional<Eigen::Isometry3d> at(double timestamp_s) const;

  static constexpr double kMaxGap_s = 0.1;
  size_t size() const { return poses_.size(); }

 private:
  std::vector<io::StampedPose> poses_;
};

}  // namespace sdf_tracker::tools
