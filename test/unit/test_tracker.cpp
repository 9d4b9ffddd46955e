#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <iostream>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/tracking/tracker.h"
#include "sdf_tracker/util/parallel.h"
#include "sdf_tracker/util/se3.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

// Acceptance bounds of the tracker on exact synthetic depth.
constexpr double kMaxTranslationError_m = 1e-3;
constexpr double kMaxRotationError_rad = 0.1 * M_PI / 180.0;

/// The synthetic room fused once from the desk path's start pose.
class TrackerFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, 10.0);
    depth = test::renderRoom(T_W_C);
    volume = std::make_unique<TsdfVolume>(test::roomVolume());
    Integrator(IntegratorConfig{}).integrate(depth, camera, T_W_C, volume.get());
  }

  PinholeCamera camera = test::testCamera();
  Eigen::Isometry3d T_W_C;
  DepthImage depth;
  std::unique_ptr<TsdfVolume> volume;
};

TEST_F(TrackerFixture, RecoversAKnownOffsetOfTwoCentimetresAndTwoDegrees) {
  const Tracker tracker(TrackerConfig{});
  const Eigen::Isometry3d guess = test::perturbed(T_W_C, 0.02, 2.0 * M_PI / 180.0);
  const TrackResult result = tracker.track(depth, camera, *volume, guess);
  ASSERT_EQ(result.status, TrackStatus::kOk) << result.message;
  const Eigen::Isometry3d error = T_W_C.inverse() * result.T_W_C;
  EXPECT_LT(error.translation().norm(), kMaxTranslationError_m);
  EXPECT_LT(rotationAngle(error), kMaxRotationError_rad);
  EXPECT_EQ(result.iterations_per_level.size(), 3u);
  EXPECT_GT(result.valid_points, 1000);
  EXPECT_LT(result.rms_residual_m, 0.005);
}

TEST_F(TrackerFixture, TheCovarianceIsPositiveDefiniteAndCoversTheTrueError) {
  using Covariance = Eigen::Matrix<double, 6, 6>;
  const Tracker tracker(TrackerConfig{});
  const TrackResult exact = tracker.track(depth, camera, *volume, test::perturbed(T_W_C, 0.01, 0.01));
  ASSERT_EQ(exact.status, TrackStatus::kOk) << exact.message;
  EXPECT_TRUE(exact.covariance.isApprox(exact.covariance.transpose()));
  EXPECT_EQ(Eigen::LLT<Covariance>(exact.covariance).info(), Eigen::Success) << exact.covariance;
  const double floor_m = 0.1 * volume->voxelSize();
  for (int i = 3; i < 6; ++i) EXPECT_GE(exact.covariance(i, i), 0.99 * floor_m * floor_m) << "a tenth of a voxel";

  synthetic::NoiseModel kinect;  // the default: a Kinect's axial noise and quantisation
  const DepthImage noisy = synthetic::Scene::indoorRoom().render(camera, T_W_C, kinect, 7);
  const TrackResult measured = tracker.track(noisy, camera, *volume, test::perturbed(T_W_C, 0.01, 0.01));
  ASSERT_EQ(measured.status, TrackStatus::kOk) << measured.message;
  EXPECT_EQ(Eigen::LLT<Covariance>(measured.covariance).info(), Eigen::Success);
  const double position_sigma = std::sqrt(measured.covariance.bottomRightCorner<3, 3>().trace());
  const double rotation_sigma = std::sqrt(measured.covariance.topLeftCorner<3, 3>().trace());
  const Eigen::Isometry3d error = T_W_C.inverse() * measured.T_W_C;
  std::cout << "[ figures  ] noisy frame: position sigma " << position_sigma * 1000 << " mm (error "
            << error.translation().norm() * 1000 << " mm), rotation sigma " << rotation_sigma * 180 / M_PI
            << " deg (error " << rotationAngle(error) * 180 / M_PI << " deg)\n";
  EXPECT_LT(error.translation().norm(), 3.0 * position_sigma) << "the stated uncertainty covers the error";
  EXPECT_LT(rotationAngle(error), 3.0 * rotation_sigma);
  EXPECT_LT(position_sigma, 0.01) << "all six directions are well constrained in the room";
}

