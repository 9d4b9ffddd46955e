// The on-line loop: bad frames, live updates, tracking loss and recovery, motion prediction.
#include <gtest/gtest.h>

#if __has_include(<malloc.h>)
#include <malloc.h>
#endif

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/tracking/motion_model.h"
#include "sdf_tracker/util/frame_memory.h"
#include "sdf_tracker/util/se3.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

// glibc's own malloc; AddressSanitizer's replacement ignores mallopt().
#if defined(M_MMAP_THRESHOLD) && !defined(__SANITIZE_ADDRESS__)
TEST(FrameMemory, AFrameSizedBufferComesFromTheHeapAndStaysAfterItIsFreed) {
  ASSERT_TRUE(keepFrameMemoryResident()) << "glibc refused the allocator settings";
  constexpr size_t kBytes = 4 << 20;  // a 1280x800 float depth image
  const size_t mapped_before = mallinfo2().hblkhd;
  char* buffer = static_cast<char*>(std::malloc(kBytes));
  ASSERT_NE(buffer, nullptr);
  std::memset(buffer, 1, kBytes);
  EXPECT_EQ(mallinfo2().hblkhd, mapped_before) << "the buffer was mapped on its own, to be unmapped when freed";
  std::free(buffer);
  EXPECT_GE(mallinfo2().fordblks, kBytes) << "the heap gave the freed buffer back to the system";
}
#else
TEST(FrameMemory, AFrameSizedBufferComesFromTheHeapAndStaysAfterItIsFreed) {
  GTEST_SKIP() << "not glibc's malloc: keepFrameMemoryResident() has nothing to set here";
}
#endif

constexpr double kCoarseVoxel_m = 0.04;

/// The default preset on a coarse 64^3 grid: enough where what the frames show does not matter.
PipelineConfig coarseGridPipeline() {
  PipelineConfig config = preset("default").pipeline;
  config.volume.dims = Eigen::Vector3i(64, 64, 64);
  config.volume.voxel_size_m = kCoarseVoxel_m;
  return config;
}

TEST(Pipeline, BadFramesLeaveMapAndPoseUntouched) {
  SdfPipeline pipeline(coarseGridPipeline());
  const PinholeCamera camera = test::testCamera();
  const FrameReport wrong_size = pipeline.processFrame(DepthImage(640, 480, 1.0f), camera);
  EXPECT_EQ(wrong_size.track.status, TrackStatus::kBadInput);
  const FrameReport empty = pipeline.processFrame(DepthImage(camera.width, camera.height, 0.0f), camera);
  EXPECT_EQ(empty.track.status, TrackStatus::kBadInput);
  EXPECT_FALSE(empty.fused);
  const FrameReport too_near = pipeline.processFrame(DepthImage(camera.width, camera.height, 0.2f), camera);
  EXPECT_EQ(too_near.track.status, TrackStatus::kBadInput) << "depth under MinDepth is no measurement";
  EXPECT_EQ(test::totalWeight(pipeline.map()), 0.0) << "nothing fused";
  EXPECT_TRUE(pipeline.pose().isApprox(Eigen::Isometry3d::Identity()));
}

TEST(Pipeline, AMapThatObservedNothingIsRefusedAndTheLiveMapKept) {
  SdfPipeline pipeline(coarseGridPipeline());
  const PinholeCamera camera = test::testCamera();
  ASSERT_TRUE(pipeline.processFrame(DepthImage(camera.width, camera.height, 1.0f), camera, 0.0).initialised_map);
  VolumeConfig empty;
  empty.type = MapType::kSparse;
  try {
    pipeline.setMap(makeMap(empty));
    ADD_FAILURE() << "an empty map was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the map holds no observed voxel: nothing to track against");
  }
  EXPECT_GT(test::totalWeight(pipeline.map()), 0.0) << "the live map stays";
  const FrameReport next = pipeline.processFrame(DepthImage(camera.width, camera.height, 1.0f), camera, 1 / 30.0);
  EXPECT_FALSE(next.initialised_map) << "tracked in the map it had";
}

TEST(Pipeline, TheFirstFrameAnchorsTheMapWithTheSmallestCovarianceNotNone) {
  SdfPipeline pipeline(coarseGridPipeline());
  const PinholeCamera camera = test::testCamera();
  const FrameReport first = pipeline.processFrame(DepthImage(camera.width, camera.height, 1.0f), camera);
  ASSERT_TRUE(first.initialised_map);
  // An EKF takes no zero covariance: the pose the map is anchored at is as certain as the map.
  const double floor = std::pow(kSurfaceResolution_voxels * kCoarseVoxel_m, 2);
  EXPECT_TRUE(first.track.covariance.isApprox(Eigen::Matrix<double, 6, 6>::Identity() * floor, 1e-6))
      << first.track.covariance;
}

