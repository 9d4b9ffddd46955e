// The pose graph on its own: a square of four submaps whose odometry drifts, closed by a loop;
// a wrong loop among right ones rejected; edges and options that make no sense refused; the
// solver that runs it off the caller's thread.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <vector>

#include "sdf_tracker/graph/background_solver.h"
#include "sdf_tracker/graph/pose_graph.h"

namespace sdf_tracker {
namespace {

Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

double rotationDegrees(const Eigen::Isometry3d& T) { return Eigen::AngleAxisd(T.rotation()).angle() * 180.0 / M_PI; }

/// Information of a pose measured to sigma_m in translation and sigma_rad in rotation.
PoseInformation information(double sigma_m, double sigma_rad) {
  PoseInformation info = PoseInformation::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

/// The corners of a 2 m square walked anticlockwise, turning 90 degrees at each: node i at corner i.
std::vector<Eigen::Isometry3d> squareTruth() {
  return {pose(0, 0, 0, 0), pose(2, 0, 0, M_PI / 2), pose(2, 2, 0, M_PI), pose(0, 2, 0, 3 * M_PI / 2)};
}

/// The square as tracking would give it: each step's odometry turns 2 degrees too far and goes 3 %
/// too far, and the nodes are where that odometry puts them; then the loop from corner 3 back to
/// corner 0, measured right (as verified tracking against the first submap gives it).
PoseGraph driftingSquare(const std::vector<Eigen::Isometry3d>& truth) {
  PoseGraph graph;
  Eigen::Isometry3d dead_reckoned = truth[0];
  graph.addNode(dead_reckoned);
  for (int i = 0; i + 1 < 4; ++i) {
    Eigen::Isometry3d step = truth[i].inverse() * truth[i + 1];
    step.translation() *= 1.03;
    step = step * pose(0, 0, 0, 2.0 * M_PI / 180.0);
    dead_reckoned = dead_reckoned * step;
    graph.addNode(dead_reckoned);
    graph.addEdge({i, i + 1, step, information(0.02, 0.01), PoseEdgeKind::kOdometry});
  }
  graph.addEdge({3, 0, truth[3].inverse() * truth[0], information(0.01, 0.005), PoseEdgeKind::kLoop});
  return graph;
}

TEST(PoseGraph, AnEdgesLeastCertainDirectionIsWhatItsSigmaSays) {
  // Translation sigmas 1, 2 and 5 cm and rotation 0.5, 1 and 3 degrees, along axes turned away
  // from the edge's: the largest of each, whatever the axes.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).toRotationMatrix();
  const double rad = M_PI / 180.0;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  covariance.topLeftCorner<3, 3>() = R * Eigen::Vector3d(1e-4, 4e-4, 25e-4).asDiagonal() * R.transpose();
  covariance.bottomRightCorner<3, 3>() =
      R.transpose() * Eigen::Vector3d(std::pow(0.5 * rad, 2), std::pow(rad, 2), std::pow(3.0 * rad, 2)).asDiagonal() * R;
  const PoseSigma sigma = leastCertainSigma(covariance.inverse());
  EXPECT_NEAR(sigma.m, 0.05, 1e-9);
  EXPECT_NEAR(sigma.deg, 3.0, 1e-9);
  // A direction held by nothing shows as such.
  covariance(0, 0) = 1e6;
  EXPECT_GT(leastCertainSigma(covariance.inverse()).m, 900.0);
}

TEST(PoseGraph, ConsistentEdgesFromADriftedStartGiveTheTruePosesExactly) {
  const std::vector<Eigen::Isometry3d> truth = squareTruth();
  PoseGraph graph;
  for (int i = 0; i < 4; ++i) graph.addNode(truth[i] * pose(0.1 * i, -0.05 * i, 0.02 * i, 0.05 * i));
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    graph.addEdge({i, j, truth[i].inverse() * truth[j], information(0.02, 0.01),
                   j == 0 ? PoseEdgeKind::kLoop : PoseEdgeKind::kOdometry});
  }
  const PoseGraphSolution solution = graph.optimise();
  ASSERT_TRUE(solution.converged);
  EXPECT_TRUE(solution.rejected_loops.empty());
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT((solution.poses[i].translation() - truth[i].translation()).norm(), 1e-6) << "node " << i;
    EXPECT_LT(rotationDegrees(solution.poses[i].inverse() * truth[i]), 1e-5) << "node " << i;
  }
  EXPECT_LT(solution.final_cost, 1e-12);
}

TEST(PoseGraph, ALoopClosesASquareWhoseOdometryDrifted) {
  const std::vector<Eigen::Isometry3d> truth = squareTruth();
  const PoseGraph graph = driftingSquare(truth);
  // Before: the last corner is where drift put it.
  const Eigen::Isometry3d loop_before = graph.poses()[3].inverse() * graph.poses()[0];
  const Eigen::Isometry3d loop_truth = truth[3].inverse() * truth[0];
  const double gap_before_m = (loop_before.inverse() * loop_truth).translation().norm();
  EXPECT_GT(gap_before_m, 0.15);

  const PoseGraphSolution solution = graph.optimise();
  ASSERT_TRUE(solution.converged);
  EXPECT_TRUE(solution.rejected_loops.empty());
  // After: the loop is closed, to the share of the drift its information leaves it (its rotation
  // sigma is half the odometry's: about a tenth of the 6 degrees is left on it), and the error that
  // grew along the path is spread back over it: the last corner, worst before, is pulled in most
  // (the odometry's 3 % in length is as much the loop's as its turning, so the corners keep some).
  const Eigen::Isometry3d loop_after = solution.poses[3].inverse() * solution.poses[0];
  const double rotation_before_deg = rotationDegrees(loop_before.inverse() * loop_truth);
  EXPECT_NEAR(rotation_before_deg, 6.0, 1e-6);
  EXPECT_LT((loop_after.inverse() * loop_truth).translation().norm(), 0.1 * gap_before_m);
  const double rotation_after_deg = rotationDegrees(loop_after.inverse() * loop_truth);
  std::printf("[ figures  ] loop: %.3f m and %.2f degrees open before, %.3f m and %.2f after\n", gap_before_m,
              rotation_before_deg, (loop_after.inverse() * loop_truth).translation().norm(), rotation_after_deg);
  EXPECT_LT(rotation_after_deg, 0.1 * rotation_before_deg);
  EXPECT_EQ(solution.poses[0].matrix(), graph.poses()[0].matrix()) << "node 0 holds the map frame";
  double squares_before = 0.0, squares_after = 0.0, last_before_m = 0.0, last_after_m = 0.0;
  for (int i = 1; i < 4; ++i) {
    const double before_m = (graph.poses()[i].translation() - truth[i].translation()).norm();
    const double after_m = (solution.poses[i].translation() - truth[i].translation()).norm();
    std::printf("[ figures  ] corner %d: %.3f m off before, %.3f m after\n", i, before_m, after_m);
    squares_before += before_m * before_m, squares_after += after_m * after_m;
    last_before_m = before_m, last_after_m = after_m;
  }
  EXPECT_LT(last_after_m, 0.25 * last_before_m);
  EXPECT_LT(std::sqrt(squares_after), 0.7 * std::sqrt(squares_before));
  EXPECT_LT(solution.final_cost, solution.initial_cost);
}

TEST(PoseGraph, AWrongLoopAmongRightOnesIsRejectedAndLeavesNoTrace) {
  const std::vector<Eigen::Isometry3d> truth = squareTruth();
  PoseGraph right = driftingSquare(truth);
  right.addEdge({2, 0, truth[2].inverse() * truth[0], information(0.01, 0.005), PoseEdgeKind::kLoop});
  PoseGraph with_wrong = right;
  // A place that looked alike: corner 3 taken for a spot 1 m away, turned 30 degrees.
  with_wrong.addEdge({3, 1, pose(1.0, 0.0, 0.0, M_PI / 6) * (truth[3].inverse() * truth[1]), information(0.01, 0.005),
                      PoseEdgeKind::kLoop});
  const int wrong_edge = static_cast<int>(with_wrong.edges().size()) - 1;

  const PoseGraphSolution expected = right.optimise();
  const PoseGraphSolution solution = with_wrong.optimise();
  ASSERT_TRUE(solution.converged);
  ASSERT_EQ(solution.rejected_loops, std::vector<int>{wrong_edge});
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT((solution.poses[i].translation() - expected.poses[i].translation()).norm(), 1e-6) << "node " << i;
    EXPECT_LT(rotationDegrees(solution.poses[i].inverse() * expected.poses[i]), 1e-5) << "node " << i;
  }
  // Both right loops are kept, and each agrees within its bound.
  for (size_t e = 0; e + 1 < with_wrong.edges().size(); ++e) {
    EXPECT_LT(PoseGraph::whitenedResidual(with_wrong.edges()[e], solution.poses).squaredNorm(),
              PoseGraphOptions().loop_rejection_chi2)
        << "edge " << e;
  }
}