TEST_F(TrackerFixture, ScheduleIsDataAndLevelsStopEarlyWhenConverged) {
  TrackerConfig config;
  config.levels = {{8, 30}, {1, 30}};
  const TrackResult result = Tracker(config).track(depth, camera, *volume, test::perturbed(T_W_C, 0.01, 0.01));
  ASSERT_EQ(result.iterations_per_level.size(), 2u);
  EXPECT_LT(result.iterations_per_level[1], 30) << "the fine level starts near the optimum and must stop early";
  EXPECT_TRUE(result.ok()) << result.message;
}

TEST_F(TrackerFixture, OneTwoOrThreeThreadsGiveTheSamePoseToTheBit) {
#ifdef _OPENMP
  // The points are summed in stretches whose sums are added in order, whichever thread took
  // which: the normal equations, and so the pose and its covariance, are the same.
  const Tracker tracker(TrackerConfig{});
  const Eigen::Isometry3d guess = test::perturbed(T_W_C, 0.02, 0.03);
  omp_set_num_threads(1);
  const TrackResult one = tracker.track(depth, camera, *volume, guess);
  for (int threads : {2, 3}) {
    omp_set_num_threads(threads);
    const TrackResult many = tracker.track(depth, camera, *volume, guess);
    EXPECT_EQ(many.T_W_C.matrix(), one.T_W_C.matrix()) << threads << " threads";
    EXPECT_EQ(many.covariance, one.covariance) << threads << " threads";
  }
  omp_set_num_threads(2);
#else
  GTEST_SKIP() << "built without OpenMP: nothing to compare";
#endif
}

TEST(ForEachStretch, RunsEveryStretchOnceWhateverTheThreads) {
  for (int threads : {1, 2, 5}) {
    for (int count : {0, 1, 3, 64}) {
      std::vector<std::atomic<int>> runs(static_cast<size_t>(count));
      omp_set_num_threads(threads);
      forEachStretch(count, [&runs](int stretch) { ++runs[static_cast<size_t>(stretch)]; });
      for (int stretch = 0; stretch < count; ++stretch) {
        EXPECT_EQ(runs[static_cast<size_t>(stretch)], 1)
            << "stretch " << stretch << " of " << count << ", " << threads << " threads";
      }
    }
  }
  omp_set_num_threads(2);
}

TEST_F(TrackerFixture, BadFramesGiveAStatusNotACrash) {
  const Tracker tracker(TrackerConfig{});
  const float nan = std::numeric_limits<float>::quiet_NaN();

  const TrackResult all_invalid = tracker.track(DepthImage(camera.width, camera.height, 0.0f), camera, *volume, T_W_C);
  EXPECT_EQ(all_invalid.status, TrackStatus::kBadInput);
  EXPECT_TRUE(all_invalid.T_W_C.isApprox(T_W_C)) << "a failed frame must hold the pose";

  const TrackResult all_nan = tracker.track(DepthImage(camera.width, camera.height, nan), camera, *volume, T_W_C);
  EXPECT_EQ(all_nan.status, TrackStatus::kBadInput);

  const TrackResult wrong_size = tracker.track(DepthImage(640, 480, 1.0f), camera, *volume, T_W_C);
  EXPECT_EQ(wrong_size.status, TrackStatus::kBadInput);
  EXPECT_NE(wrong_size.message.find("640x480"), std::string::npos) << wrong_size.message;

  Eigen::Isometry3d nan_pose = T_W_C;
  nan_pose.translation().x() = nan;
  EXPECT_EQ(tracker.track(depth, camera, *volume, nan_pose).status, TrackStatus::kBadInput);

  // Scattered NaNs among good pixels are just missing measurements.
  DepthImage holes = depth;
  for (int v = 0; v < holes.height(); v += 3)
    for (int u = 0; u < holes.width(); u += 2) holes.at(u, v) = nan;
  EXPECT_TRUE(tracker.track(holes, camera, *volume, T_W_C).ok());
}

