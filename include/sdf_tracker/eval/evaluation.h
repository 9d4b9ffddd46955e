#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/io/trajectory_file.h"

/// Trajectory error metrics as defined by the TUM RGB-D benchmark (Sturm et al., IROS 2012).
namespace sdf_tracker::evaluation {

struct ErrorStats {
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
  size_t count = 0;
};

ErrorStats summarize(std::vector<double> errors);

/// The q-quantile (0..1) of `values`, interpolated between the two ranks around q (n - 1)
/// (numpy's default: the median of two values is their mean); 0 for none.
double percentile(std::vector<double> values, double q);

/// Pairs (estimate index, ground-truth index) whose timestamps are closest to each other and
/// within max_difference_s, each index used at most once, in time order.
std::vector<std::pair<size_t, size_t>> associate(const std::vector<io::StampedPose>& estimate,
                                                 const std::vector<io::StampedPose>& ground_truth,
                                                 double max_difference_s = 0.02);

/// Absolute trajectory error after the rigid (rotation + translation, no scale) alignment of the
/// estimate's positions onto the ground truth's that minimises the squared error.
struct AteResult {
  ErrorStats translation_m;
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  ///< the alignment
  std::vector<double> timestamps_s;
  std::vector<double> errors_m;
  std::vector<Eigen::Vector3d> aligned_estimate;
  std::vector<Eigen::Vector3d> ground_truth;
};
/// Throws std::invalid_argument when fewer than 3 poses associate.
AteResult computeAte(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& ground_truth,
                     double max_difference_s = 0.02);

/// Relative pose error over a fixed time window, per second of that window.
struct RpeResult {
  ErrorStats translation_m_per_s;
  ErrorStats rotation_deg_per_s;
};
/// Empty stats (count 0) when the trajectory is shorter than the window.
RpeResult computeRpe(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& ground_truth,
                     double window_s = 1.0, double max_difference_s = 0.02);

/// How well an estimate that lives in a given frame (a map's) localises the camera there: the
/// ground truth is brought into that frame by the rigid alignment of `reference`'s poses onto it
/// (positions and orientations; `reference` is a trajectory in the same frame, the session that
/// built the map), and the estimate is compared with it pose by pose, not aligned itself.
struct LocalisationResult {
  std::vector<double> timestamps_s;
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_rad;
  Eigen::Isometry3d T_frame_gt = Eigen::Isometry3d::Identity();  ///< ground truth into the frame
  /// Poses within both bounds.
  size_t within(double translation_m, double rotation_rad) const;
};
/// Throws std::invalid_argument when fewer than 3 reference poses associate.
LocalisationResult computeLocalisation(const std::vector<io::StampedPose>& estimate,
                                       const std::vector<io::StampedPose>& ground_truth,
                                       const std::vector<io::StampedPose>& reference, double max_difference_s = 0.02);

}  // namespace sdf_tracker::evaluation
