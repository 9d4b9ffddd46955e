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

/// A squared Mahalanobis distance in three dimensions within which 95.4 % of a Gaussian's samples
/// lie, as within two standard deviations in one.
constexpr double kTwoSigmaSquared3d = 8.02;

/// The squared Mahalanobis distance of a camera position error (world axes) under the covariance
/// the tracker stated for the pose (TrackResult::covariance: its translation block).
double squaredMahalanobisOfPosition(const Eigen::Vector3d& error_m, const Eigen::Matrix<double, 6, 6>& covariance);

/// The figures of each frame's translation error against its true pose, and how many of those
/// errors lie within the two-sigma bound of the covariance stated for the frame (the covariance's
/// calibration: about 95 % when it is right, fewer when it claims too much).
struct SingleFrameErrors {
  /// `squared_mahalanobis`: squaredMahalanobisOfPosition of each of the errors.
  SingleFrameErrors(const std::vector<double>& errors_m, const std::vector<double>& squared_mahalanobis);
  evaluation::ErrorStats stats;
  double p90_m, p99_m;
  size_t over_1cm;
  size_t within_two_sigma;

  /// The summary's line ("tracker alone (--fuse-ground-truth): ...").
  std::string summaryLine(size_t without_ground_truth) const;
  /// The figures as a JSON object.
  std::string json() const;
};

}  // namespace sdf_tracker::tools