TEST_F(TrackerFixture, FramesOutsideTheMapHaveTooFewPoints) {
  Eigen::Isometry3d far_away = T_W_C;
  far_away.translation() += Eigen::Vector3d(50.0, 0.0, 0.0);
  const TrackResult result = Tracker(TrackerConfig{}).track(depth, camera, *volume, far_away);
  EXPECT_EQ(result.status, TrackStatus::kTooFewPoints);
  EXPECT_TRUE(result.T_W_C.isApprox(far_away));
}

TEST(Tracker, AnEstimateThatFitsOnlyPartOfTheImageHasLowOverlap) {
  // The whole room in 2 cm voxels, so that the map has seen everything the first view shows.
  VolumeConfig whole_room;
  whole_room.dims = Eigen::Vector3i(260, 150, 260);
  whole_room.voxel_size_m = 0.02;
  whole_room.origin_W = Eigen::Vector3d(-2.6, -1.6, -1.6);
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, 10.0);
  const DepthImage depth = test::renderRoom(T_W_C, camera);
  TsdfVolume volume(whole_room);
  Integrator(IntegratorConfig{}).integrate(depth, camera, T_W_C, &volume);

  // The right two thirds of the image are pulled 30 % nearer, into space the map has seen empty:
  // the left third alone still pins the pose, as when tracking locks onto a part of a view after
  // a loss.
  DepthImage partial = depth;
  for (int v = 0; v < partial.height(); ++v) {
    for (int u = partial.width() / 3; u < partial.width(); ++u) partial.at(u, v) *= 0.7f;
  }
  const Eigen::Isometry3d guess = test::perturbed(T_W_C, 0.01, 0.01);
  TrackerConfig config;
  config.min_overlap = 0.5;
  const TrackResult whole = Tracker(config).track(depth, camera, volume, guess);
  EXPECT_TRUE(whole.ok()) << whole.message;
  EXPECT_GT(whole.overlap, 0.7) << "the map was fused from this very view";

  const TrackResult gated = Tracker(config).track(partial, camera, volume, guess);
  EXPECT_EQ(gated.status, TrackStatus::kLowOverlap) << gated.message;
  EXPECT_FALSE(gated.tracked());
  EXPECT_TRUE(gated.T_W_C.isApprox(guess)) << "a frame that fails holds the guess";
  EXPECT_NEAR(gated.overlap, whole.overlap / 3.0, 0.08) << "a third of the image still fits";
  EXPECT_NE(gated.message.find("% of the image's points lie near a mapped surface (need 50 %)"), std::string::npos)
      << gated.message;

  config.min_overlap = 0.0;  // the paper: no such test
  EXPECT_TRUE(Tracker(config).track(partial, camera, volume, guess).ok());
}

TEST_F(TrackerFixture, PointsOutsideADenseGridDoNotCountAgainstOverlap) {
  // The fixture's grid leaves the room's far walls out: about half of the image lands outside
  // it, where the map can never hold a value. Those points say nothing about the fit.
  const Eigen::AlignedBox3f grid_W = volume->holdableRegion();
  size_t outside = 0, measured = 0;
  for (int v = 0; v < depth.height(); v += 2) {
    for (int u = 0; u < depth.width(); u += 2) {
      const float z = depth.at(u, v);
      if (!DepthImage::isMeasurement(z)) continue;
      ++measured;
      outside += !grid_W.contains((T_W_C * camera.backProject(u, v, z).cast<double>()).cast<float>());
    }
  }
  ASSERT_GT(outside, measured / 3) << "the test needs a view that reaches well beyond the grid";

  TrackerConfig config;
  config.min_overlap = 0.5;
  const TrackResult result = Tracker(config).track(depth, camera, *volume, test::perturbed(T_W_C, 0.01, 0.01));
  EXPECT_TRUE(result.ok()) << result.message;
  EXPECT_GT(result.overlap, 0.7) << "the grid was fused from this very view";
  EXPECT_LE(result.overlap, 1.0);
}