TEST(Pipeline, LiveUpdatesValidateAndRefuseGridChanges) {
  Settings settings = preset("default");
  settings.pipeline.volume.dims = Eigen::Vector3i(32, 32, 32);
  SdfPipeline pipeline(settings.pipeline);
  PipelineConfig candidate = pipeline.config();
  candidate.integrator.max_weight = 10.0;
  pipeline.updateConfig(candidate);
  EXPECT_DOUBLE_EQ(pipeline.config().integrator.max_weight, 10.0);
  candidate.integrator.max_weight = -1.0;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument);
  EXPECT_DOUBLE_EQ(pipeline.config().integrator.max_weight, 10.0) << "a rejected update changes nothing";
  candidate = pipeline.config();
  candidate.volume.voxel_size_m = 0.05;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument);
  candidate = pipeline.config();
  candidate.volume.compact_voxels = true;
  EXPECT_THROW(pipeline.updateConfig(candidate), std::invalid_argument) << "the storage belongs to the grid";
}

/// The default preset on a small grid around the synthetic room, for pipeline tests.
PipelineConfig smallRoomPipeline() {
  PipelineConfig config = preset("default").pipeline;
  config.volume.dims = Eigen::Vector3i(128, 128, 128);
  config.volume.voxel_size_m = 0.03;
  config.initial_camera_in_grid = Eigen::Vector3d(0.5, 0.5, 0.1);
  return config;
}

constexpr double kFramePeriod_s = 1.0 / 30.0;
constexpr double kDeskDuration_s = 10.0;

TEST(Pipeline, ALostCameraHoldsItsPoseFusesNothingAndRelocalisesWhenItSeesTheMapAgain) {
  SdfPipeline pipeline(smallRoomPipeline());
  const PinholeCamera camera = test::testCamera();
  // The tracker's world is the first camera's frame; the room is rendered in the scene's.
  const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, kDeskDuration_s);
  auto frameAt = [&](int i) {
    return test::renderRoom(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s), camera);
  };
  int i = 0;
  for (; i < 10; ++i) ASSERT_TRUE(pipeline.processFrame(frameAt(i), camera, i * kFramePeriod_s).track.ok()) << i;
  const Eigen::Isometry3d held = pipeline.pose();
  const double weight_before = test::totalWeight(pipeline.map());

  // The camera is carried far away (half a metre, 70 degrees): no frame may be tracked or fused.
  const Eigen::Isometry3d away = test::perturbed(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s,
                                                                       kDeskDuration_s), 0.5, 70.0 * M_PI / 180.0);
  for (int k = 0; k < 15; ++k, ++i) {
    const FrameReport report = pipeline.processFrame(test::renderRoom(away, camera), camera, i * kFramePeriod_s);
    EXPECT_FALSE(report.track.ok()) << "frame " << i << " was tracked to a wrong pose";
    EXPECT_FALSE(report.fused);
  }
  EXPECT_EQ(pipeline.consecutiveFailures(), 15);
  EXPECT_EQ(test::totalWeight(pipeline.map()), weight_before) << "nothing fused while lost";
  EXPECT_TRUE(pipeline.pose().isApprox(held, 1e-9)) << "the pose is held";

  // Back near where it was lost: tracking resumes by itself, at the right pose.
  int resumed_at = -1;
  for (int k = 0; k < 5 && resumed_at < 0; ++k) {
    const int j = 10 + k;  // the path continues from the held pose
    if (pipeline.processFrame(frameAt(j), camera, (i + k) * kFramePeriod_s).track.ok()) resumed_at = k;
  }
  ASSERT_GE(resumed_at, 0) << "did not relocalise";
  EXPECT_EQ(pipeline.consecutiveFailures(), 0);
  const Eigen::Isometry3d truth =
      T_scene_W.inverse() * synthetic::cameraPose(synthetic::Motion::kDesk, (10 + resumed_at) * kFramePeriod_s,
                                                  kDeskDuration_s);
  EXPECT_LT((pipeline.pose().translation() - truth.translation()).norm(), 0.01);
}

