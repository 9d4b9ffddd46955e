#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <limits>

#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/sdfmap_file.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/surface/surface.h"
#include "sdfmap_bytes.h"
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

using test::writeFile;

/// What `action` threw as std::runtime_error, or "" when it threw nothing.
std::string runtimeErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
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
  // By extension: OBJ, PLY, and nothing under a name that promises another format.
  io::writeMesh(dir + "/by_name.ply", mesh);
  EXPECT_EQ(io::readPlyMesh(dir + "/by_name.ply").triangles.size(), mesh.triangles.size());
  try {
    io::writeMesh(dir + "/mesh.stl", mesh);
    ADD_FAILURE() << "a PLY was written as mesh.stl";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), dir + "/mesh.stl: unknown mesh file extension (known: .ply, .obj)");
  }
  EXPECT_FALSE(std::ifstream(dir + "/mesh.stl").good());
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
    EXPECT_NE(std::string(e.what()).find("10 vertices"), std::string::npos) << e.what();
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

/// A sparse map with blocks on both sides of the origin, each voxel's value its own.
SparseTsdfMap patternedSparseMap() {
  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = 0.02;
  config.origin_W = Eigen::Vector3d(0.1, -0.2, 0.3);
  config.positive_truncation_m = 0.08;
  SparseTsdfMap map(config);
  for (const SparseTsdfMap::BlockIndex& index : {SparseTsdfMap::BlockIndex(0, 0, 0), SparseTsdfMap::BlockIndex(-3, 5, -1),
                                                 SparseTsdfMap::BlockIndex(1000, -2000, 7)}) {
    VoxelBlock& block = map.allocate(index);
    for (int v = 0; v < kBlockVoxels; ++v) {
      block.voxels[v] = Voxel{0.08f * std::sin(0.37f * v + index.x()), static_cast<float>(v % 5)};
    }
  }
  return map;
}

