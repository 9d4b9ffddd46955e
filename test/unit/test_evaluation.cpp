#include <gtest/gtest.h>

#include "sdf_tracker/eval/evaluation.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

std::vector<io::StampedPose> wavyTrajectory(double t0, int n) {
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + i / 30.0;
    poses.push_back({t, synthetic::cameraPose(synthetic::Motion::kDesk, t - t0, n / 30.0)});
  }
  return poses;
}

TEST(Evaluation, RigidlyMovedCopyHasZeroError) {
  const auto gt = wavyTrajectory(100.0, 90);
  auto estimate = gt;
  const Eigen::Isometry3d offset = test::perturbed(Eigen::Isometry3d::Identity(), 1.5, 0.7);
  for (auto& p : estimate) p.T_W_C = offset * p.T_W_C;
  const auto ate = evaluation::computeAte(estimate, gt);
  EXPECT_EQ(ate.translation_m.count, 90u);
  EXPECT_LT(ate.translation_m.rmse, 1e-9);
  const auto rpe = evaluation::computeRpe(estimate, gt);
  EXPECT_GT(rpe.translation_m_per_s.count, 50u);
  EXPECT_LT(rpe.translation_m_per_s.rmse, 1e-9);
  EXPECT_LT(rpe.rotation_deg_per_s.rmse, 1e-6);
}

TEST(Evaluation, ConstantOffsetAlongTheCameraShowsInAte) {
  const auto gt = wavyTrajectory(0.0, 60);
  auto estimate = gt;
  // Every other position 1 cm off along x: no rigid motion removes a zig-zag, and the best
  // alignment splits it, so every pose is off by about half of it.
  for (size_t i = 0; i < estimate.size(); i += 2) estimate[i].T_W_C.translation().x() += 0.01;
  const auto ate = evaluation::computeAte(estimate, gt);
  EXPECT_NEAR(ate.translation_m.rmse, 0.005, 0.001);
  EXPECT_LE(ate.translation_m.max, 0.01);
}

TEST(Evaluation, SummaryStatistics) {
  const auto s = evaluation::summarize({3.0, 4.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(30.0 / 4.0));
}

TEST(Evaluation, PercentilesInterpolateBetweenRanks) {
  EXPECT_EQ(evaluation::percentile({}, 0.5), 0.0);
  EXPECT_EQ(evaluation::percentile({7.0}, 0.95), 7.0);
  EXPECT_DOUBLE_EQ(evaluation::percentile({4.0, 2.0}, 0.5), 3.0) << "the median of two is their mean, not the larger";
  EXPECT_DOUBLE_EQ(evaluation::percentile({3.0, 1.0, 2.0}, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(evaluation::percentile({0.0, 10.0, 20.0, 30.0, 40.0}, 0.95), 38.0);
  EXPECT_EQ(evaluation::percentile({5.0, 1.0, 9.0}, 1.0), 9.0);
  EXPECT_EQ(evaluation::percentile({5.0, 1.0, 9.0}, 0.0), 1.0);
}

TEST(Evaluation, AssociatesNearestTimestampsWithinTolerance) {
  std::vector<io::StampedPose> a, b;
  for (double t : {0.0, 0.1, 0.2, 0.5}) a.push_back({t, Eigen::Isometry3d::Identity()});
  for (double t : {0.005, 0.11, 0.19, 0.3}) b.push_back({t, Eigen::Isometry3d::Identity()});
  const auto matches = evaluation::associate(a, b, 0.02);
  ASSERT_EQ(matches.size(), 3u);
  EXPECT_EQ(matches[0].first, 0u);
  EXPECT_EQ(matches[0].second, 0u);
  EXPECT_EQ(matches[2].first, 2u);
  EXPECT_EQ(matches[2].second, 2u);
  EXPECT_THROW(evaluation::computeAte(a, {}), std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
