#pragma once

#include <string>
#include <vector>

#include "sdf_tracker/util/stamped_pose.h"

namespace sdf_tracker::io {

using sdf_tracker::StampedPose;

/// TUM trajectory format: "timestamp tx ty tz qx qy qz qw" per line, '#' comments.
void writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses);
std::vector<StampedPose> readTrajectory(const std::string& path);

}  // namespace sdf_tracker::io