/// The message readSparseMap gives for these bytes ("" when it loads them).
std::string sparseMapError(const std::string& dir, const std::string& bytes) {
  writeFile(dir + "/edited.sdfmap", bytes);
  try {
    io::readSparseMap(dir + "/edited.sdfmap");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(Io, SparseMapRoundTripsEveryBlockExactly) {
  const std::string dir = test::scratchDirectory("sdfmap");
  const SparseTsdfMap map = patternedSparseMap();
  io::writeMap(dir + "/map.sdfmap", map);
  EXPECT_FALSE(io::removeStaleTemporary(dir + "/map.sdfmap")) << "no temporary file is left behind";
  const std::unique_ptr<TsdfMap> loaded = io::readMap(dir + "/map.sdfmap");
  ASSERT_EQ(loaded->type(), MapType::kSparse);
  const auto& sparse = static_cast<const SparseTsdfMap&>(*loaded);
  EXPECT_TRUE(sparse.config().sameLattice(map.config()));
  ASSERT_EQ(sparse.blockIndices(), map.blockIndices());
  for (const SparseTsdfMap::BlockIndex& index : map.blockIndices()) {
    const VoxelBlock& a = *map.find(index);
    const VoxelBlock& b = *sparse.find(index);
    for (int v = 0; v < kBlockVoxels; ++v) {
      ASSERT_EQ(a.voxels[v].distance_m, b.voxels[v].distance_m) << index.transpose() << " voxel " << v;
      ASSERT_EQ(a.voxels[v].weight, b.voxels[v].weight) << index.transpose() << " voxel " << v;
    }
  }
}

TEST(Io, ADenseGridSavedAsASparseMapKeepsEveryObservedVoxel) {
  const std::string dir = test::scratchDirectory("sdfmap_dense");
  TsdfVolume volume = sphereVolume();
  for (int k = 0; k < 40; ++k)  // leave part of the grid unobserved: it must stay so
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 12; ++i) volume.setVoxel(i, j, k, Voxel{volume.positiveTruncation(), 0.0f});
  io::writeMap(dir + "/sphere.sdfmap", volume);
  const SparseTsdfMap sparse = io::readSparseMap(dir + "/sphere.sdfmap");
  EXPECT_EQ(sparse.blockCount(), 4u * 5u * 5u) << "blocks wholly unobserved are not stored";
  for (int k = 0; k < 40; ++k) {
    for (int j = 0; j < 40; ++j) {
      for (int i = 0; i < 40; ++i) {
        const Voxel a = volume.voxel(i, j, k), b = sparse.voxel({i, j, k});
        ASSERT_EQ(a.weight, b.weight) << i << " " << j << " " << k;
        if (a.weight > 0.0f) {
          ASSERT_EQ(a.distance_m, b.distance_m) << i << " " << j << " " << k;
        }
      }
    }
  }
}

using test::asOlderSdfmapVersion;
using test::readBytes;
using test::withValidChecksum;
constexpr size_t kPlacesHeader = test::kSdfmapPlacesHeader;
constexpr size_t kMapFrame = test::kSdfmapMapFrame;
constexpr size_t kFirstBlock = test::kSdfmapFirstBlock;

TEST(Io, CorruptSparseMapsAreRefusedSayingWhatIsWrong) {
  const std::string dir = test::scratchDirectory("sdfmap_bad");
  io::writeSparseMap(dir + "/good.sdfmap", patternedSparseMap());
  const std::string good = readBytes(dir + "/good.sdfmap");
  ASSERT_EQ(sparseMapError(dir, good), "");
  auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  EXPECT_TRUE(has(sparseMapError(dir, good.substr(0, good.size() - 100)), "truncated"));
  EXPECT_TRUE(has(sparseMapError(dir, good + "x"), "truncated"));
  EXPECT_TRUE(has(sparseMapError(dir, "hello"), "not an sdf_tracker map"));
  std::string version = good;
  version[8] = 6;
  EXPECT_TRUE(has(sparseMapError(dir, version), "format version 6; this build reads versions 1 to 5"))
      << sparseMapError(dir, version);
  std::string flipped = good;
  flipped[kFirstBlock + 12 + 1000] ^= 0x01;  // one bit of a voxel of the first block
  EXPECT_TRUE(has(sparseMapError(dir, flipped), "checksum"));
  std::string not_a_number = good;
  const float nan = std::nanf("");
  not_a_number.replace(kFirstBlock + 12 + 8 * 5, sizeof(float), reinterpret_cast<const char*>(&nan), sizeof(float));
  EXPECT_TRUE(has(sparseMapError(dir, not_a_number), "voxel 5: distance nan m is not within [-10, 0.08] m"))
      << sparseMapError(dir, not_a_number);
  // Values no fusion writes, even with a valid checksum: a weight beyond any MaxWeight, a distance
  // beyond the band.
  std::string heavy = good;
  const float huge = 1e30f;
  heavy.replace(kFirstBlock + 12 + 8 * 6 + 4, sizeof(float), reinterpret_cast<const char*>(&huge), sizeof(float));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(heavy)), "voxel 6: weight 1e+30 is not within [0, 1e+09]"))
      << sparseMapError(dir, withValidChecksum(heavy));
  std::string far = good;
  far.replace(kFirstBlock + 12 + 8 * 7, sizeof(float), reinterpret_cast<const char*>(&huge), sizeof(float));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(far)), "voxel 7: distance 1e+30 m is not within [-10, 0.08] m"))
      << sparseMapError(dir, withValidChecksum(far));
  std::string huge_count = good;
  const uint64_t count = 1ull << 40;
  huge_count.replace(56, sizeof(count), reinterpret_cast<const char*>(&count), sizeof(count));
  EXPECT_TRUE(has(sparseMapError(dir, huge_count), "lists 1099511627776 blocks"));
  const uint64_t absurd_count = 1ull << 62;  // count x block size wraps in 64 bits
  huge_count.replace(56, sizeof(absurd_count), reinterpret_cast<const char*>(&absurd_count), sizeof(absurd_count));
  EXPECT_TRUE(has(sparseMapError(dir, huge_count), "lists 4611686018427387904 blocks, 0 keyframes, 1 submaps and 0 "
                                                   "edges (more than 2^60 bytes after"))
      << sparseMapError(dir, huge_count);
  EXPECT_THROW(io::readMap(dir + "/good.map"), std::runtime_error) << "unknown extension";
  EXPECT_THROW(io::writeMap(dir + "/out.bin", patternedSparseMap()), std::runtime_error) << "unknown extension";
}

TEST(Io, ASparseMapBeyondTheMapsReachIsRefusedEvenWithAValidChecksum) {
  const std::string dir = test::scratchDirectory("sdfmap_reach");
  io::writeSparseMap(dir + "/good.sdfmap", patternedSparseMap());
  const std::string good = readBytes(dir + "/good.sdfmap");
  ASSERT_EQ(sparseMapError(dir, withValidChecksum(good)), "") << "the forger's checksum is the writer's";
  auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  std::string lowest_index = good;
  const int32_t int_min = std::numeric_limits<int32_t>::min();
  lowest_index.replace(kFirstBlock, sizeof(int_min), reinterpret_cast<const char*>(&int_min), sizeof(int_min));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(lowest_index)), "lies beyond the map's reach"))
      << sparseMapError(dir, withValidChecksum(lowest_index));
  std::string far_origin = good;
  const double far = 1e300;
  far_origin.replace(32, sizeof(far), reinterpret_cast<const char*>(&far), sizeof(far));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(far_origin)), "invalid map geometry: origin_W.x"))
      << sparseMapError(dir, withValidChecksum(far_origin));
}

