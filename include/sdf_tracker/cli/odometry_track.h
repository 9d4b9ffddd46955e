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
  /// Faster than this between two poses, the odometry jumped (a reset, a glitch): said, as no
  /// robot or hand-held camera moves so.
  static constexpr double kMaxPlausibleSpeed_mps = 10.0;
  size_t size() const { return poses_.size(); }

  /// Its steps faster than kMaxPlausibleSpeed_mps, said in words ("--odometry FILE: 2 jumps, the
  /// largest 100 m in 0.033 s at 12.5 s"), or "" when there are none.
  const std::string& jumps() const { return jumps_; }
  /// Throws std::invalid_argument naming the file and both time spans when at() gives a pose for
  /// none of `timestamps_s` (another clock, or gaps everywhere); returns how many it covers.
  size_t requireCoverage(const std::vector<double>& timestamps_s) const;

 private:
  std::string path_;
  std::vector<io::StampedPose> poses_;
  std::string jumps_;
};

}  // namespace sdf_tracker::tools
