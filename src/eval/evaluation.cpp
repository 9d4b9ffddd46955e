#include "sdf_tracker/eval/evaluation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <utility>

#include <Eigen/Geometry>

#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/util/se3.h"

namespace sdf_tracker::evaluation {

ErrorStats summarize(std::vector<double> errors) {
  ErrorStats stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
    stats.max = std::max(stats.max, e);
  }
  stats.mean = sum / errors.size();
  stats.rmse = std::sqrt(sum_sq / errors.size());
  stats.median = percentile(std::move(errors), 0.5);
  return stats;
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const double rank = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(rank));
  std::nth_element(values.begin(), values.begin() + below, values.end());
  const double lower = values[below];
  if (below + 1 >= values.size()) return lower;
  // The next rank up is the smallest of those after `below` (nth_element left them unordered).
  const double upper = *std::min_element(values.begin() + below + 1, values.end());
  return lower + (rank - static_cast<double>(below)) * (upper - lower);
}

std::vector<std::pair<size_t, size_t>> associate(const std::vector<io::StampedPose>& estimate,
                                                 const std::vector<io::StampedPose>& ground_truth,
                                                 double max_difference_s) {
  std::vector<double> estimate_s, ground_truth_s;
  for (const io::StampedPose& pose : estimate) estimate_s.push_back(pose.timestamp_s);
  for (const io::StampedPose& pose : ground_truth) ground_truth_s.push_back(pose.timestamp_s);
  const std::vector<long> partner = associateByTime(estimate_s, ground_truth_s, max_difference_s);
  std::vector<std::pair<size_t, size_t>> matches;
  for (size_t i = 0; i < partner.size(); ++i) {
    if (partner[i] >= 0) matches.emplace_back(i, static_cast<size_t>(partner[i]));
  }
  return matches;
}

AteResult computeAte(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& ground_truth,
                     double max_difference_s) {
  const auto matches = associate(estimate, ground_truth, max_difference_s);
  if (matches.size() < 3) {
    throw std::invalid_argument("only " + std::to_string(matches.size()) +
                                " estimated poses have a ground-truth pose within " +
                                std::to_string(max_difference_s) + " s; ATE needs at least 3");
  }
  Eigen::Matrix3Xd est(3, matches.size()), gt(3, matches.size());
  for (size_t m = 0; m < matches.size(); ++m) {
    est.col(m) = estimate[matches[m].first].T_W_C.translation();
    gt.col(m) = ground_truth[matches[m].second].T_W_C.translation();
  }
  AteResult result;
  result.T_gt_est.matrix() = Eigen::umeyama(est, gt, false);
  for (size_t m = 0; m < matches.size(); ++m) {
    const Eigen::Vector3d aligned = result.T_gt_est * est.col(m);
    result.timestamps_s.push_back(estimate[matches[m].first].timestamp_s);
    result.errors_m.push_back((aligned - gt.col(m)).norm());
    result.aligned_estimate.push_back(aligned);
    result.ground_truth.push_back(gt.col(m));
  }
  result.translation_m = summarize(result.errors_m);
  return result;
}

size_t LocalisationResult::within(double translation_m, double rotation_rad) const {
  size_t n = 0;
  for (size_t i = 0; i < timestamps_s.size(); ++i) {
    n += translation_errors_m[i] <= translation_m && rotation_errors_rad[i] <= rotation_rad;
  }
  return n;
}

LocalisationResult computeLocalisation(const std::vector<io::StampedPose>& estimate,
                                       const std::vector<io::StampedPose>& ground_truth,
                                       const std::vector<io::StampedPose>& reference, double max_difference_s) {
  LocalisationResult result;
  // The rigid alignment of whole poses: each pose is its position and two points 0.5 m along its
  // viewing and right axes, so that orientations are aligned as well as positions.
  const auto matches = associate(reference, ground_truth, max_difference_s);
  if (matches.size() < 3) {
    throw std::invalid_argument("only " + std::to_string(matches.size()) + " reference poses have a ground-truth "
                                "pose within " + std::to_string(max_difference_s) + " s; the alignment needs 3");
  }
  Eigen::Matrix3Xd in_frame(3, 3 * matches.size()), in_gt(3, 3 * matches.size());
  for (size_t m = 0; m < matches.size(); ++m) {
    const Eigen::Isometry3d& a = reference[matches[m].first].T_W_C;
    const Eigen::Isometry3d& b = ground_truth[matches[m].second].T_W_C;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d offset = k == 0 ? Eigen::Vector3d(Eigen::Vector3d::Zero())
                                            : Eigen::Vector3d(0.5 * Eigen::Vector3d::Unit(k == 1 ? 2 : 0));
      in_frame.col(3 * m + k) = a * offset;
      in_gt.col(3 * m + k) = b * offset;
    }
  }
  result.T_frame_gt.matrix() = Eigen::umeyama(in_gt, in_frame, false);
  for (const auto& [e, g] : associate(estimate, ground_truth, max_difference_s)) {
    const Eigen::Isometry3d truth = result.T_frame_gt * ground_truth[g].T_W_C;
    const Eigen::Isometry3d error = truth.inverse() * estimate[e].T_W_C;
    result.timestamps_s.push_back(estimate[e].timestamp_s);
    result.translation_errors_m.push_back(error.translation().norm());
    result.rotation_errors_rad.push_back(Eigen::AngleAxisd(error.rotation()).angle());
  }
  return result;
}

RpeResult computeRpe(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& ground_truth,
                     double window_s, double max_difference_s) {
  const auto matches = associate(estimate, ground_truth, max_difference_s);
  std::vector<double> translation_errors, rotation_errors;
  size_t j = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    const double t_i = estimate[matches[i].first].timestamp_s;
    j = std::max(j, i + 1);
    while (j < matches.size() && estimate[matches[j].first].timestamp_s < t_i + window_s) ++j;
    if (j >= matches.size()) break;
    const auto& e_i = estimate[matches[i].first];
    const auto& e_j = estimate[matches[j].first];
    const auto& g_i = ground_truth[matches[i].second];
    const auto& g_j = ground_truth[matches[j].second];
    const double dt = g_j.timestamp_s - g_i.timestamp_s;
    const Eigen::Isometry3d error =
        (g_i.T_W_C.inverse() * g_j.T_W_C).inverse() * (e_i.T_W_C.inverse() * e_j.T_W_C);
    translation_errors.push_back(error.translation().norm() / dt);
    rotation_errors.push_back(rotationAngle(error) * 180.0 / M_PI / dt);
  }
  return {summarize(translation_errors), summarize(rotation_errors)};
}

}  // namespace sdf_tracker::evaluation