/// A place memory of three keyframes with codes of every fern value.
PlaceMemory patternedPlaces() {
  PlaceMemoryConfig config;
  config.descriptor.fern_count = 20;
  config.descriptor.seed = 7;
  PlaceMemory places(config);
  for (int k = 0; k < 3; ++k) {
    Keyframe keyframe;
    keyframe.T_W_C = test::perturbed(Eigen::Isometry3d::Identity(), 0.3 * k, 0.2 * k);
    for (int f = 0; f < 20; ++f) keyframe.code.push_back(static_cast<uint8_t>((f + k) % 16));
    places.add(keyframe);
  }
  return places;
}

TEST(Io, TheMapFileKeepsThePlaceMemoryAndAFirstVersionFileStillLoads) {
  const std::string dir = test::scratchDirectory("sdfmap_places");
  const PlaceMemory places = patternedPlaces();
  io::writeMap(dir + "/map.sdfmap", patternedSparseMap(), &places);
  std::unique_ptr<PlaceMemory> loaded;
  PlaceMemoryConfig settings;
  settings.max_keyframes = 2;  // the file's keyframes are all kept all the same
  const std::unique_ptr<TsdfMap> map = io::readMap(dir + "/map.sdfmap", false, &loaded, settings);
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->config().descriptor, places.config().descriptor) << "the file's descriptor, not the settings'";
  ASSERT_EQ(loaded->keyframes().size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(loaded->keyframes()[k].code, places.keyframes()[k].code);
    EXPECT_TRUE(loaded->keyframes()[k].T_W_C.isApprox(places.keyframes()[k].T_W_C, 1e-12));
  }
  EXPECT_EQ(static_cast<const SparseTsdfMap&>(*map).blockIndices(), patternedSparseMap().blockIndices());

  // Version 1: the same blocks without the place memory's header or keyframes (nor the map frame).
  const std::string v5 = readBytes(dir + "/map.sdfmap");
  const size_t keyframes = 3 * test::sdfmapKeyframeBytes(20);
  writeFile(dir + "/v1.sdfmap", asOlderSdfmapVersion(v5, 1, 3, 20));
  const std::unique_ptr<TsdfMap> old = io::readMap(dir + "/v1.sdfmap", false, &loaded);
  EXPECT_FALSE(loaded) << "a version 1 file has no place memory";
  EXPECT_EQ(static_cast<const SparseTsdfMap&>(*old).blockIndices(), patternedSparseMap().blockIndices());

  // Version 4: one map, its keyframes without their submaps.
  writeFile(dir + "/v4.sdfmap", asOlderSdfmapVersion(v5, 4, 3, 20));
  const std::unique_ptr<TsdfMap> four = io::readMap(dir + "/v4.sdfmap", false, &loaded);
  ASSERT_TRUE(loaded);
  ASSERT_EQ(loaded->keyframes().size(), 3u);
  EXPECT_TRUE(loaded->keyframes()[2].T_W_C.isApprox(places.keyframes()[2].T_W_C, 1e-12));
  EXPECT_EQ(static_cast<const SparseTsdfMap&>(*four).blockIndices(), patternedSparseMap().blockIndices());

  // Keyframes no writer makes are refused by name, even with a valid checksum.
  auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  const size_t first_keyframe = v5.size() - 8 - keyframes;
  std::string skewed = v5;
  const double two = 2.0;
  skewed.replace(first_keyframe + 24, sizeof(two), reinterpret_cast<const char*>(&two), sizeof(two));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(skewed)), "keyframe 0: orientation of norm"))
      << sparseMapError(dir, withValidChecksum(skewed));
  std::string wide_code = v5;
  wide_code[first_keyframe + 56 + 3] = static_cast<char>(0x30);
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(wide_code)), "keyframe 0: fern 3 has code 48, beyond its 4 bits"))
      << sparseMapError(dir, withValidChecksum(wide_code));
  std::string no_ferns = v5;
  const int32_t zero = 0;
  no_ferns.replace(kPlacesHeader + 16, sizeof(zero), reinterpret_cast<const char*>(&zero), sizeof(zero));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(no_ferns)), "invalid place descriptor: fern_count"))
      << sparseMapError(dir, withValidChecksum(no_ferns));
  EXPECT_TRUE(has(sparseMapError(dir, v5.substr(0, v5.size() - 30)), "3 keyframes"));
  std::string no_submap = v5;
  const int32_t fourth = 3;
  no_submap.replace(first_keyframe + 56 + 20, sizeof(fourth), reinterpret_cast<const char*>(&fourth), sizeof(fourth));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(no_submap)), "keyframe 0 is of submap 3, none of the 1 there are"))
      << sparseMapError(dir, withValidChecksum(no_submap));
}

