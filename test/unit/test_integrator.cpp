#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// A wall (the plane z = 2 of the single-wall scene) seen by a camera turned 20 degrees.
struct PlaneFixture : public ::testing::Test {
  void SetUp() override {
    config.dims = Eigen::Vector3i(100, 100, 60);
    config.voxel_size_m = 0.02;
    config.origin_W = Eigen::Vector3d(-1.0, -1.0, 1.4);
    config.positive_truncation_m = 0.1;
    T_W_C.linear() = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()).toRotationMatrix();
    synthetic::NoiseModel exact;
    exact.enabled = false;
    depth = synthetic::Scene::singleWall().render(camera, T_W_C, exact, 0);
  }
  /// Euclidean signed distance to the wall's front face (free space positive).
  static float planeDistance(const Eigen::Vector3f& p_W) { return 2.0f - p_W.z(); }

  VolumeConfig config;
  PinholeCamera camera = test::testCamera();
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  DepthImage depth;
};

TEST_F(PlaneFixture, FusedPlaneIsWithinOneVoxelNearTheSurface) {
  TsdfVolume volume(config);
  const Integrator integrator(IntegratorConfig{});
  ASSERT_GT(integrator.integrate(depth, camera, T_W_C, &volume), 0u);
  int checked = 0;
  for (int k = 0; k < config.dims.z(); ++k)
    for (int j = 0; j < config.dims.y(); ++j)
      for (int i = 0; i < config.dims.x(); ++i) {
        const Voxel v = volume.voxel(i, j, k);
        const float truth = planeDistance(volume.position(i, j, k));
        if (v.weight <= 0.0f || std::fabs(truth) > 0.5f * config.voxel_size_m) continue;
        EXPECT_LT(std::fabs(v.distance_m), config.voxel_size_m) << "voxel " << i << "," << j << "," << k;
        ++checked;
      }
  EXPECT_GT(checked, 1000) << "the wall should cross many observed voxels";
}

TEST_F(PlaneFixture, RespectsTruncationRulesAndTheWeightCap) {
  TsdfVolume volume(config);
  IntegratorConfig integrator_config;
  integrator_config.negative_truncation_m = -0.04;
  integrator_config.max_weight = 5.0;
  const Integrator integrator(integrator_config);
  for (int n = 0; n < 8; ++n) integrator.integrate(depth, camera, T_W_C, &volume);
  const float dmax = static_cast<float>(config.positive_truncation_m);
  for (int k = 0; k < config.dims.z(); ++k) {
    const Voxel v = volume.voxel(50, 50, k);  // on the optical axis region
    const float truth = planeDistance(volume.position(50, 50, k));
    EXPECT_LE(v.distance_m, dmax + 1e-6f);
    EXPECT_LE(v.weight, 5.0f);
    // Far behind the surface (beyond Dmin along the ray, with margin for the slant): never updated.
    if (truth < -0.1f) {
      EXPECT_EQ(v.weight, 0.0f) << "k=" << k;
    }
    // In free space beyond the band: clamped to Dmax.
    if (truth > 0.3f && v.weight > 0.0f) {
      EXPECT_FLOAT_EQ(v.distance_m, dmax);
    }
    if (std::fabs(truth) < 0.02f) {
      EXPECT_FLOAT_EQ(v.weight, 5.0f);
    }
  }
}

TEST_F(PlaneFixture, InvalidPixelsUpdateNothing) {
  TsdfVolume volume(config);
  const Integrator integrator(IntegratorConfig{});
  DepthImage invalid(camera.width, camera.height, std::numeric_limits<float>::quiet_NaN());
  invalid.at(0, 0) = 0.0f;
  invalid.at(1, 0) = -1.0f;
  invalid.at(2, 0) = std::numeric_limits<float>::infinity();
  EXPECT_EQ(integrator.integrate(invalid, camera, T_W_C, &volume), 0u);
  EXPECT_THROW(integrator.integrate(DepthImage(10, 10, 1.0f), camera, T_W_C, &volume), std::invalid_argument);
}

TEST(IntegratorConfig, RejectsEveryInvalidValue) {
  IntegratorConfig config;
  config.negative_truncation_m = 0.02;
  config.max_weight = 0.0;
  const auto violations = config.validate();
  ASSERT_EQ(violations.size(), 2u);
  EXPECT_NE(violations[0].find("negative_truncation_m must be < 0 (got 0.02)"), std::string::npos);
  EXPECT_NE(violations[1].find("max_weight must be > 0 (got 0)"), std::string::npos);
  EXPECT_THROW(Integrator{config}, std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker

namespace sdf_tracker {
namespace {

/// The plain fusion of eq. (1)-(2): every voxel of the grid, no frustum clipping. The fast path
/// must change exactly the voxels this one changes, to the same values.
void integratePlain(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                    const IntegratorConfig& config, TsdfVolume* volume) {
  const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
  for (int k = 0; k < volume->dims().z(); ++k)
    for (int j = 0; j < volume->dims().y(); ++j)
      for (int i = 0; i < volume->dims().x(); ++i) {
        const Eigen::Vector3f p_C = T_C_W * volume->position(i, j, k);
        if (p_C.z() <= 0.0f) continue;
        const Eigen::Vector2f uv = camera.project(p_C);
        const int u = static_cast<int>(std::floor(uv.x() + 0.5f)), v = static_cast<int>(std::floor(uv.y() + 0.5f));
        if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) continue;
        const float z = depth.at(u, v);
        if (!DepthImage::isMeasurement(z)) continue;
        const float d = z - p_C.z();
        if (d < config.negative_truncation_m) continue;
        Voxel voxel = volume->voxel(i, j, k);
        const float w_new = 1.0f;
        const float w_sum = voxel.weight + w_new;
        voxel.distance_m = (voxel.distance_m * voxel.weight + std::min(d, volume->positiveTruncation()) * w_new) / w_sum;
        voxel.weight = std::min(w_sum, static_cast<float>(config.max_weight));
        volume->setVoxel(i, j, k, voxel);
      }
}

TEST(Integrator, FrustumClippedFusionMatchesThePlainReference) {
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 1.0, 10.0);
  const DepthImage depth = test::renderRoom(T_W_C);
  VolumeConfig config = test::roomVolume();
  config.dims = Eigen::Vector3i(128, 96, 128);
  config.voxel_size_m = 0.02;
  TsdfVolume fast(config), plain(config);
  const IntegratorConfig integrator_config;
  Integrator(integrator_config).integrate(depth, camera, T_W_C, &fast);
  integratePlain(depth, camera, T_W_C, integrator_config, &plain);
  // The fast path walks each row incrementally; a voxel centre that lands within float rounding
  // of a pixel border may pick the neighbouring pixel. Allow that for one voxel in ten thousand.
  size_t updated = 0, differing = 0;
  for (size_t n = 0; n < fast.voxelCount(); ++n) {
    const Voxel a = fast.voxel(n), b = plain.voxel(n);
    updated += b.weight > 0.0f;
    differing += a.weight != b.weight || std::fabs(a.distance_m - b.distance_m) > 1e-5f;
  }
  EXPECT_GT(updated, 10000u);
  EXPECT_LE(differing, fast.voxelCount() / 10000);
}

}  // namespace
}  // namespace sdf_tracker
