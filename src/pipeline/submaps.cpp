#include "sdf_tracker/pipeline/submaps.h"

#include <cmath>

#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

std::vector<std::string> SubmapConfig::validate() const {
  Violations v;
  v.requireNonNegative("max_distance_m", max_distance_m);
  v.requireInRange("max_rotation_deg", max_rotation_deg, 0.1, 180.0);
  v.requireInRange("handover_frames", handover_frames, 1, 1000);
  v.requireNonNegative("track_recent_m", track_recent_m);
  v.requirePositive("recent_settled_weight", recent_settled_weight);
  return v.list();
}

bool leavesSubmap(const SubmapConfig& config, const Eigen::Isometry3d& T_W_anchor, const Eigen::Isometry3d& T_W_C) {
  if (!config.enabled()) return false;
  const Eigen::Isometry3d motion = T_W_anchor.inverse() * T_W_C;
  return motion.translation().norm() > config.max_distance_m || rotationAngle(motion) > config.max_rotation_deg * M_PI / 180.0;
}

}  // namespace sdf_tracker