TEST(Io, TheMapFileKeepsTheFrameTheMapWasPublishedInAndASecondVersionFileLoadsWithout) {
  // Issue 42: a second session in a node levelled its map frame anew, from the accelerometer where
  // the camera was found, and published in a frame tilted from the first session's.
  const std::string dir = test::scratchDirectory("sdfmap_frame");
  const Eigen::Isometry3d T_map_W = test::perturbed(Eigen::Isometry3d::Identity(), 0.4, 0.05);
  const PlaceMemory places = patternedPlaces();
  io::writeMap(dir + "/map.sdfmap", patternedSparseMap(), &places, T_map_W);
  std::optional<Eigen::Isometry3d> loaded_frame;
  std::unique_ptr<PlaceMemory> loaded_places;
  io::readMap(dir + "/map.sdfmap", false, &loaded_places, PlaceMemoryConfig(), &loaded_frame);
  ASSERT_TRUE(loaded_frame) << "the saved map frame";
  EXPECT_TRUE(loaded_frame->isApprox(T_map_W, 1e-12));
  ASSERT_TRUE(loaded_places);
  EXPECT_EQ(loaded_places->keyframes().size(), 3u);

  io::writeMap(dir + "/no_frame.sdfmap", patternedSparseMap(), &places);
  io::readMap(dir + "/no_frame.sdfmap", false, nullptr, PlaceMemoryConfig(), &loaded_frame);
  EXPECT_FALSE(loaded_frame) << "a map saved without a frame (an offline run's) has none";
  io::writeMap(dir + "/map.vti", sphereVolume(), nullptr, T_map_W);
  io::readMap(dir + "/map.vti", false, nullptr, PlaceMemoryConfig(), &loaded_frame);
  EXPECT_FALSE(loaded_frame) << "a .vti keeps no map frame";

  // Version 2: the place memory, no map frame (nor colour flag).
  const std::string v5 = readBytes(dir + "/map.sdfmap");
  writeFile(dir + "/v2.sdfmap", asOlderSdfmapVersion(v5, 2, 3, 20));
  io::readMap(dir + "/v2.sdfmap", false, &loaded_places, PlaceMemoryConfig(), &loaded_frame);
  EXPECT_FALSE(loaded_frame) << "a version 2 file has no map frame";
  ASSERT_TRUE(loaded_places);
  EXPECT_EQ(loaded_places->keyframes().size(), 3u);

  // Frames no writer makes are refused by name, even with a valid checksum.
  auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  std::string flag = v5;
  flag[kMapFrame] = 2;
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(flag)), "map frame: flag 2 is neither 0 nor 1"))
      << sparseMapError(dir, withValidChecksum(flag));
  std::string skewed = v5;
  const double two = 2.0;
  skewed.replace(kMapFrame + 8 + 24, sizeof(two), reinterpret_cast<const char*>(&two), sizeof(two));
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(skewed)), "map frame: orientation of norm"))
      << sparseMapError(dir, withValidChecksum(skewed));
  EXPECT_TRUE(has(sparseMapError(dir, v5.substr(0, kMapFrame + 20)), "truncated"));
}

/// Three submaps of the patterned map's blocks (the second without its last block) at places of
/// their own, joined by two odometry edges and a loop, and the patterned keyframes taken in
/// submaps 0, 2 and 1.
SubmapGraph patternedSubmaps() {
  SubmapGraph saved;
  for (int i = 0; i < 3; ++i) {
    auto map = std::make_unique<SparseTsdfMap>(patternedSparseMap());
    if (i == 1) map->remove(SparseTsdfMap::BlockIndex(1000, -2000, 7));
    SubmapPlace place;
    place.node = i;
    place.T_W_anchor = test::perturbed(Eigen::Isometry3d::Identity(), 0.7 * i, 0.1 * i);
    place.T_map_W = test::perturbed(Eigen::Isometry3d::Identity(), 0.02 * i, 0.01 * i);
    place.frames_fused = 30 + i;
    place.path_m = 0.9 * i;
    saved.submaps.push_back(Submap{std::move(map), place});
  }
  PoseInformation loop = PoseInformation::Identity() * 400.0;
  loop(0, 4) = loop(4, 0) = 3.5;  // not diagonal: every entry must come back
  saved.edges = {PoseEdge{0, 1, test::perturbed(Eigen::Isometry3d::Identity(), 0.7, 0.1), PoseInformation::Identity() * 900.0,
                          PoseEdgeKind::kOdometry},
                 PoseEdge{1, 2, test::perturbed(Eigen::Isometry3d::Identity(), 0.7, 0.1), PoseInformation::Identity() * 800.0,
                          PoseEdgeKind::kOdometry},
                 PoseEdge{0, 2, test::perturbed(Eigen::Isometry3d::Identity(), 1.4, 0.2), loop, PoseEdgeKind::kLoop}};
  saved.keyframe_submaps = {0, 2, 1};
  return saved;
}