/// A single wall 2 m ahead of the camera at the origin (facing +z), mapped from there: distance
/// and tilt are constrained, sliding along the wall and rolling about its normal are not.
class WallFixture : public ::testing::Test {
 protected:
  static DepthImage renderWall(const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C) {
    synthetic::NoiseModel exact;
    exact.enabled = false;
    return synthetic::Scene::singleWall().render(camera, T_W_C, exact, 0);
  }
  static VolumeConfig wallVolume() {
    VolumeConfig config;
    config.dims = Eigen::Vector3i(200, 160, 60);
    config.voxel_size_m = 0.02;
    config.origin_W = Eigen::Vector3d(-2.0, -1.6, 1.4);
    return config;
  }
  void SetUp() override { Integrator(IntegratorConfig{}).integrate(wall, camera, T_W_C, &volume); }

  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  const DepthImage wall = renderWall(camera, T_W_C);
  TsdfVolume volume{wallVolume()};
};

TEST_F(WallFixture, ASinglePlaneIsReportedAsDegenerate) {
  const TrackResult result = Tracker(TrackerConfig{}).track(wall, camera, volume, test::perturbed(T_W_C, 0.01, 0.01));
  EXPECT_EQ(result.status, TrackStatus::kDegenerate) << result.message << " inverse condition " << result.inverse_condition;
  EXPECT_TRUE(result.T_W_C.isApprox(test::perturbed(T_W_C, 0.01, 0.01))) << "a degenerate frame must hold the pose";
}

TEST_F(WallFixture, ASinglePlaneIsSolvedInTheThreeDirectionsItConstrains) {
  // The guess is off in every direction: along the wall (x, y) and about its normal (z), which
  // the wall cannot tell, and in distance and tilt, which it can.
  Eigen::Isometry3d guess = T_W_C;
  guess.translation() = Eigen::Vector3d(0.03, -0.02, 0.04);
  guess.linear() = (Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()) *
                    Eigen::AngleAxisd(-0.02, Eigen::Vector3d::UnitY()))
                       .toRotationMatrix();
  TrackerConfig tracker_config;
  tracker_config.solve_constrained_directions = true;
  const TrackResult result = Tracker(tracker_config).track(wall, camera, volume, guess);
  EXPECT_EQ(result.status, TrackStatus::kDegenerate) << result.message;
  EXPECT_EQ(result.constrained_rank, 3) << "distance and two tilts";
  EXPECT_TRUE(result.tracked()) << "the frame is used: its constrained directions are estimated";
  EXPECT_NE(result.message.find("constrains 3 of six"), std::string::npos) << result.message;

  // Constrained: the distance to the wall and its normal as the camera sees it.
  const Eigen::Vector3d normal_C = result.T_W_C.linear().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(result.T_W_C.translation().z(), 0.0, 0.003);
  EXPECT_LT(std::acos(std::min(1.0, normal_C.z())), 0.003) << "the tilt towards the wall is corrected";
  // Unconstrained: kept from the guess, not pushed anywhere by noise or regularisation.
  EXPECT_NEAR(result.T_W_C.translation().x(), 0.03, 0.003);
  EXPECT_NEAR(result.T_W_C.translation().y(), -0.02, 0.003);
  const Eigen::Vector3d x_axis = result.T_W_C.linear().col(0);
  EXPECT_NEAR(std::atan2(x_axis.y(), x_axis.x()), 0.03, 0.003) << "the roll about the wall's normal";
  // The covariance ([rotation; translation], world axes) says the same: nothing is known along the
  // wall and about its normal, the distance to it is known well.
  const Eigen::Matrix<double, 6, 6>& P = result.covariance;
  EXPECT_GT(P(3, 3), 0.1 * kUnconstrainedVariance) << "along the wall (x)";
  EXPECT_GT(P(4, 4), 0.1 * kUnconstrainedVariance) << "along the wall (y)";
  EXPECT_GT(P(2, 2), 1e4) << "about the wall's normal";
  EXPECT_GT(P(5, 5), 0.0);
  EXPECT_LT(P(5, 5), 1e-5) << "across the wall: the floor, a tenth of a voxel";

  // The paper's behaviour is still there: the frame fails and the guess is handed back.
  tracker_config.solve_constrained_directions = false;
  const TrackResult plain = Tracker(tracker_config).track(wall, camera, volume, guess);
  EXPECT_EQ(plain.status, TrackStatus::kDegenerate);
  EXPECT_FALSE(plain.tracked());
  EXPECT_TRUE(plain.T_W_C.isApprox(guess));
}

