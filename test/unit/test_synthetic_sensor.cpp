// The synthetic sequences' data that drifts: the depth bias fixed in the image (an uncalibrated
// Kinect's) and the round trip through the house, which ends where and as it started.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// What depth_bias multiplies the depth of pixel (u, v) by: 1 + bias r^2 / r_corner^2.
double biasFactor(const PinholeCamera& camera, double bias, int u, int v) {
  auto r2 = [&camera](double x, double y) { return (x - camera.cx) * (x - camera.cx) + (y - camera.cy) * (y - camera.cy); };
  double corner_r2 = 0.0;
  for (double x : {0.0, camera.width - 1.0}) {
    for (double y : {0.0, camera.height - 1.0}) corner_r2 = std::max(corner_r2, r2(x, y));
  }
  return 1.0 + bias * r2(u, v) / corner_r2;
}

/// The room from the desk path at t_s, exact and with a depth bias of `bias`.
DepthImage roomWithBias(double t_s, double bias) {
  synthetic::NoiseModel noise;
  noise.enabled = false;
  noise.depth_bias = bias;
  return synthetic::Scene::indoorRoom().render(test::testCamera(),
                                               synthetic::cameraPose(synthetic::Motion::kDesk, t_s, 10.0), noise, 0);
}

TEST(SyntheticSensor, ADepthBiasLeavesThePrincipalPointAndLengthensTheFarthestCornerByItsValue) {
  const PinholeCamera camera = test::testCamera();
  const DepthImage exact = roomWithBias(2.0, 0.0), biased = roomWithBias(2.0, 0.02);
  const int cu = static_cast<int>(std::lround(camera.cx)), cv = static_cast<int>(std::lround(camera.cy));
  ASSERT_GT(exact.at(cu, cv), 0.0f);
  EXPECT_NEAR(biased.at(cu, cv) / exact.at(cu, cv), 1.0, 1e-4);
  // The corner farthest from the principal point is 2 % too far; the others by their distance.
  int far_u = 0, far_v = 0;
  double far_r2 = 0.0;
  for (int u : {0, camera.width - 1}) {
    for (int v : {0, camera.height - 1}) {
      ASSERT_GT(exact.at(u, v), 0.0f) << "corner " << u << ", " << v;
      const double ratio = biased.at(u, v) / exact.at(u, v);
      EXPECT_NEAR(ratio, biasFactor(camera, 0.02, u, v), 1e-4) << "corner " << u << ", " << v;
      EXPECT_GT(ratio, 1.01) << "corner " << u << ", " << v;
      const double r2 = (u - camera.cx) * (u - camera.cx) + (v - camera.cy) * (v - camera.cy);
      if (r2 > far_r2) far_r2 = r2, far_u = u, far_v = v;
    }
  }
  EXPECT_NEAR(biased.at(far_u, far_v) / exact.at(far_u, far_v), 1.02, 1.02e-4);
}

TEST(SyntheticSensor, ADepthBiasIsTheSameInEveryFrameAndAppliesWithTheNoiseOff) {
  // Two views of the room 3 s apart: at each pixel the biased depth is the exact one times the
  // same factor, whatever the scene there.
  const PinholeCamera camera = test::testCamera();
  const DepthImage exact_1 = roomWithBias(1.0, 0.0), biased_1 = roomWithBias(1.0, 0.02);
  const DepthImage exact_2 = roomWithBias(4.0, 0.0), biased_2 = roomWithBias(4.0, 0.02);
  int compared = 0;
  for (int v = 0; v < camera.height; v += 17) {
    for (int u = 0; u < camera.width; u += 23) {
      if (exact_1.at(u, v) <= 0.0f || exact_2.at(u, v) <= 0.0f) continue;
      const double ratio_1 = biased_1.at(u, v) / exact_1.at(u, v), ratio_2 = biased_2.at(u, v) / exact_2.at(u, v);
      EXPECT_NEAR(ratio_1, ratio_2, 1e-5) << "pixel " << u << ", " << v;
      EXPECT_NEAR(ratio_1, biasFactor(camera, 0.02, u, v), 1e-5) << "pixel " << u << ", " << v;
      ++compared;
    }
  }
  EXPECT_GT(compared, 150);
  // A negative bias shortens.
  const DepthImage shortened = roomWithBias(1.0, -synthetic::kMaxDepthBias);
  EXPECT_NEAR(shortened.at(0, 0) / exact_1.at(0, 0), biasFactor(camera, -synthetic::kMaxDepthBias, 0, 0), 1e-4);
}