TEST(Io, TheMapFileKeepsTheSubmapsTheirGraphAndEachKeyframesSubmap) {
  // Issue 43: a .sdfmap kept the submaps merged, and a second session started a graph of its own
  // on the merged whole.
  const std::string dir = test::scratchDirectory("sdfmap_submaps");
  const SubmapGraph saved = patternedSubmaps();
  const PlaceMemory places = patternedPlaces();
  const Eigen::Isometry3d T_map_W = test::perturbed(Eigen::Isometry3d::Identity(), 0.4, 0.05);
  io::writeMap(dir + "/map.sdfmap", saved, &places, T_map_W);
  const io::LoadedMap loaded = io::loadMap(dir + "/map.sdfmap");
  ASSERT_EQ(loaded.submaps.submaps.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const auto& before = static_cast<const SparseTsdfMap&>(*saved.submaps[i].map);
    const auto& after = static_cast<const SparseTsdfMap&>(*loaded.submaps.submaps[i].map);
    ASSERT_EQ(after.blockIndices(), before.blockIndices()) << "submap " << i;
    for (const SparseTsdfMap::BlockIndex& index : before.blockIndices()) {
      for (int v = 0; v < kBlockVoxels; ++v) {
        ASSERT_EQ(after.find(index)->voxels[v].distance_m, before.find(index)->voxels[v].distance_m);
        ASSERT_EQ(after.find(index)->voxels[v].weight, before.find(index)->voxels[v].weight);
      }
    }
    const SubmapPlace& a = loaded.submaps.submaps[i].place;
    const SubmapPlace& b = saved.submaps[i].place;
    EXPECT_EQ(a.node, b.node);
    EXPECT_TRUE(a.T_W_anchor.isApprox(b.T_W_anchor, 1e-12)) << "submap " << i;
    EXPECT_TRUE(a.T_map_W.isApprox(b.T_map_W, 1e-12)) << "submap " << i;
    EXPECT_EQ(a.frames_fused, b.frames_fused);
    EXPECT_EQ(a.path_m, b.path_m);
  }
  ASSERT_EQ(loaded.submaps.edges.size(), 3u);
  for (size_t e = 0; e < 3; ++e) {
    EXPECT_EQ(loaded.submaps.edges[e].from, saved.edges[e].from);
    EXPECT_EQ(loaded.submaps.edges[e].to, saved.edges[e].to);
    EXPECT_EQ(loaded.submaps.edges[e].kind, saved.edges[e].kind);
    EXPECT_TRUE(loaded.submaps.edges[e].T_from_to.isApprox(saved.edges[e].T_from_to, 1e-12));
    EXPECT_EQ(loaded.submaps.edges[e].information, saved.edges[e].information) << "edge " << e;
  }
  EXPECT_EQ(loaded.submaps.keyframe_submaps, saved.keyframe_submaps);
  ASSERT_TRUE(loaded.places);
  ASSERT_EQ(loaded.places->keyframes().size(), 3u);
  EXPECT_TRUE(loaded.places->keyframes()[1].T_W_C.isApprox(places.keyframes()[1].T_W_C, 1e-12)) << "in its submap's frame";
  ASSERT_TRUE(loaded.T_map_W);
  EXPECT_TRUE(loaded.T_map_W->isApprox(T_map_W, 1e-12));

  // As one map: the submaps merged where the graph places them, the keyframes in the map frame.
  std::unique_ptr<PlaceMemory> merged_places;
  const std::unique_ptr<TsdfMap> merged = io::readMap(dir + "/map.sdfmap", false, &merged_places);
  std::vector<PlacedMap> parts;
  for (const Submap& submap : saved.submaps) {
    parts.push_back({&static_cast<const SparseTsdfMap&>(*submap.map), submap.place.T_map_W});
  }
  EXPECT_EQ(static_cast<const SparseTsdfMap&>(*merged).blockIndices(), mergeMaps(parts).blockIndices());
  ASSERT_TRUE(merged_places);
  EXPECT_TRUE(merged_places->keyframes()[1].T_W_C.isApprox(saved.submaps[2].place.T_map_W * places.keyframes()[1].T_W_C, 1e-12));

  // What no writer makes is refused by name, even with a valid checksum.
  const std::string good = readBytes(dir + "/map.sdfmap");
  auto has = [](const std::string& message, const std::string& part) {
    return message.find(part) != std::string::npos;
  };
  const size_t first_edge = test::kSdfmapFirstSubmap + 3 * test::kSdfmapSubmapRecord;
  auto edited = [&](size_t at, const auto& value) {
    std::string bytes = good;
    bytes.replace(at, sizeof(value), reinterpret_cast<const char*>(&value), sizeof(value));
    return sparseMapError(dir, withValidChecksum(bytes));
  };
  EXPECT_TRUE(has(edited(first_edge + 4, int32_t{5}), "edge 0 (0 to 5) names a submap that is none of the 3 there are"))
      << edited(first_edge + 4, int32_t{5});
  EXPECT_TRUE(has(edited(first_edge + 4, int32_t{0}), "edge 0 (0 to 0) joins a submap to itself"));
  EXPECT_TRUE(has(edited(first_edge + test::kSdfmapEdgeRecord + 8, uint32_t{2}), "edge 1: kind 2 is neither"));
  EXPECT_TRUE(has(edited(first_edge + 12, uint32_t{7}), "edge 0: reserved field 7 is not 0"));
  const size_t loop_information = first_edge + 2 * test::kSdfmapEdgeRecord + 72;
  EXPECT_TRUE(has(edited(loop_information + 8 * 4, 3.6), "edge 2: information is not symmetric"))
      << edited(loop_information + 8 * 4, 3.6);
  EXPECT_TRUE(has(edited(loop_information, -400.0), "edge 2: information is not positive definite"));
  // The second submap's block count: one fewer than it holds, then more than the file holds.
  const size_t second_blocks = test::kSdfmapFirstSubmap + test::kSdfmapSubmapRecord + 112;
  EXPECT_TRUE(has(edited(second_blocks, uint64_t{1}), "its submaps list 7 blocks, its header 8")) << edited(second_blocks, uint64_t{1});
  EXPECT_TRUE(has(edited(second_blocks, uint64_t{7}), "submap 1 lists 7 blocks, beyond the 8 of the file"));
  EXPECT_TRUE(has(edited(second_blocks + 16, std::nan("")), "submap 1: path of nan m")) << edited(second_blocks + 16, std::nan(""));
  EXPECT_TRUE(has(edited(test::kSdfmapFirstSubmap + 56 + 24, 2.0), "submap 0: place: orientation of norm"));
  // The edges join the third submap to no other: the graph could not place it.
  std::string cut = good;
  const uint64_t one_edge = 1;
  cut.replace(test::kSdfmapSubmapCounts + 8, sizeof(one_edge), reinterpret_cast<const char*>(&one_edge), sizeof(one_edge));
  cut.erase(first_edge + test::kSdfmapEdgeRecord, 2 * test::kSdfmapEdgeRecord);
  EXPECT_TRUE(has(sparseMapError(dir, withValidChecksum(cut)), "submap 2 is joined to the first by no edge"))
      << sparseMapError(dir, withValidChecksum(cut));
  // ... and such submaps are not written either.
  SubmapGraph unjoined = patternedSubmaps();
  unjoined.edges.erase(unjoined.edges.begin() + 1, unjoined.edges.end());
  EXPECT_EQ(runtimeErrorOf([&] { io::writeMap(dir + "/unjoined.sdfmap", unjoined, &places); }),
            dir + "/unjoined.sdfmap: not written: submap 2 is joined to the first by no edge: the graph cannot place it");
  EXPECT_FALSE(std::ifstream(dir + "/unjoined.sdfmap").good());
}

