#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_undistortion.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/util/memory.h"
#include "test_helpers.h"

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

/// TUM freiburg1's published lens (the strongest distortion a supported camera has).
PinholeCamera distortedCamera() {
  PinholeCamera camera = PinholeCamera::tumFreiburg1();
  camera.distortion = PinholeCamera::tumCamera("freiburg1")->distortion;
  return camera;
}

TEST(LensDistortion, UndistortInvertsDistortAcrossTheImage) {
  const PinholeCamera camera = distortedCamera();
  for (const Eigen::Vector2d& pixel : {Eigen::Vector2d(0, 0), Eigen::Vector2d(639, 479), Eigen::Vector2d(320, 10),
                                      Eigen::Vector2d(318.6, 255.3), Eigen::Vector2d(5, 400)}) {
    const Eigen::Vector2d seen((pixel.x() - camera.cx) / camera.fx, (pixel.y() - camera.cy) / camera.fy);
    const Eigen::Vector2d ideal = camera.distortion.undistort(seen);
    EXPECT_LT((camera.distortion.distort(ideal) - seen).norm() * camera.fx, 1e-6) << pixel.transpose();
  }
  // The corner moves by pixels: the distortion is not negligible.
  const Eigen::Vector2d corner(-camera.cx / camera.fx, -camera.cy / camera.fy);
  EXPECT_GT((camera.distortion.undistort(corner) - corner).norm() * camera.fx, 5.0);
  EXPECT_EQ(LensDistortion().distort(corner), corner);
}

TEST(PinholeCamera, IntrinsicsThatAreATumCamerasAreRecognisedForAHintOnly) {
  EXPECT_EQ(PinholeCamera::tumCameraWithIntrinsicsOf(PinholeCamera::tumFreiburg1()), "freiburg1");
  PinholeCamera freiburg2 = PinholeCamera::tumFreiburg1();
  freiburg2.fx = 520.9, freiburg2.fy = 521.0, freiburg2.cx = 325.1, freiburg2.cy = 249.7;
  EXPECT_EQ(PinholeCamera::tumCameraWithIntrinsicsOf(freiburg2), "freiburg2");
  EXPECT_EQ(PinholeCamera::tumCameraWithIntrinsicsOf(*PinholeCamera::tumCamera("freiburg3")), "")
      << "TUM undistorted freiburg3's images: nothing the user would miss";
  EXPECT_EQ(PinholeCamera::tumCameraWithIntrinsicsOf(PinholeCamera()), "") << "a generic Kinect";
  EXPECT_EQ(PinholeCamera::tumCameraWithIntrinsicsOf(test::testCamera()), "") << "another resolution";
}

TEST(PinholeCamera, TumCamerasCarryTheirPublishedCalibrationByName) {
  const std::optional<PinholeCamera> freiburg1 = PinholeCamera::tumCamera("freiburg1");
  ASSERT_TRUE(freiburg1.has_value());
  EXPECT_DOUBLE_EQ(freiburg1->fx, 517.3);
  EXPECT_DOUBLE_EQ(freiburg1->cy, 255.3);
  EXPECT_DOUBLE_EQ(freiburg1->distortion.k1, 0.2624);
  EXPECT_EQ(freiburg1->withoutDistortion(), PinholeCamera::tumFreiburg1());
  const std::optional<PinholeCamera> freiburg2 = PinholeCamera::tumCamera("freiburg2");
  ASSERT_TRUE(freiburg2.has_value());
  EXPECT_DOUBLE_EQ(freiburg2->fx, 520.9);
  EXPECT_DOUBLE_EQ(freiburg2->distortion.k1, 0.2312);
  const std::optional<PinholeCamera> freiburg3 = PinholeCamera::tumCamera("freiburg3");
  ASSERT_TRUE(freiburg3.has_value());
  EXPECT_DOUBLE_EQ(freiburg3->fy, 539.2);
  EXPECT_TRUE(freiburg3->distortion.isZero()) << "TUM undistorted freiburg3's images";
  EXPECT_FALSE(PinholeCamera::tumCamera("fr1").has_value());
  EXPECT_FALSE(PinholeCamera::tumCamera("").has_value());
  EXPECT_EQ(PinholeCamera::tumCameraNames(), "freiburg1, freiburg2, freiburg3");
}

