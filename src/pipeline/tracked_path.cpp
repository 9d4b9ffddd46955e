#include "sdf_tracker/pipeline/tracked_path.h"

#include "sdf_tracker/pipeline/pipeline.h"

namespace sdf_tracker {

void TrackedPath::add(double timestamp_s, int submap, const Eigen::Isometry3d& T_W_C, const Eigen::Isometry3d& T_map_C) {
  published_.push_back({timestamp_s, T_map_C});
  in_submaps_.emplace_back(submap, T_W_C);
}

void TrackedPath::detachFromSubmaps() {
  for (auto& pose : in_submaps_) pose.first = -1;
}

void TrackedPath::clear() {
  published_.clear();
  in_submaps_.clear();
}

std::vector<StampedPose> TrackedPath::placed(const SdfPipeline& pipeline) const {
  std::vector<StampedPose> poses = published_;
  for (size_t k = 0; k < poses.size(); ++k) {
    const auto& [submap, T_W_C] = in_submaps_[k];
    if (submap >= 0) poses[k].T_W_C = pipeline.submapPlace(submap).T_map_W * T_W_C;
  }
  return poses;
}

}  // namespace sdf_tracker
