// Another odometry beside the tracker (a robot's wheels, SdfPipeline::processFrame's T_odom_C):
// where the view constrains only some directions, the odometry's motion holds the others, and
// without one such views do no worse than a camera standing still.

#include <gtest/gtest.h>

#include <iostream>

#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/sim/wheel_odometry.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

constexpr double kRate_hz = 30.0;

/// ATEs of one synthetic drive (QVGA, default preset): tracked with the wheel odometry as the
/// prediction and without it, the wheel odometry alone, and a camera that stood still.
struct Drive {
  double with_m, without_m, wheels_alone_m, standing_still_m;
  int lost_with = 0, lost_without = 0, predicted = 0;
  int frames;
};

Drive drive(synthetic::Motion motion, synthetic::HouseWalls walls, int frames, bool noise, uint32_t seed) {
  const PinholeCamera camera = test::testCamera();
  synthetic::NoiseModel noise_model;
  noise_model.enabled = noise;
  const synthetic::Scene scene = synthetic::Scene::forMotion(motion, walls);
  const double duration_s = frames / kRate_hz;
  const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(motion, 0.0, duration_s);
  std::vector<io::StampedPose> truth;
  std::vector<DepthImage> images;
  for (int i = 0; i < frames; ++i) {
    const double t = i / kRate_hz;
    const Eigen::Isometry3d T_scene_C = synthetic::cameraPose(motion, t, duration_s);
    truth.push_back({t, T_scene_W.inverse() * T_scene_C});
    images.push_back(scene.render(camera, T_scene_C, noise_model, seed * 100003u + static_cast<uint32_t>(i)));
  }
  synthetic::WheelOdometryModel wheels;
  wheels.seed = seed;
  const std::vector<io::StampedPose> odometry = synthetic::wheelOdometry(truth, wheels);

  Drive result;
  result.frames = frames;
  auto track = [&](bool with_odometry, int* lost) {
    SdfPipeline pipeline(preset("default").pipeline);
    std::vector<io::StampedPose> estimate;
    for (int i = 0; i < frames; ++i) {
      const FrameReport report = pipeline.processFrame(
          images[i], camera, truth[i].timestamp_s,
          with_odometry ? std::optional<Eigen::Isometry3d>(odometry[i].T_W_C) : std::nullopt);
      *lost += !report.track.tracked();
      if (with_odometry) result.predicted += report.predicted_by_odometry;
      estimate.push_back({truth[i].timestamp_s, pipeline.pose()});
    }
    return evaluation::computeAte(estimate, truth).translation_m.rmse;
  };
  result.with_m = track(true, &result.lost_with);
  result.without_m = track(false, &result.lost_without);
  result.wheels_alone_m = evaluation::computeAte(odometry, truth).translation_m.rmse;
  std::vector<io::StampedPose> standing_still = truth;
  for (auto& pose : standing_still) pose.T_W_C = truth.front().T_W_C;
  result.standing_still_m = evaluation::computeAte(standing_still, truth).translation_m.rmse;
  return result;
}

void print(const std::string& name, const Drive& d) {
  std::cout << "[ figures  ] " << name << ", ATE: with wheel odometry " << d.with_m * 100 << " cm, wheel odometry alone "
            << d.wheels_alone_m * 100 << " cm, tracker alone " << d.without_m * 100 << " cm, standing still "
            << d.standing_still_m * 100 << " cm; frames lost " << d.lost_with << " / " << d.lost_without << "\n";
}

TEST(OdometryPrior, AWheelOdometryHoldsWhatASingleWallLeavesOpen) {
  // The planar sequence: sliding along a single wall 2 m ahead, which fixes the distance and the
  // two tilts but not the slide or the turn about the wall's normal.
  for (const bool noise : {false, true}) {
    const Drive d = drive(synthetic::Motion::kPlanar, synthetic::HouseWalls::kFurnished, 150, noise, 3);
    print(noise ? "planar, Kinect noise" : "planar, exact depth", d);
    EXPECT_EQ(d.lost_with, 0);
    EXPECT_EQ(d.predicted, d.frames - 1) << "every frame after the first is predicted by the odometry";
    EXPECT_LT(d.with_m, 0.02);
    EXPECT_LT(d.with_m, 0.1 * d.without_m) << "the slide the wall cannot see comes from the wheels";
    EXPECT_LT(d.with_m, d.wheels_alone_m + 0.002) << "and the tracker makes the wheels' estimate no worse";
    // Without the wheels nothing sees the slide: the camera must do no worse than standing still.
    EXPECT_LE(d.without_m, d.standing_still_m * 1.02);
  }
}

TEST(OdometryPrior, DownABareCorridorTheWheelsGiveItsLengthAndTheViewTheRest) {
  // A robot drives down the corridor, its camera on the floor and one wall, which place
  // everything but the way along the corridor; pictures, cabinets and doors come by now and then.
  const Drive d = drive(synthetic::Motion::kCorridor, synthetic::HouseWalls::kBare, 330, true, 5);
  print("corridor, bare walls", d);
  EXPECT_EQ(d.lost_with, 0);
  EXPECT_LT(d.with_m, 0.03);
  EXPECT_LT(d.with_m, 0.5 * d.wheels_alone_m) << "the view corrects the wheels' heading drift";
  EXPECT_LE(d.without_m, d.standing_still_m);
}

}  // namespace
}  // namespace sdf_tracker