TEST(PinholeCamera, TheOpenNiDriversDefaultIsItsFocalLengthAtTheImageCentre) {
  const PinholeCamera vga = PinholeCamera::openNiDefault(640, 480);
  EXPECT_EQ(vga.fx, 525.0);
  EXPECT_EQ(vga.fy, 525.0);
  EXPECT_EQ(vga.cx, 319.5);
  EXPECT_EQ(vga.cy, 239.5);
  EXPECT_TRUE(vga.distortion.isZero());
  const PinholeCamera qvga = PinholeCamera::openNiDefault(320, 240);
  EXPECT_EQ(qvga.fx, 262.5);
  EXPECT_EQ(qvga.cx, 159.5);
  EXPECT_EQ(qvga.cy, 119.5);
}

TEST(PinholeCamera, ValidateRejectsANonFiniteDistortion) {
  PinholeCamera camera;
  camera.distortion.k2 = std::nan("");
  const auto violations = camera.validate();
  ASSERT_EQ(violations.size(), 1u);
  EXPECT_NE(violations[0].find("k2"), std::string::npos);
}

TEST(DepthUndistortion, GivesTheImageAnIdealLensWouldHaveTaken) {
  const PinholeCamera lens = distortedCamera();
  DepthUndistortion undistortion(lens);
  const PinholeCamera ideal = lens.withoutDistortion();
  EXPECT_TRUE(ideal.distortion.isZero());
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, 10.0);
  const DepthImage seen = test::renderRoom(T_W_C, lens);
  const DepthImage expected = test::renderRoom(T_W_C, ideal);
  auto agreement = [&](const DepthImage& image) {  // share of pixels within 1 cm of the ideal image
    int close = 0, both = 0;
    for (int v = 0; v < ideal.height; ++v) {
      for (int u = 0; u < ideal.width; ++u) {
        if (!DepthImage::isMeasurement(image.at(u, v)) || !DepthImage::isMeasurement(expected.at(u, v))) continue;
        ++both;
        close += std::abs(image.at(u, v) - expected.at(u, v)) < 0.01f;
      }
    }
    return static_cast<double>(close) / both;
  };
  const DepthImage undistorted = undistortion.apply(seen);
  EXPECT_GT(agreement(undistorted), 0.97);
  EXPECT_LT(agreement(seen), agreement(undistorted) - 0.05) << "the test scene shows the distortion";
  EXPECT_GT(undistorted.countMeasurements(), seen.countMeasurements() * 0.9);
  EXPECT_THROW(undistortion.apply(DepthImage(320, 240)), std::invalid_argument);
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

TEST(Memory, ARequestBeyondWhatIsAvailableIsRefusedSayingHowMuch) {
  EXPECT_NO_THROW(requireMemory(1 << 20, "a small grid", 2 << 20));
  try {
    requireMemory(3ull << 30, "a grid of 1024x1024x384 voxels", 1ull << 30);
    FAIL() << "3 GiB fitted into 1 GiB";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "a grid of 1024x1024x384 voxels needs 3072 MiB of memory, but 1024 MiB are available");
  }
  EXPECT_GT(availableMemoryBytes(), 0u);
}

TEST(TsdfVolume, AGridBeyondTheProcesssMemoryLimitIsRefusedByNameNotByBadAlloc) {
  // A 2 GiB grid in a process that may allocate 512 MiB more (ulimit -v).
  const bool refused_by_name = test::withinMemory(512, [] {
    VolumeConfig config;
    config.dims = Eigen::Vector3i(640, 640, 640);
    try {
      TsdfVolume volume(config);
    } catch (const std::runtime_error& e) {
      return std::string(e.what()).rfind("a dense grid of 640x640x640 voxels needs 2000 MiB of memory, but ", 0) == 0;
    } catch (const std::bad_alloc&) {
    }
    return false;  // allocated although the limit forbids it, or std::bad_alloc
  });
  EXPECT_TRUE(refused_by_name);
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
