#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/util/stamped_pose.h"

namespace sdf_tracker {

class SdfPipeline;

/// The camera's path as it was tracked, kept twice: each pose as it was published at the time (in
/// the map frame where the pose graph had its submap then), and in the frame of the submap it was
/// tracked in, so that it can be placed where the graph places that submap now. Without submaps
/// both are the same.
class TrackedPath {
 public:
  /// A tracked frame: `T_W_C` in the frame of `submap` (FrameReport::submap, SdfPipeline::pose()),
  /// `T_map_C` where it was published (SdfPipeline::mapPose()).
  void add(double timestamp_s, int submap, const Eigen::Isometry3d& T_W_C, const Eigen::Isometry3d& T_map_C);
  /// The map was cleared (a reset after failures): the poses so far keep the place they were
  /// published at, as no graph places their submaps any more.
  void detachFromSubmaps();
  void clear();
  bool empty() const { return published_.empty(); }
  size_t size() const { return published_.size(); }

  /// Each pose as it was published at the time.
  const std::vector<StampedPose>& published() const { return published_; }
  /// Each pose where `pipeline`'s pose graph places its submap now (as published when detached):
  /// the optimised path.
  std::vector<StampedPose> placed(const SdfPipeline& pipeline) const;

 private:
  std::vector<StampedPose> published_;
  /// Per pose: its submap (-1 once detached) and its pose in that submap's frame.
  std::vector<std::pair<int, Eigen::Isometry3d>> in_submaps_;
};

}  // namespace sdf_tracker