TEST(Io, AnEmptyMapIsNeitherWrittenNorLoaded) {
  // Issue 44: a node that mapped nothing answered save_volume with success and a 120-byte map,
  // which then loaded and replaced the live map: the node never tracked again.
  const std::string dir = test::scratchDirectory("empty_map");
  VolumeConfig sparse_config;
  sparse_config.type = MapType::kSparse;
  const SparseTsdfMap empty_sparse(sparse_config);
  VolumeConfig dense_config;
  dense_config.dims = Eigen::Vector3i(8, 8, 8);
  const TsdfVolume empty_dense(dense_config);
  for (const TsdfMap* map : {static_cast<const TsdfMap*>(&empty_sparse), static_cast<const TsdfMap*>(&empty_dense)}) {
    for (const std::string name : {"/out.sdfmap", "/out.vti"}) {
      EXPECT_EQ(runtimeErrorOf([&] { io::writeMap(dir + name, *map); }),
                dir + name + ": not written: nothing is mapped yet (no voxel holds an observation)");
      EXPECT_FALSE(std::ifstream(dir + name).good()) << name << ": no file, not even a partial one";
    }
  }
  // Such files, from an older build or written directly, are refused when loaded, by name.
  io::writeSparseMap(dir + "/empty.sdfmap", empty_sparse);
  io::writeVti(dir + "/empty.vti", empty_dense);
  for (const std::string name : {"/empty.sdfmap", "/empty.vti"}) {
    EXPECT_EQ(runtimeErrorOf([&] { io::readMap(dir + name); }),
              dir + name + ": an empty map: no voxel holds an observation, nothing to track against");
  }
  // A block allocated but never observed is as empty as none.
  SparseTsdfMap unobserved(sparse_config);
  unobserved.allocate(SparseTsdfMap::BlockIndex(0, 0, 0));
  EXPECT_TRUE(unobserved.observesNothing());
  unobserved.allocate(SparseTsdfMap::BlockIndex(0, 0, 0)).voxels[5].weight = 1.0f;
  EXPECT_FALSE(unobserved.observesNothing());
  EXPECT_FALSE(sphereVolume().observesNothing());
}