TEST(Pipeline, AfterFramesMissingLongerThanThePredictionBridgesTheHeldPosesFitIsConfirmedFirst) {
  // The camera may have been carried anywhere while no frame came: a fit from the held pose could
  // be a wrong place that looks alike, so it is followed like any candidate before anything is fused.
  PipelineConfig config = smallRoomPipeline();
  config.relocalise = true;
  SdfPipeline pipeline(config);
  const PinholeCamera camera = test::testCamera();
  auto frameAt = [&](int i) {
    return test::renderRoom(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s), camera);
  };
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(pipeline.processFrame(frameAt(i), camera, i * kFramePeriod_s).track.ok()) << i;
  const double gap_s = 2.0 * config.max_prediction_gap_s;
  double t = 9 * kFramePeriod_s + gap_s;
  const int confirm = config.relocaliser.confirm_frames;
  for (int k = 0; k < confirm - 1; ++k, t += kFramePeriod_s) {
    const FrameReport report = pipeline.processFrame(frameAt(10 + k), camera, t);
    EXPECT_EQ(report.track.status, TrackStatus::kRelocalising) << "frame " << k << ": " << report.track.message;
    EXPECT_FALSE(report.fused);
    EXPECT_NE(report.track.message.find("since the last tracked frame"), std::string::npos) << report.track.message;
  }
  const FrameReport found = pipeline.processFrame(frameAt(10 + confirm - 1), camera, t);
  EXPECT_TRUE(found.track.ok()) << found.track.message;
  EXPECT_TRUE(found.fused);

  // Frames that come within the gap are taken at once, as before.
  t += config.max_prediction_gap_s * 0.5;
  const FrameReport next = pipeline.processFrame(frameAt(10 + confirm), camera, t);
  EXPECT_TRUE(next.track.ok()) << next.track.message;
  EXPECT_TRUE(next.fused);

  // A camera that sends a frame a second (a throttled topic) misses none: each is taken at once.
  SdfPipeline slow(config);
  for (int i = 0; i < 5; ++i) {
    const FrameReport report = slow.processFrame(frameAt(i), camera, 2.0 * config.max_prediction_gap_s * i);
    EXPECT_TRUE(report.track.ok()) << "frame " << i << ": " << report.track.message;
    EXPECT_TRUE(report.fused) << "frame " << i;
  }
}

TEST(Pipeline, WhileFramesFailTheHeldPoseMovesOnWithTheOtherOdometry) {
  SdfPipeline pipeline(smallRoomPipeline());
  const PinholeCamera camera = test::testCamera();
  auto truthAt = [](int i) { return synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s); };
  // The other odometry's frame is the scene's; it measures the true motion.
  int i = 0;
  for (; i < 10; ++i) {
    ASSERT_TRUE(pipeline.processFrame(test::renderRoom(truthAt(i), camera), camera, i * kFramePeriod_s, truthAt(i))
                    .track.ok()) << i;
  }
  const Eigen::Isometry3d T_W_scene = pipeline.pose() * truthAt(i - 1).inverse();
  // The view is blocked (every frame fails) while the robot drives on 2 cm a frame.
  const Eigen::Isometry3d away = test::perturbed(truthAt(i), 0.5, 70.0 * M_PI / 180.0);
  Eigen::Isometry3d T_scene_C = truthAt(i - 1);
  for (int k = 0; k < 5; ++k, ++i) {
    T_scene_C.translation().x() += 0.02;
    const FrameReport report =
        pipeline.processFrame(test::renderRoom(away, camera), camera, i * kFramePeriod_s, T_scene_C);
    ASSERT_FALSE(report.track.tracked()) << "frame " << i;
    EXPECT_TRUE(report.predicted_by_odometry);
    EXPECT_FALSE(report.fused);
  }
  EXPECT_LT((pipeline.pose().translation() - (T_W_scene * T_scene_C).translation()).norm(), 1e-9)
      << "the held pose follows the odometry, 10 cm on";
}

