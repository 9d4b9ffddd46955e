#include "sdf_tracker/io/trajectory_file.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::io {

void writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses) {
  std::ostringstream s;
  s << "# timestamp tx ty tz qx qy qz qw (camera to world)\n" << std::fixed;
  for (const auto& pose : poses) {
    const Eigen::Quaterniond q(pose.T_W_C.linear());
    const Eigen::Vector3d t = pose.T_W_C.translation();
    s << std::setprecision(6) << pose.timestamp_s << std::setprecision(7) << ' ' << t.x() << ' ' << t.y() << ' '
      << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  writeTextFile(path, s.str());
}

std::vector<StampedPose> readTrajectory(const std::string& path) {
  std::ifstream in = openForReading(path);
  std::vector<StampedPose> poses;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    double v[8];
    for (double& value : v) {
      if (!(words >> value) || !std::isfinite(value)) {
        throwFileError(path, "line " + std::to_string(line_number) + " is not \"timestamp tx ty tz qx qy qz qw\": " + line);
      }
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (std::fabs(q.norm() - 1.0) > 1e-2) {
      throwFileError(path, "line " + std::to_string(line_number) + " has a quaternion of norm " + std::to_string(q.norm()));
    }
    StampedPose pose{v[0], Eigen::Isometry3d::Identity()};
    pose.T_W_C.linear() = q.normalized().toRotationMatrix();
    pose.T_W_C.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace sdf_tracker::io