TEST_F(WallFixture, OnASinglePlaneTheOdometryGivesWhatTheWallLeavesOpenAndTheMapTheRest) {
  // The wheels put the camera 2 cm off along the wall, 1.5 cm off across it and turned 1 degree
  // towards it; the guess is theirs.
  MotionPrior prior;
  prior.odometry.emplace();
  prior.odometry->T_W_C = T_W_C;
  prior.odometry->T_W_C.translation() += Eigen::Vector3d(0.02, 0.0, 0.015);
  prior.odometry->T_W_C.linear() = Eigen::AngleAxisd(0.0175, Eigen::Vector3d::UnitY()).toRotationMatrix() * T_W_C.linear();
  prior.odometry->sigma << Eigen::Vector3d::Constant(1e-3), Eigen::Vector3d::Constant(1e-3);
  TrackerConfig config;
  config.solve_constrained_directions = true;
  const TrackResult result = Tracker(config).track(wall, camera, volume, prior.odometry->T_W_C, prior);
  EXPECT_TRUE(result.tracked()) << result.message;
  EXPECT_EQ(result.status, TrackStatus::kDegenerate);
  EXPECT_NE(result.message.find("the others follow the odometry"), std::string::npos) << result.message;
  // What the wall sees, the map sets: distance and tilt.
  const Eigen::Vector3d normal_C = result.T_W_C.linear().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(result.T_W_C.translation().z(), T_W_C.translation().z(), 0.002);
  EXPECT_LT(std::acos(std::min(1.0, normal_C.z())), 0.003);
  // What it does not, the wheels keep.
  EXPECT_NEAR(result.T_W_C.translation().x(), T_W_C.translation().x() + 0.02, 0.002);
  EXPECT_NEAR(result.T_W_C.translation().y(), T_W_C.translation().y(), 0.002);
  // Without SolveConstrainedDirections (the paper) the odometry still estimates the frame.
  config.solve_constrained_directions = false;
  EXPECT_TRUE(Tracker(config).track(wall, camera, volume, prior.odometry->T_W_C, prior).tracked());
}

TEST_F(WallFixture, WithoutOdometryADegenerateFrameGoesWhereItIsToldAlongWhatTheWallLeavesOpen) {
  // The guess is a constant-velocity prediction 3 cm along the wall and 1 cm too close: the wall
  // sees the distance, nothing sees the slide, so the camera stays where it was along the wall.
  MotionPrior prior;
  prior.T_W_C_unconstrained = T_W_C;
  Eigen::Isometry3d guess = T_W_C;
  guess.translation() += Eigen::Vector3d(0.03, -0.01, 0.01);
  TrackerConfig config;
  config.solve_constrained_directions = true;
  const TrackResult result = Tracker(config).track(wall, camera, volume, guess, prior);
  EXPECT_TRUE(result.tracked()) << result.message;
  EXPECT_NE(result.message.find("the others keep a decaying part of the predicted motion"), std::string::npos)
      << result.message;
  EXPECT_NEAR(result.T_W_C.translation().z(), T_W_C.translation().z(), 0.002) << "the distance is fitted";
  EXPECT_NEAR(result.T_W_C.translation().x(), T_W_C.translation().x(), 0.002) << "no slide from the prediction";
  EXPECT_NEAR(result.T_W_C.translation().y(), T_W_C.translation().y(), 0.002);
  // Without a held pose the prediction is kept, as before.
  const TrackResult predicted = Tracker(config).track(wall, camera, volume, guess);
  EXPECT_NEAR(predicted.T_W_C.translation().x(), T_W_C.translation().x() + 0.03, 0.002);
}

