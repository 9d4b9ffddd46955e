#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "sdf_tracker/core/camera.h"
#include "sdf_tracker/core/tsdf_volume.h"

namespace sdf_tracker {
namespace {

// Trilinear interpolation reproduces a linear field exactly (up to float rounding).
constexpr float kLinearTolerance = 1e-5f;

TEST(PinholeCamera, ProjectInvertsBackProject) {
  const PinholeCamera camera = PinholeCamera::tumFreiburg1();
  const Eigen::Vector3f p = camera.backProject(100.25f, 321.5f, 2.5f);
  const Eigen::Vector2f uv = camera.project(p);
  EXPECT_NEAR(uv.x(), 100.25f, 1e-3f);
  EXPECT_NEAR(uv.y(), 321.5f, 1e-3f);
  EXPECT_FLOAT_EQ(p.z(), 2.5f);
}

TEST(PinholeCamera, ScalesToQvgaAndQqvgaLikeTheReference) {
  PinholeCamera vga;  // reference defaults: 520, 520, 319.5, 239.5
  const PinholeCamera qvga = vga.scaledTo(320, 240);
  EXPECT_DOUBLE_EQ(qvga.fx, 260.0);
  EXPECT_DOUBLE_EQ(qvga.cx, 159.5);
  EXPECT_DOUBLE_EQ(qvga.cy, 119.5);
  const PinholeCamera qqvga = vga.scaledTo(160, 120);
  EXPECT_DOUBLE_EQ(qqvga.fy, 130.0);
  EXPECT_DOUBLE_EQ(qqvga.cx, 79.5);
  // The same ray through the scaled principal point.
  EXPECT_THROW(vga.scaledTo(300, 240), std::invalid_argument);
}

TEST(PinholeCamera, ValidateNamesEveryViolation) {
  PinholeCamera camera;
  camera.fx = -1.0;
  camera.height = 0;
  const auto violations = camera.validate();
  ASSERT_EQ(violations.size(), 2u);
  EXPECT_NE(violations[0].find("fx must be > 0 (got -1)"), std::string::npos);
  EXPECT_NE(violations[1].find("height"), std::string::npos);
}

TEST(TsdfVolume, IndexingIsXFastestAndPositionsFollowTheOrigin) {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(4, 5, 6);
  config.voxel_size_m = 0.5;
  config.origin_W = Eigen::Vector3d(1, 2, 3);
  const TsdfVolume volume(config);
  EXPECT_EQ(volume.voxelCount(), 120u);
  EXPECT_EQ(volume.index(1, 0, 0), 1u);
  EXPECT_EQ(volume.index(0, 1, 0), 4u);
  EXPECT_EQ(volume.index(0, 0, 1), 20u);
  EXPECT_EQ(volume.index(3, 4, 5), 119u);
  EXPECT_TRUE(volume.position(2, 1, 3).isApprox(Eigen::Vector3f(2.0f, 2.5f, 4.5f)));
  EXPECT_EQ(volume.voxel(3, 4, 5).weight, 0.0f);
  EXPECT_FLOAT_EQ(volume.voxel(3, 4, 5).distance_m, static_cast<float>(config.positive_truncation_m));
}

TEST(TsdfVolume, RejectsInvalidGeometryNamingEachField) {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(0, 10, 10);
  config.voxel_size_m = -0.1;
  try {
    TsdfVolume volume(config);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("dims.x"), std::string::npos) << what;
    EXPECT_NE(what.find("voxel_size_m must be > 0 (got -0.1)"), std::string::npos) << what;
  }
}

/// Fills every voxel with f(position) and weight 1.
template <typename Field>
TsdfVolume filledVolume(Field f) {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(40, 40, 40);
  config.voxel_size_m = 0.05;
  config.origin_W = Eigen::Vector3d(-1, -1, -1);
  config.positive_truncation_m = 10.0;  // no truncation: compare with the analytic field
  TsdfVolume volume(config);
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) volume.setVoxel(i, j, k, Voxel{f(volume.position(i, j, k)), 1.0f});
  return volume;
}

TEST(TsdfVolume, TrilinearValueAndGradientMatchAnAnalyticPlane) {
  const Eigen::Vector3f n = Eigen::Vector3f(1, -2, 0.5).normalized();
  auto plane = [&n](const Eigen::Vector3f& p) { return n.dot(p) - 0.1f; };
  const TsdfVolume volume = filledVolume(plane);
  for (const Eigen::Vector3f& p : {Eigen::Vector3f(0.013f, -0.27f, 0.4f), Eigen::Vector3f(-0.5f, 0.33f, -0.07f)}) {
    FieldSample s;
    ASSERT_TRUE(volume.sample(p, &s));
    EXPECT_NEAR(s.distance_m, plane(p), kLinearTolerance);
    EXPECT_LT((s.gradient - n).norm(), 1e-4f);
  }
}

