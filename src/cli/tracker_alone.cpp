#include "sdf_tracker/cli/tracker_alone.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "sdf_tracker/cli/report.h"

namespace sdf_tracker::tools {

std::vector<std::optional<Eigen::Isometry3d>> truePosesInFirstFrame(const TumSequence& sequence) {
  if (sequence.groundTruth().empty()) {
    throw std::invalid_argument("--fuse-ground-truth needs the sequence's groundtruth.txt, which is missing or empty");
  }
  std::vector<io::StampedPose> frames;
  for (size_t i = 0; i < sequence.size(); ++i) frames.push_back({sequence.timestamp(i), Eigen::Isometry3d::Identity()});
  std::vector<std::optional<Eigen::Isometry3d>> poses(sequence.size());
  std::optional<Eigen::Isometry3d> first_inverse;
  for (const auto& [frame, truth] : evaluation::associate(frames, sequence.groundTruth())) {
    const Eigen::Isometry3d& T_gt = sequence.groundTruth()[truth].T_W_C;
    if (!first_inverse) first_inverse = T_gt.inverse();
    poses[frame] = *first_inverse * T_gt;
  }
  if (!first_inverse) {
    throw std::invalid_argument("--fuse-ground-truth: no frame has a ground-truth pose within 0.02 s of its timestamp");
  }
  return poses;
}

double squaredMahalanobisOfPosition(const Eigen::Vector3d& error_m, const Eigen::Matrix<double, 6, 6>& covariance) {
  const Eigen::LLT<Eigen::Matrix3d> llt(covariance.bottomRightCorner<3, 3>());
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();  // not positive definite
  return error_m.dot(llt.solve(error_m));
}

SingleFrameErrors::SingleFrameErrors(const std::vector<double>& errors_m, const std::vector<double>& squared_mahalanobis)
    : stats(evaluation::summarize(errors_m)),
      p90_m(evaluation::percentile(errors_m, 0.9)),
      p99_m(evaluation::percentile(errors_m, 0.99)),
      over_1cm(std::count_if(errors_m.begin(), errors_m.end(), [](double e) { return e > 0.01; })),
      within_two_sigma(std::count_if(squared_mahalanobis.begin(), squared_mahalanobis.end(),
                                     [](double d2) { return d2 <= kTwoSigmaSquared3d; })) {}

std::string SingleFrameErrors::summaryLine(size_t without_ground_truth) const {
  std::ostringstream out;
  out << "tracker alone (--fuse-ground-truth): ";
  if (stats.count == 0) {
    out << "no frame tracked\n";
    return out.str();
  }
  out << std::setprecision(3) << "translation error per frame (mm) mean " << 1000 * stats.mean << ", median "
      << 1000 * stats.median << ", p90 " << 1000 * p90_m << ", p99 " << 1000 * p99_m << ", max " << 1000 * stats.max
      << "; over 1 cm: " << over_1cm << " of " << stats.count << " frames; within the stated covariance's 2 sigma: "
      << std::lround(100.0 * within_two_sigma / stats.count) << " % (95 % if it is calibrated)";
  if (without_ground_truth > 0) out << "; " << without_ground_truth << " frames without ground truth skipped";
  out << "\n";
  return out.str();
}

std::string SingleFrameErrors::json() const {
  std::ostringstream out;
  out << "{\"rmse\": " << jsonNumber(stats.rmse) << ", \"mean\": " << jsonNumber(stats.mean) << ", \"median\": "
      << jsonNumber(stats.median) << ", \"p90\": " << jsonNumber(p90_m) << ", \"max\": " << jsonNumber(stats.max)
      << ", \"frames_over_1cm\": " << over_1cm << ", \"frames_within_two_sigma\": " << within_two_sigma
      << ", \"frames\": " << stats.count << "}";
  return out.str();
}

}  // namespace sdf_tracker::tools