TEST(Io, WhatALoadedMapsPlaceMemoryBringsIsSaidAsItIs) {
  PlaceMemory none_kept;
  const PlaceMemory places = patternedPlaces();
  EXPECT_EQ(io::describeLoadedPlaces(nullptr, true),
            "holds no place memory (a .vti, or a .sdfmap of format version 1): the camera is searched for from the "
            "map's start pose only");
  // Issue 44: a version 2 file whose first session kept no keyframe was called a .vti or version 1.
  EXPECT_EQ(io::describeLoadedPlaces(&none_kept, true),
            "holds a place memory without keyframes (its first session stored none): the camera is searched for "
            "from the map's start pose only");
  EXPECT_EQ(io::describeLoadedPlaces(&places, true),
            "holds 3 keyframes in its place memory: the camera is searched for in it, and nothing is fused until it "
            "is found");
  EXPECT_EQ(io::describeLoadedPlaces(&places, false),
            "holds 3 keyframes in its place memory; Relocalise is off: tracking starts at the map's start pose");

  // What readMap hands over for each: a version 2 file without keyframes has a place memory.
  const std::string dir = test::scratchDirectory("places_described");
  io::writeMap(dir + "/none.sdfmap", patternedSparseMap(), &none_kept);
  std::unique_ptr<PlaceMemory> loaded;
  io::readMap(dir + "/none.sdfmap", false, &loaded);
  ASSERT_TRUE(loaded);
  EXPECT_TRUE(loaded->empty());
}