TEST(SyntheticSensor, ADepthBiasOutsideItsRangeIsRefusedNamingTheOptionAndTheValue) {
  for (double bias : {-synthetic::kMaxDepthBias, 0.0, 0.02, synthetic::kMaxDepthBias}) {
    EXPECT_NO_THROW(synthetic::checkDepthBias(bias, "--depth-bias")) << bias;
  }
  for (double bias : {0.2, -0.15, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    try {
      synthetic::checkDepthBias(bias, "--depth-bias");
      ADD_FAILURE() << "accepted a depth bias of " << bias;
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("--depth-bias"), std::string::npos) << message;
      EXPECT_NE(message.find("[-0.1, 0.1]"), std::string::npos) << message;
      if (bias == 0.2) {
        EXPECT_NE(message.find("0.2"), std::string::npos) << message;
      }
    }
  }
  // A sequence refuses it too, before writing anything.
  synthetic::SequenceSpec spec;
  spec.frames = 1;
  spec.noise.depth_bias = 0.5;
  const std::string directory = test::scratchDirectory("depth_bias") + "/sequence";
  EXPECT_THROW(synthetic::writeSequence(directory, spec), std::invalid_argument);
}

TEST(HouseRoundTrip, WalksRoundTheHouseAndStopsWhereAndAsItStartedAlwaysSeeingTheHouse) {
  using synthetic::Motion;
  EXPECT_EQ(synthetic::parseMotion("round-trip"), Motion::kRoundTrip);
  EXPECT_EQ(synthetic::toString(Motion::kRoundTrip), "round-trip");
  EXPECT_TRUE(synthetic::goesThroughTheHouse(Motion::kRoundTrip));
  const synthetic::Scene house = synthetic::Scene::forMotion(Motion::kRoundTrip);
  synthetic::NoiseModel noise;  // the Kinect's: nothing beyond 4.5 m or at grazing angles
  const PinholeCamera camera = PinholeCamera::tumFreiburg1().scaledTo(160, 120);
  // 100 s at 30 Hz: longer than the path (about 71 s), whose end the camera stays at.
  const int kFrames = 3000;
  const Eigen::Isometry3d start = synthetic::cameraPose(Motion::kRoundTrip, 0.0, 0.0);
  Eigen::Vector3d previous = start.translation();
  double length_m = 0.0;
  for (int i = 1; i <= kFrames; ++i) {
    const Eigen::Isometry3d T_W_C = synthetic::cameraPose(Motion::kRoundTrip, i / 30.0, 0.0);
    const Eigen::Vector3d here = T_W_C.translation();
    const double step_m = (here - previous).norm();
    ASSERT_LT(step_m, 0.03) << "frame " << i << ": faster than a walk";
    length_m += step_m;
    previous = here;
    if (i % 10 == 0) {
      // Nothing within 0.25 m of the walker, from head height (0.25 m above the camera) down to
      // the shins: no wall, shelf, door frame or piece of furniture is walked through.
      for (double y : {-0.25, 0.0, 0.5, 1.0}) {
        for (int k = 0; k < 36; ++k) {
          const double a = k * M_PI / 18.0;
          double t;
          Eigen::Vector3d normal;
          const bool hit = house.intersect({here.x(), y, here.z()}, {std::cos(a), 0.0, std::sin(a)}, &t, &normal);
          ASSERT_TRUE(hit && t > 0.25) << "frame " << i << " at (" << here.x() << ", " << here.z() << "), height " << y
                                       << ", direction " << k * 10 << " deg: " << (hit ? t : -1.0) << " m";
        }
      }
    }
    if (i % 60 == 0) {
      const DepthImage depth = house.render(camera, T_W_C, noise, static_cast<uint32_t>(i));
      EXPECT_GE(depth.countMeasurements(), depth.width() * depth.height() / 2) << "frame " << i << " sees little";
    }
  }
  EXPECT_GT(length_m, 30.0);
  EXPECT_LT(length_m, 45.0);
  const Eigen::Isometry3d end = synthetic::cameraPose(Motion::kRoundTrip, kFrames / 30.0, 0.0);
  EXPECT_LT((end.translation() - start.translation()).norm(), 0.2);
  EXPECT_LT(Eigen::AngleAxisd(start.linear().transpose() * end.linear()).angle(), 5.0 * M_PI / 180.0);
  // It has stopped there.
  EXPECT_TRUE(synthetic::cameraPose(Motion::kRoundTrip, 90.0, 0.0).isApprox(end, 1e-12));
}

}  // namespace
}  // namespace sdf_tracker