TEST(Pipeline, AfterResetAfterFailuresFailedFramesANewMapStartsWhereTheCameraWasHeld) {
  PipelineConfig config = smallRoomPipeline();
  config.reset_after_failures = 5;
  SdfPipeline pipeline(config);
  const PinholeCamera camera = test::testCamera();
  int i = 0;
  for (; i < 10; ++i) {
    const Eigen::Isometry3d pose = synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s);
    ASSERT_TRUE(pipeline.processFrame(test::renderRoom(pose, camera), camera, i * kFramePeriod_s).track.ok()) << i;
  }
  const Eigen::Isometry3d held = pipeline.pose();
  const double weight_before = test::totalWeight(pipeline.map());
  const DepthImage away = test::renderRoom(
      test::perturbed(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s), 0.5,
                      70.0 * M_PI / 180.0),
      camera);
  for (int k = 0; k < 5; ++k, ++i) {
    const FrameReport report = pipeline.processFrame(away, camera, i * kFramePeriod_s);
    ASSERT_FALSE(report.track.ok()) << "frame " << i;
    EXPECT_FALSE(report.reset) << "frame " << i << ": reset before ResetAfterFailures failures";
  }
  const FrameReport restart = pipeline.processFrame(away, camera, i++ * kFramePeriod_s);
  EXPECT_TRUE(restart.reset);
  EXPECT_TRUE(restart.initialised_map && restart.fused) << "the frame starts the new map";
  EXPECT_TRUE(pipeline.pose().isApprox(held, 1e-9)) << "the new map starts at the held pose";
  const double weight_after = test::totalWeight(pipeline.map());
  EXPECT_GT(weight_after, 0.0);
  EXPECT_LT(weight_after, weight_before) << "the old map was cleared";
  EXPECT_TRUE(pipeline.processFrame(away, camera, i * kFramePeriod_s).track.ok()) << "tracked in the new map";
}

TEST(MotionModel, LogInvertsExpAndAConstantTwistIsExtrapolatedExactly) {
  Twist xi;
  xi << 0.3, -0.2, 0.5, 0.1, -0.4, 0.25;
  const Twist back = logSe3(expSe3(xi));
  EXPECT_LT((back - xi).norm(), 1e-12) << back.transpose();
  EXPECT_LT(logSe3(Eigen::Isometry3d::Identity()).norm(), 1e-15);

  // A camera turning while it moves: poses exp(t xi) at 0.1 s and 0.2 s predict the one at 0.35 s.
  const Eigen::Isometry3d start = expSe3((Twist() << 0.0, 0.4, 0.0, 1.0, 0.0, 2.0).finished());
  auto at = [&](double t_s) { return start * expSe3(t_s * xi); };
  MotionModel motion(0.5);
  EXPECT_TRUE(motion.predict(0.1).isApprox(Eigen::Isometry3d::Identity())) << "no pose yet";
  motion.addTracked(0.1, at(0.1));
  EXPECT_TRUE(motion.predict(0.2).isApprox(at(0.1))) << "one pose: no velocity yet";
  motion.addTracked(0.2, at(0.2));
  EXPECT_LT((motion.predict(0.35).matrix() - at(0.35).matrix()).norm(), 1e-12) << "a dropped frame is bridged";
  EXPECT_TRUE(motion.predict(0.75).isApprox(at(0.2))) << "no prediction across more than 0.5 s";
  EXPECT_TRUE(motion.predict(0.2).isApprox(at(0.2))) << "no prediction backwards";
  motion.addTracked(0.3, at(0.3));
  EXPECT_LT((motion.predict(0.4).matrix() - at(0.4).matrix()).norm(), 1e-12) << "from the last two poses";
  motion.clear();
  motion.addTracked(0.5, at(0.5));
  EXPECT_TRUE(motion.predict(0.6).isApprox(at(0.5))) << "cleared: the old poses give no velocity";
}

TEST(Pipeline, AFrameAtAGivenPoseIsTrackedFromItButFusedThere) {
  // A map made at the true poses; then a frame handed over with a pose 3 cm off the truth: the
  // tracker's estimate goes back to the truth, the frame is fused at the given pose.
  const PinholeCamera camera = test::testCamera();
  SdfPipeline pipeline(smallRoomPipeline());
  const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, kDeskDuration_s);
  auto truth = [&](int i) {
    return T_scene_W.inverse() * synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s);
  };
  auto frame = [&](int i) {
    return test::renderRoom(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s), camera);
  };
  for (int i = 0; i < 5; ++i) {
    const FrameReport report = pipeline.processFrameAtPose(frame(i), camera, truth(i), i * kFramePeriod_s);
    EXPECT_TRUE(report.fused) << "frame " << i;
    EXPECT_TRUE(pipeline.pose().isApprox(truth(i))) << "frame " << i;
  }
  const Eigen::Isometry3d given = Eigen::Translation3d(0.03, 0.0, 0.0) * truth(5);
  const FrameReport report = pipeline.processFrameAtPose(frame(5), camera, given, 5 * kFramePeriod_s);
  ASSERT_TRUE(report.track.tracked()) << report.track.message;
  EXPECT_LT((report.track.T_W_C.translation() - truth(5).translation()).norm(), 0.005) << "the estimate";
  EXPECT_TRUE(pipeline.pose().isApprox(given)) << "the fused pose is the given one";
  EXPECT_TRUE(report.fused);
}

