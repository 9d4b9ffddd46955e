#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "sdf_tracker/core/io.h"
#include "sdf_tracker/core/surface.h"
#include "sdf_tracker/core/tum_sequence.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// A sphere of radius 0.3 m as a TSDF (observed everywhere, truncated at 0.1 m).
TsdfVolume sphereVolume() {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(40, 40, 40);
  config.voxel_size_m = 0.025;
  config.origin_W = Eigen::Vector3d(-0.5, -0.5, -0.5);
  TsdfVolume volume(config);
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i)
        volume.setVoxel(i, j, k, Voxel{std::min(0.1f, volume.position(i, j, k).norm() - 0.3f), 1.0f});
  return volume;
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

TEST(Surface, MeshAndCloudLieOnTheZeroLevelSetWithOutwardNormals) {
  const TsdfVolume volume = sphereVolume();
  const TriangleMesh mesh = extractMesh(volume);
  ASSERT_GT(mesh.triangles.size(), 500u);
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    EXPECT_NEAR(mesh.vertices_W[i].norm(), 0.3f, 0.01f);
    EXPECT_GT(mesh.normals_W[i].dot(mesh.vertices_W[i].normalized()), 0.9f);
  }
  // Winding: face normals point out of the sphere. Slivers under a square micrometre, where a
  // corner sits on the zero crossing, have no meaningful orientation.
  const float kSliverArea_m2 = 1e-12f;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.vertices_W[t[0]], b = mesh.vertices_W[t[1]], c = mesh.vertices_W[t[2]];
    const Eigen::Vector3f face = (b - a).cross(c - a);
    if (0.5f * face.norm() < kSliverArea_m2) continue;
    EXPECT_GT(face.normalized().dot((a + b + c).normalized()), 0.0f);
  }
  const SurfaceCloud cloud = extractSurfaceCloud(volume);
  ASSERT_GT(cloud.points_W.size(), 500u);
  for (const auto& p : cloud.points_W) EXPECT_NEAR(p.norm(), 0.3f, 0.01f);
}

TEST(Surface, UnobservedCellsMakeNoSurface) {
  TsdfVolume volume = sphereVolume();
  for (size_t i = 0; i < volume.voxelCount(); ++i) volume.setVoxel(i, Voxel{0.1f, 0.0f});
  EXPECT_TRUE(extractMesh(volume).triangles.empty());
  EXPECT_TRUE(extractSurfaceCloud(volume).points_W.empty());
}

TEST(Io, PlyMeshWritesAndLoadsBack) {
  const std::string dir = test::scratchDirectory("ply");
  const TriangleMesh mesh = extractMesh(sphereVolume());
  io::writePly(dir + "/mesh.ply", mesh);
  const TriangleMesh loaded = io::readPlyMesh(dir + "/mesh.ply");
  ASSERT_EQ(loaded.vertices_W.size(), mesh.vertices_W.size());
  ASSERT_EQ(loaded.triangles.size(), mesh.triangles.size());
  EXPECT_EQ(loaded.triangles[7], mesh.triangles[7]);
  EXPECT_EQ(loaded.vertices_W[5], mesh.vertices_W[5]);
  io::writeObj(dir + "/triangles.obj", mesh);
  std::ifstream obj(dir + "/triangles.obj");
  std::string first;
  std::getline(obj, first);
  EXPECT_EQ(first[0], '#');
}

TEST(Io, CorruptPlyIsRejectedWithTheFileName) {
  const std::string dir = test::scratchDirectory("ply_bad");
  writeFile(dir + "/bad.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\nshort");
  try {
    io::readPlyMesh(dir + "/bad.ply");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.ply"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("vertex"), std::string::npos);
  }
}

TEST(Io, VtiVolumeRoundTripsExactly) {
  const std::string dir = test::scratchDirectory("vti");
  const TsdfVolume volume = sphereVolume();
  io::writeVti(dir + "/sdf_volume.vti", volume);
  const TsdfVolume loaded = io::readVti(dir + "/sdf_volume.vti");
  EXPECT_EQ(loaded.dims(), volume.dims());
  EXPECT_DOUBLE_EQ(loaded.config().voxel_size_m, volume.config().voxel_size_m);
  EXPECT_TRUE(loaded.config().origin_W.isApprox(volume.config().origin_W));
  EXPECT_DOUBLE_EQ(loaded.config().positive_truncation_m, volume.config().positive_truncation_m);
  for (size_t i = 0; i < volume.voxelCount(); i += 97) {
    EXPECT_EQ(loaded.voxel(i).distance_m, volume.voxel(i).distance_m);
    EXPECT_EQ(loaded.voxel(i).weight, volume.voxel(i).weight);
  }
}