TEST(PoseGraph, AnEdgeOrOptionThatMakesNoSenseIsRefusedByName) {
  PoseGraph graph;
  graph.addNode(Eigen::Isometry3d::Identity());
  graph.addNode(pose(1, 0, 0, 0));
  auto message = [&graph](const PoseEdge& edge) {
    try {
      graph.addEdge(edge);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({0, 2, pose(1, 0, 0, 0), information(0.1, 0.1), PoseEdgeKind::kOdometry}),
            "odometry edge 0 -> 2: the graph has nodes 0 to 1");
  EXPECT_EQ(message({1, 1, pose(1, 0, 0, 0), information(0.1, 0.1), PoseEdgeKind::kLoop}),
            "loop edge 1 -> 1: an edge joins two different nodes");
  PoseInformation singular = information(0.1, 0.1);
  singular(5, 5) = 0.0;
  EXPECT_EQ(message({0, 1, pose(1, 0, 0, 0), singular, PoseEdgeKind::kLoop}),
            "loop edge 0 -> 1: the information matrix is not positive definite");
  Eigen::Isometry3d not_finite = pose(1, 0, 0, 0);
  not_finite.translation().x() = std::nan("");
  EXPECT_EQ(message({0, 1, not_finite, information(0.1, 0.1), PoseEdgeKind::kOdometry}),
            "odometry edge 0 -> 1: the relative pose is not finite");
  EXPECT_TRUE(graph.edges().empty());

  PoseGraphOptions options;
  options.loop_loss_sigma = -1.0;
  try {
    graph.optimise(options);
    FAIL() << "negative loop_loss_sigma accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "pose graph options: loop_loss_sigma must be > 0, got -1; ");
  }
}

TEST(BackgroundGraphSolver, GivesWhatASolveInPlaceGivesAndTheNewestGraphLast) {
  BackgroundGraphSolver solver;
  EXPECT_FALSE(solver.busy());
  EXPECT_FALSE(solver.poll().has_value()) << "nothing was handed over";
  EXPECT_FALSE(solver.finish().has_value());

  const std::vector<Eigen::Isometry3d> truth = squareTruth();
  const PoseGraph square = driftingSquare(truth);
  PoseGraph with_wrong_loop = square;
  with_wrong_loop.addEdge({2, 0, pose(0.5, 0.5, 0, 0.3), information(0.01, 0.005), PoseEdgeKind::kLoop});
  // The second graph is handed over while the first may still run: both are solved, in order.
  solver.solve(square);
  solver.solve(with_wrong_loop);
  EXPECT_TRUE(solver.busy());
  const std::optional<BackgroundGraphSolver::Result> last = solver.finish();
  EXPECT_FALSE(solver.busy());
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->graph.edges().size(), with_wrong_loop.edges().size()) << "the newest graph is solved last";
  const PoseGraphSolution in_place = with_wrong_loop.optimise();
  ASSERT_EQ(last->solution.poses.size(), in_place.poses.size());
  for (size_t i = 0; i < in_place.poses.size(); ++i) {
    EXPECT_TRUE(last->solution.poses[i].isApprox(in_place.poses[i], 1e-9)) << "node " << i;
  }
  EXPECT_EQ(last->solution.rejected_loops, in_place.rejected_loops);
  EXPECT_EQ(last->solution.rejected_loops, std::vector<int>{4}) << "the wrong loop is rejected off the thread too";
  EXPECT_GE(last->solve_ms, 0.0);

  // poll() never waits: it returns nothing until the solve is done, then the result once.
  solver.solve(square);
  std::optional<BackgroundGraphSolver::Result> polled;
  for (int i = 0; i < 10000 && !polled; ++i) {
    polled = solver.poll();
    if (!polled) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_TRUE(polled.has_value()) << "no result after 10 s";
  EXPECT_EQ(polled->graph.edges().size(), square.edges().size());
  EXPECT_FALSE(solver.poll().has_value());
}

}  // namespace
}  // namespace sdf_tracker