TEST(Io, AFifoOrAFolderGivenAsAFileIsRefusedWithoutBlocking) {
  const std::string dir = test::scratchDirectory("not_a_file");
  ASSERT_EQ(::mkfifo((dir + "/map.sdfmap").c_str(), 0644), 0);
  ::mkdir((dir + "/folder.vti").c_str(), 0755);
  EXPECT_EQ(runtimeErrorOf([&] { io::readMap(dir + "/map.sdfmap"); }),
            dir + "/map.sdfmap: is not a regular file (a FIFO or a device?)");
  EXPECT_EQ(runtimeErrorOf([&] { io::readMap(dir + "/folder.vti"); }), dir + "/folder.vti: is a folder, not a file");
  EXPECT_NE(runtimeErrorOf([&] { io::readPlyMesh(dir + "/map.sdfmap"); }), "");
  EXPECT_NE(runtimeErrorOf([&] { io::readDepthPng(dir + "/map.sdfmap", 5000.0); }), "");
  EXPECT_NE(runtimeErrorOf([&] { io::readTrajectory(dir + "/map.sdfmap"); }), "");
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

/// A PNG signature and IHDR chunk with the given size and format, and nothing after it.
std::string pngHeader(uint32_t width, uint32_t height, uint8_t bit_depth, uint8_t colour_type) {
  std::string bytes("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
  for (uint32_t value : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) bytes += static_cast<char>((value >> shift) & 0xff);
  }
  bytes += static_cast<char>(bit_depth);
  bytes += static_cast<char>(colour_type);
  bytes += std::string("\0\0\0\0\0\0\0", 7);  // compression, filter, interlace, CRC
  return bytes;
}

TEST(Io, TheTemporaryOfAKilledWriterIsFoundAndRemoved) {
  const std::string dir = test::scratchDirectory("stale_tmp");
  io::writeTextFile(dir + "/trajectory.txt", "finished");
  writeFile(dir + "/trajectory.txt.tmp", "a writer was killed here");  // as AtomicOutput names it
  EXPECT_TRUE(io::removeStaleTemporary(dir + "/trajectory.txt"));
  EXPECT_FALSE(std::ifstream(dir + "/trajectory.txt.tmp").good());
  EXPECT_TRUE(std::ifstream(dir + "/trajectory.txt").good()) << "the finished file stays";
  EXPECT_FALSE(io::removeStaleTemporary(dir + "/trajectory.txt"));
}

TEST(Io, AShortVtiClaimingAHugeGridIsRefusedBeforeAnythingIsAllocated) {
  const std::string dir = test::scratchDirectory("vti_bomb");
  io::writeVti(dir + "/small.vti", sphereVolume());
  std::ifstream in(dir + "/small.vti", std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* extent : {"0 511 0 511 0 511", "0 4095 0 4095 0 127"}) {
    std::string bomb = text;
    for (size_t at = 0; (at = bomb.find("0 39 0 39 0 39", at)) != std::string::npos;) bomb.replace(at, 14, extent);
    bomb.resize(bomb.find("_", bomb.find("<AppendedData")) + 200);  // about 1.5 KB in all
    writeFile(dir + "/bomb.vti", bomb);
    EXPECT_TRUE(test::withinMemory(64, [&] {
      try {
        io::readVti(dir + "/bomb.vti");
      } catch (const std::runtime_error& e) {
        if (std::string(e.what()).find("truncated") != std::string::npos) return true;
        std::cerr << e.what() << "\n";
      }
      return false;
    })) << extent;
  }
  std::string wild = text;
  wild.replace(wild.find("0 39 0 39 0 39"), 14, "0 2147483647 -2147483648 0 0 39");
  writeFile(dir + "/wild.vti", wild);
  EXPECT_THROW(io::readVti(dir + "/wild.vti"), std::runtime_error) << "extents that overflow int";
}

TEST(Io, DepthPngsAreCheckedFromTheirHeaderBeforeDecoding) {
  const std::string dir = test::scratchDirectory("png_header");
  auto errorOf = [](const std::string& path, int width, int height) {
    try {
      io::readDepthPng(path, 5000.0, width, height);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  writeFile(dir + "/huge.png", pngHeader(20000, 20000, 16, 0));  // would take 2.5 GB to decode
  EXPECT_NE(errorOf(dir + "/huge.png", 640, 480).find("image is 20000x20000 but the intrinsics are for 640x480"),
            std::string::npos);
  EXPECT_TRUE(test::withinMemory(64, [&] { return !errorOf(dir + "/huge.png", 0, 0).empty(); })) << "no size given";
  writeFile(dir + "/rgb16.png", pngHeader(640, 480, 16, 2));
  EXPECT_NE(errorOf(dir + "/rgb16.png", 640, 480).find("16-bit greyscale PNG (got 16-bit RGB)"), std::string::npos);
  writeFile(dir + "/grey_alpha.png", pngHeader(640, 480, 16, 4));
  EXPECT_NE(errorOf(dir + "/grey_alpha.png", 640, 480).find("got 16-bit greyscale + alpha"), std::string::npos);
  writeFile(dir + "/grey8.png", pngHeader(640, 480, 8, 0));
  EXPECT_NE(errorOf(dir + "/grey8.png", 640, 480).find("got 8-bit greyscale"), std::string::npos);
  writeFile(dir + "/text.png", "not a png at all, but long enough to hold a header");
  EXPECT_NE(errorOf(dir + "/text.png", 640, 480).find("not a PNG file"), std::string::npos);
}

TEST(Io, APlyHeaderClaimingMoreThanItsFileHoldsIsRefused) {
  const std::string dir = test::scratchDirectory("ply_bomb");
  writeFile(dir + "/bomb.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0000");
  EXPECT_TRUE(test::withinMemory(64, [&] {
    try {
      io::readPlyMesh(dir + "/bomb.ply");
    } catch (const std::runtime_error& e) {
      return std::string(e.what()).find("more than its") != std::string::npos;
    }
    return false;
  }));
  writeFile(dir + "/negative.ply", "ply\nformat ascii 1.0\nelement vertex -3\nproperty float x\nproperty float y\n"
                                   "property float z\nend_header\n");
  EXPECT_THROW(io::readPlyMesh(dir + "/negative.ply"), std::runtime_error);
}

}  // namespace
}  // namespace sdf_tracker
