#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/io/tum_sequence.h"

/// What sdf_tracker_offline --fuse-ground-truth measures: the tracker alone, each frame tracked from
/// its true pose against a map fused at true poses.
namespace sdf_tracker::tools {

/// Each frame's ground-truth pose (associated within 0.02 s) relative to the first associated
/// frame's, which is the tracker's start pose; none for frames without one. Throws
/// std::invalid_argument naming --fuse-ground-truth when the sequence has no usable ground truth.
std::vector<std::optional<Eigen::Isometry3d>> truePosesInFirstFrame(const TumSequence& sequence);

/// The figures of each frame's translation error against its true pose.
struct SingleFrameErrors {
  explicit SingleFrameErrors(const std::vector<double>& errors_m);
  evaluation::ErrorStats stats;
  double p90_m, p99_m;
  size_t over_1cm;

  /// The summary's line ("tracker alone (--fuse-ground-truth): ...").
  std::string summaryLine(size_t without_ground_truth) const;
  /// The figures as a JSON object.
  std::string json() const;
};

}  // namespace sdf_tracker::tools