TEST(TsdfVolume, TrilinearValueAndGradientApproximateAnAnalyticSphere) {
  const float radius = 0.5f;
  auto sphere = [radius](const Eigen::Vector3f& p) { return p.norm() - radius; };
  const TsdfVolume volume = filledVolume(sphere);
  // Interpolating a curved field: the error is second order in the voxel size.
  const float value_tolerance = 0.05f * 0.05f;
  for (const Eigen::Vector3f& p : {Eigen::Vector3f(0.31f, 0.2f, 0.3f), Eigen::Vector3f(-0.1f, -0.45f, 0.12f)}) {
    FieldSample s;
    ASSERT_TRUE(volume.sample(p, &s));
    EXPECT_NEAR(s.distance_m, sphere(p), value_tolerance);
    EXPECT_GT(s.gradient.normalized().dot(p.normalized()), 0.995f);
    EXPECT_NEAR(s.gradient.norm(), 1.0f, 0.05f);
  }
}

/// The same 20^3 grid twice: float voxels, then compact ones.
std::pair<TsdfVolume, TsdfVolume> floatAndCompactGrids(double voxel_size_m) {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(20, 20, 20);
  config.voxel_size_m = voxel_size_m;
  config.positive_truncation_m = 0.1;
  TsdfVolume full(config);
  config.compact_voxels = true;
  return {std::move(full), TsdfVolume(config)};
}

TEST(TsdfVolume, CompactVoxelsHalveMemoryAndQuantiseFinely) {
  auto [full, compact] = floatAndCompactGrids(0.05);
  EXPECT_EQ(compact.memoryBytes() * 2, full.memoryBytes());
  EXPECT_EQ(compact.voxel(3, 3, 3).weight, 0.0f);
  EXPECT_NEAR(compact.voxel(3, 3, 3).distance_m, 0.1f, 1e-5f);
  // One distance step is 2 Dmax / 32767, one weight step 1/256; a tiny weight still counts.
  const float distance_step = 0.2f / 32767.0f;
  for (const Voxel v : {Voxel{0.0123456f, 3.3f}, Voxel{-0.0987f, 63.9f}, Voxel{0.05f, 0.001f}}) {
    compact.setVoxel(5, 6, 7, v);
    EXPECT_NEAR(compact.voxel(5, 6, 7).distance_m, v.distance_m, distance_step);
    EXPECT_NEAR(compact.voxel(5, 6, 7).weight, v.weight, 1.0f / 256.0f);
    EXPECT_GT(compact.voxel(5, 6, 7).weight, 0.0f);
  }
  // Out-of-range values saturate instead of wrapping around.
  compact.setVoxel(1, 1, 1, Voxel{-5.0f, 1000.0f});
  EXPECT_NEAR(compact.voxel(1, 1, 1).distance_m, -0.2f, distance_step);
  EXPECT_NEAR(compact.voxel(1, 1, 1).weight, 65535.0f / 256.0f, 1e-3f);
}

TEST(TsdfVolume, CompactTrilinearSamplingMatchesTheFloatGrid) {
  const Eigen::Vector3f n = Eigen::Vector3f(0.3f, -1.0f, 0.7f).normalized();
  auto [full, compact] = floatAndCompactGrids(0.01);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const Voxel v{n.dot(full.position(i, j, k)) - 0.1f, 2.0f};
        full.setVoxel(i, j, k, v);
        compact.setVoxel(i, j, k, v);
      }
  FieldSample a, b;
  const Eigen::Vector3f p(0.083f, 0.121f, 0.0557f);
  ASSERT_TRUE(full.sample(p, &a));
  ASSERT_TRUE(compact.sample(p, &b));
  EXPECT_NEAR(a.distance_m, b.distance_m, 1e-5f);
  EXPECT_LT((a.gradient - b.gradient).norm(), 2e-3f);
}

TEST(TsdfVolume, SamplingRejectsUnobservedOutsideAndNaN) {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(10, 10, 10);
  config.voxel_size_m = 0.1;
  TsdfVolume volume(config);
  FieldSample s;
  EXPECT_FALSE(volume.sample(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &s)) << "unobserved voxels must not be sampled";
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) volume.setVoxel(i, j, k, Voxel{volume.voxel(i, j, k).distance_m, 1.0f});
  EXPECT_TRUE(volume.sample(Eigen::Vector3f(0.5f, 0.5f, 0.5f), &s));
  EXPECT_FALSE(volume.sample(Eigen::Vector3f(-0.01f, 0.5f, 0.5f), &s));
  EXPECT_FALSE(volume.sample(Eigen::Vector3f(0.5f, 0.95f, 0.5f), &s));
  EXPECT_FALSE(volume.sample(Eigen::Vector3f(std::nanf(""), 0.5f, 0.5f), &s));
}

}  // namespace
}  // namespace sdf_tracker