TEST(Tracker, ConstrainedDirectionsChangeNothingWhereTheGeometryConstrainsAll) {
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, 10.0);
  const DepthImage depth = test::renderRoom(T_W_C, camera);
  TsdfVolume volume(test::roomVolume());
  Integrator(IntegratorConfig{}).integrate(depth, camera, T_W_C, &volume);
  const Eigen::Isometry3d guess = test::perturbed(T_W_C, 0.02, 0.02);
  TrackerConfig config;
  const TrackResult plain = Tracker(config).track(depth, camera, volume, guess);
  config.solve_constrained_directions = true;
  const TrackResult constrained = Tracker(config).track(depth, camera, volume, guess);
  ASSERT_TRUE(plain.ok()) << plain.message;
  ASSERT_TRUE(constrained.ok()) << constrained.message;
  EXPECT_EQ(constrained.constrained_rank, 6);
  EXPECT_LT((plain.T_W_C.translation() - constrained.T_W_C.translation()).norm(), 1e-5);
}

TEST(TrackerConfig, RejectsEveryInvalidValue) {
  TrackerConfig config;
  config.levels = {{0, 5}, {2, -1}};
  config.huber_coefficient = -1.0;
  config.min_overlap = 1.5;
  const auto violations = config.validate();
  ASSERT_EQ(violations.size(), 4u);
  EXPECT_NE(violations[0].find("levels[0].stride"), std::string::npos);
  EXPECT_NE(violations[1].find("levels[1].max_iterations"), std::string::npos);
  EXPECT_NE(violations[2].find("huber_coefficient must be > 0 (got -1)"), std::string::npos);
  EXPECT_NE(violations[3].find("min_overlap"), std::string::npos) << violations[3];
  EXPECT_NE(violations[3].find("1.5"), std::string::npos) << violations[3];
  config.levels.clear();
  EXPECT_THROW(Tracker{config}, std::invalid_argument);
}

TEST(HouseWalk, PicturesAndShelvesOnTheWallsGiveTheTrackerAllSixDirectionsWhereABareWallDoesNot) {
  // At 65 s the camera turns close to a room's wall. Bare, the view holds that plane and little
  // else, and one direction is left to the motion model; with what a lived-in room has on its
  // walls, the same view fixes the whole pose.
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kWalk, 65.0, 0.0);
  synthetic::NoiseModel exact;
  exact.enabled = false;
  const PipelineConfig config = preset("default").pipeline;
  auto trackFromNearby = [&](synthetic::HouseWalls walls) {
    const DepthImage depth = synthetic::Scene::house(walls).render(camera, T_W_C, exact, 0);
    SparseTsdfMap map(config.volume);
    Integrator(config.integrator).integrate(depth, camera, T_W_C, &map);
    return Tracker(config.tracker).track(depth, camera, map, test::perturbed(T_W_C, 0.01, 0.01));
  };
  const TrackResult bare = trackFromNearby(synthetic::HouseWalls::kBare);
  EXPECT_EQ(bare.status, TrackStatus::kDegenerate) << bare.message;
  EXPECT_LT(bare.constrained_rank, 6) << bare.message;
  const TrackResult furnished = trackFromNearby(synthetic::HouseWalls::kFurnished);
  ASSERT_EQ(furnished.status, TrackStatus::kOk) << furnished.message;
  EXPECT_EQ(furnished.constrained_rank, 6);
  EXPECT_LT((furnished.T_W_C.translation() - T_W_C.translation()).norm(), 0.005) << "from a guess 1 cm off";
  std::cout << "inverse condition at 65 s: bare walls " << bare.inverse_condition << " (rank "
            << bare.constrained_rank << "), furnished " << furnished.inverse_condition << " (rank "
            << furnished.constrained_rank << ")\n";
}

}  // namespace
}  // namespace sdf_tracker
