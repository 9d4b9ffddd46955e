#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "sdf_tracker/surface/raycaster.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// The room fused from the desk path's first half second (every third frame: noise-free frames
/// need no averaging), then cast from its start pose.
class RaycastFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    volume = std::make_unique<TsdfVolume>(test::roomVolume());
    const Integrator integrator{IntegratorConfig{}};
    for (int i = 0; i < 15; i += 3) {
      const Eigen::Isometry3d T = synthetic::cameraPose(synthetic::Motion::kDesk, i / 30.0, 10.0);
      integrator.integrate(test::renderRoom(T), camera, T, volume.get());
    }
    T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, 10.0);
    truth = test::renderRoom(T_W_C);
  }

  /// Median |cast - truth| over pixels where both exist, and how many there were.
  std::pair<double, int> medianDepthError(const DepthImage& cast) const {
    std::vector<double> errors;
    for (int v = 0; v < cast.height(); ++v)
      for (int u = 0; u < cast.width(); ++u)
        if (DepthImage::isMeasurement(cast.at(u, v)) && DepthImage::isMeasurement(truth.at(u, v))) {
          errors.push_back(std::fabs(cast.at(u, v) - truth.at(u, v)));
        }
    if (errors.empty()) return {1e9, 0};
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    return {errors[errors.size() / 2], static_cast<int>(errors.size())};
  }

  PinholeCamera camera = test::testCamera();
  std::unique_ptr<TsdfVolume> volume;
  Eigen::Isometry3d T_W_C;
  DepthImage truth;
};

TEST_F(RaycastFixture, VirtualSensorReproducesTheSceneDepthWithinAFractionOfAVoxel) {
  const RaycastImage cast = raycast(*volume, camera, T_W_C, RaycastConfig{});
  const auto [median_error, pixels] = medianDepthError(cast.depth);
  EXPECT_GT(pixels, camera.width * camera.height / 3) << "the desk area must be hit";
  EXPECT_LT(median_error, 0.25 * volume->voxelSize());
  // Normals face the camera (they point into free space, towards the viewer).
  int facing = 0, with_normal = 0;
  for (int v = 0; v < camera.height; v += 4)
    for (int u = 0; u < camera.width; u += 4) {
      const Eigen::Vector3f& n = cast.normals_C[static_cast<size_t>(v) * camera.width + u];
      if (!n.allFinite()) continue;
      ++with_normal;
      facing += n.dot(camera.backProject(u, v, 1.0f)) < 0.0f;
      EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
    }
  EXPECT_GT(facing, 0.98 * with_normal);
}

TEST_F(RaycastFixture, RefiningMeasuredDepthMovesItOntoTheSurface) {
  // A measured image 3 mm too far everywhere: refinement pulls it back to the fused surface.
  DepthImage measured = truth;
  for (int v = 0; v < measured.height(); ++v)
    for (int u = 0; u < measured.width(); ++u)
      if (DepthImage::isMeasurement(measured.at(u, v))) measured.at(u, v) += 0.003f;
  const double before = medianDepthError(measured).first;
  const RaycastImage refined = raycast(*volume, camera, T_W_C, RaycastConfig{}, &measured);
  EXPECT_LT(medianDepthError(refined.depth).first, 0.5 * before);
}

TEST(Raycast, RejectsInvalidConfigAndMismatchedSeed) {
  TsdfVolume volume(test::roomVolume());
  RaycastConfig config;
  config.max_depth_m = 0.1;
  EXPECT_THROW(raycast(volume, test::testCamera(), Eigen::Isometry3d::Identity(), config), std::invalid_argument);
  const DepthImage wrong(10, 10, 1.0f);
  EXPECT_THROW(raycast(volume, test::testCamera(), Eigen::Isometry3d::Identity(), RaycastConfig{}, &wrong),
               std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