TEST(Pipeline, MotionPredictionBridgesDroppedFramesWithFewerIterations) {
  // Every third frame of the fast path, with its real timestamps: the camera moves three frames'
  // worth between the frames the tracker sees.
  const PinholeCamera camera = test::testCamera();
  std::vector<DepthImage> images;  // rendered once for both runs
  for (int i = 0; i < 60; i += 3) {
    images.push_back(
        test::renderRoom(synthetic::cameraPose(synthetic::Motion::kFast, i * kFramePeriod_s, kDeskDuration_s), camera));
  }
  auto run = [&](bool predict, double* mean_iterations) {
    PipelineConfig config = smallRoomPipeline();
    config.predict_motion = predict;
    SdfPipeline pipeline(config);
    const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(synthetic::Motion::kFast, 0.0, kDeskDuration_s);
    int iterations = 0, frames = 0;
    double worst_error_m = 0.0;
    for (int i = 0; i < 60; i += 3) {
      const double t = i * kFramePeriod_s;
      const Eigen::Isometry3d T_scene_C = synthetic::cameraPose(synthetic::Motion::kFast, t, kDeskDuration_s);
      const FrameReport report = pipeline.processFrame(images[i / 3], camera, t);
      EXPECT_TRUE(report.track.ok()) << "frame " << i << ": " << report.track.message;
      for (int n : report.track.iterations_per_level) iterations += n;
      ++frames;
      worst_error_m = std::max(worst_error_m,
                               (pipeline.pose().translation() - (T_scene_W.inverse() * T_scene_C).translation()).norm());
    }
    *mean_iterations = static_cast<double>(iterations) / frames;
    return worst_error_m;
  };
  double iterations_predicted, iterations_plain;
  const double error_predicted = run(true, &iterations_predicted);
  const double error_plain = run(false, &iterations_plain);
  std::cout << "[ figures  ] every third frame: " << iterations_predicted << " iterations per frame with prediction, "
            << iterations_plain << " without; worst error " << error_predicted * 1000 << " / " << error_plain * 1000
            << " mm\n";
  EXPECT_LT(iterations_predicted, iterations_plain);
  // On a 3 cm grid a single QVGA view leaves about a third of a voxel of bias, with or without.
  const double half_voxel_m = 0.5 * smallRoomPipeline().volume.voxel_size_m;
  EXPECT_LT(error_predicted, half_voxel_m);
  EXPECT_LT(error_predicted, error_plain + 0.001) << "prediction must not make the estimate worse";
}

TEST(Pipeline, DegenerateFramesAreReportedWithTheirRankTrackedWhereConstrainedAndFused) {
  // Sliding along a single wall: the distance to it and the tilts are seen, the slide and the roll
  // about the wall's normal are not.
  const PinholeCamera camera = test::testCamera();
  synthetic::NoiseModel exact;
  exact.enabled = false;
  const synthetic::Scene wall = synthetic::Scene::singleWall();
  PipelineConfig config = preset("default").pipeline;
  config.volume.dims = Eigen::Vector3i(160, 128, 128);  // the wall is 2 m ahead
  config.volume.voxel_size_m = 0.02;
  SdfPipeline pipeline(config);
  const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(synthetic::Motion::kPlanar, 0.0, 10.0);
  int degenerate = 0, fused = 0;
  for (int i = 0; i < 30; ++i) {
    const double t = i * kFramePeriod_s;
    const Eigen::Isometry3d T_scene_C = synthetic::cameraPose(synthetic::Motion::kPlanar, t, 10.0);
    const FrameReport report = pipeline.processFrame(wall.render(camera, T_scene_C, exact, 0), camera, t);
    if (i == 0) continue;
    EXPECT_TRUE(report.track.tracked()) << "frame " << i << ": " << report.track.message;
    if (report.track.status == TrackStatus::kDegenerate) {
      ++degenerate;
      EXPECT_EQ(report.track.constrained_rank, 3) << "frame " << i << ": " << report.track.message;
    }
    fused += report.fused;
    // The distance to the wall is observed: it stays right even though the slide is not.
    const Eigen::Isometry3d truth = T_scene_W.inverse() * T_scene_C;
    EXPECT_NEAR(pipeline.pose().translation().z(), truth.translation().z(), 0.005) << "frame " << i;
  }
  EXPECT_EQ(degenerate, 29) << "every tracked frame of a single wall is degenerate";
  EXPECT_GT(fused, 0) << "degenerate frames still build the map";
  EXPECT_EQ(pipeline.consecutiveFailures(), 0);
}

}  // namespace
}  // namespace sdf_tracker