TEST(Io, VtiLoadsIntoCompactVoxels) {
  const std::string dir = test::scratchDirectory("vti_compact");
  const TsdfVolume volume = sphereVolume();
  io::writeVti(dir + "/v.vti", volume);
  const TsdfVolume compact = io::readVti(dir + "/v.vti", true);
  EXPECT_TRUE(compact.compact());
  // Compact voxels hold +-2 Dmax; the sphere's untruncated inside saturates there.
  const float limit = 2.0f * volume.positiveTruncation();
  for (size_t i = 0; i < volume.voxelCount(); i += 101) {
    EXPECT_NEAR(compact.voxel(i).distance_m, std::max(-limit, volume.voxel(i).distance_m), 1e-5f);
  }
}

TEST(Io, CorruptVtiIsRejected) {
  const std::string dir = test::scratchDirectory("vti_bad");
  io::writeVti(dir + "/good.vti", sphereVolume());
  std::ifstream in(dir + "/good.vti", std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  writeFile(dir + "/truncated.vti", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(io::readVti(dir + "/truncated.vti"), std::runtime_error);
  std::string negative_spacing = bytes;
  negative_spacing.replace(negative_spacing.find("Spacing=\"") + 9, 1, "-");
  EXPECT_THROW(io::readVti(dir + "/x.vti"), std::runtime_error) << "missing file";
  writeFile(dir + "/spacing.vti", negative_spacing);
  EXPECT_THROW(io::readVti(dir + "/spacing.vti"), std::runtime_error);
  writeFile(dir + "/garbage.vti", "hello");
  EXPECT_THROW(io::readVti(dir + "/garbage.vti"), std::runtime_error);
}

TEST(Io, TrajectoryRoundTripsAndBadLinesAreNamed) {
  const std::string dir = test::scratchDirectory("traj");
  std::vector<io::StampedPose> poses;
  for (int i = 0; i < 5; ++i) poses.push_back({i * 0.1, test::perturbed(Eigen::Isometry3d::Identity(), 0.1 * i, 0.05 * i)});
  io::writeTrajectory(dir + "/t.txt", poses);
  const auto loaded = io::readTrajectory(dir + "/t.txt");
  ASSERT_EQ(loaded.size(), 5u);
  EXPECT_NEAR(loaded[3].timestamp_s, 0.3, 1e-9);
  EXPECT_TRUE(loaded[4].T_W_C.isApprox(poses[4].T_W_C, 1e-6));
  writeFile(dir + "/bad.txt", "# header\n0.0 1 2 3 0 0 0 1\n0.1 1 2 nan 0 0 0 1\n");
  try {
    io::readTrajectory(dir + "/bad.txt");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
}

TEST(Io, DepthPngRoundTripsAtTheDepthFactor) {
  const std::string dir = test::scratchDirectory("png");
  DepthImage depth(4, 3, 0.0f);
  depth.at(1, 1) = 1.2346f;
  depth.at(3, 2) = std::nanf("");
  io::writeDepthPng(dir + "/d.png", depth, 5000.0);
  const DepthImage loaded = io::readDepthPng(dir + "/d.png", 5000.0);
  EXPECT_NEAR(loaded.at(1, 1), 1.2346f, 1.0f / 5000.0f);
  EXPECT_EQ(loaded.at(3, 2), 0.0f);
  EXPECT_EQ(loaded.countMeasurements(), 1);
  writeFile(dir + "/corrupt.png", "\x89PNG\r\n\x1a\nnot really");
  EXPECT_THROW(io::readDepthPng(dir + "/corrupt.png", 5000.0), std::runtime_error);
}

TEST(TumSequence, ReadsIntrinsicsFileOrFallsBackToFreiburg1) {
  const std::string dir = test::scratchDirectory("seq");
  synthetic::SequenceSpec spec;
  spec.frames = 3;
  spec.camera = test::testCamera();
  synthetic::writeSequence(dir, spec);
  TumSequence sequence = TumSequence::open(dir);
  EXPECT_EQ(sequence.size(), 3u);
  EXPECT_EQ(sequence.intrinsicsSource(), "intrinsics.txt");
  EXPECT_EQ(sequence.camera().width, 320);
  EXPECT_EQ(sequence.groundTruth().size(), 3u);
  EXPECT_GT(sequence.depth(2).countMeasurements(), 10000);

  std::remove((dir + "/intrinsics.txt").c_str());
  const TumSequence defaults = TumSequence::open(dir);
  EXPECT_EQ(defaults.intrinsicsSource(), "TUM freiburg1 defaults");
  EXPECT_DOUBLE_EQ(defaults.camera().fx, 517.3);
  EXPECT_DOUBLE_EQ(defaults.depthFactor(), 5000.0);
  // The 320x240 frames do not match the 640x480 default intrinsics: a clear error, not garbage.
  EXPECT_THROW(defaults.depth(0), std::runtime_error);
  EXPECT_THROW(TumSequence::open(dir + "/missing"), std::runtime_error);
}

}  // namespace
}  // namespace sdf_tracker
