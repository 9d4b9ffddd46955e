// Colour in the map: fusion (a two-coloured wall comes out two-coloured at the right boundary,
// the bounded weight follows a change of light, distances do not depend on colour), the colour
// kept through every copy, swap, merge and file, and TUM's rgb.txt paired with the depth.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>

#include "sdf_tracker/eval/colour_agreement.h"
#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/io/colour_image_file.h"
#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/sdfmap_file.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/map/block_swap.h"
#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/surface/surface.h"
#include "sdfmap_bytes.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

constexpr Rgb kRed = {230, 20, 30};
constexpr Rgb kBlue = {25, 40, 220};

/// A colour image: kRed left of column `boundary`, kBlue from it on.
ColourImage twoColoured(const PinholeCamera& camera, int boundary) {
  ColourImage image(camera.width, camera.height);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Rgb& c = u < boundary ? kRed : kBlue;
      std::copy(c.begin(), c.end(), image.at(u, v));
    }
  }
  return image;
}

ColourImage filled(const PinholeCamera& camera, const Rgb& c) { return twoColoured(camera, c == kRed ? camera.width : 0); }

/// The wall z = 2 m of the single-wall scene, seen head on from the origin.
struct ColourWall : public ::testing::TestWithParam<MapType> {
  ColourWall() {
    config.type = GetParam();
    config.dims = Eigen::Vector3i(120, 100, 30);
    config.voxel_size_m = 0.02;
    config.origin_W = Eigen::Vector3d(-1.2, -1.0, 1.7);
    synthetic::NoiseModel exact;
    exact.enabled = false;
    depth = synthetic::Scene::singleWall().render(camera, T_W_C, exact, 0);
  }
  /// Where on the wall the colour image's column `boundary` begins: a voxel is fused from the
  /// pixel nearest to where it projects, so the colours part at that pixel's left edge.
  double boundaryX(int boundary) const { return (boundary - 0.5 - camera.cx) / camera.fx * 2.0; }

  VolumeConfig config;
  PinholeCamera camera = test::testCamera();
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  DepthImage depth;
};

TEST_P(ColourWall, ATwoColouredWallComesOutTwoColouredAtTheBoundaryInTheMeshAndTheCloud) {
  const int boundary = 200;
  std::unique_ptr<TsdfMap> map = makeMap(config);
  const Integrator integrator(IntegratorConfig{});
  const ColourImage colour = twoColoured(camera, boundary);
  for (int n = 0; n < 3; ++n) integrator.integrate(depth, camera, T_W_C, map.get(), &colour);
  ASSERT_TRUE(map->holdsColour());
  const double x_boundary = boundaryX(boundary);
  const double voxel = config.voxel_size_m;

  const TriangleMesh mesh = extractMesh(*map);
  ASSERT_EQ(mesh.colours.size(), mesh.vertices_W.size());
  int red = 0, blue = 0, between = 0;
  for (size_t i = 0; i < mesh.vertices_W.size(); ++i) {
    const double x = mesh.vertices_W[i].x();
    const Rgb& c = mesh.colours[i];
    if (x < x_boundary - voxel) {
      EXPECT_EQ(c, kRed) << "vertex at x = " << x << " m, the boundary at " << x_boundary;
      ++red;
    } else if (x > x_boundary + voxel) {
      EXPECT_EQ(c, kBlue) << "vertex at x = " << x << " m, the boundary at " << x_boundary;
      ++blue;
    } else {
      // Within a voxel of the boundary: between the two, never a third colour.
      for (int ch = 0; ch < 3; ++ch) {
        EXPECT_GE(c[ch], std::min(kRed[ch], kBlue[ch]));
        EXPECT_LE(c[ch], std::max(kRed[ch], kBlue[ch]));
      }
      ++between;
    }
  }
  EXPECT_GT(red, 500);
  EXPECT_GT(blue, 500);
  EXPECT_GT(between, 10) << "the boundary runs across the whole wall";

  const SurfaceCloud cloud = extractSurfaceCloud(*map);
  ASSERT_EQ(cloud.colours.size(), cloud.points_W.size());
  for (size_t i = 0; i < cloud.points_W.size(); ++i) {
    const double x = cloud.points_W[i].x();
    if (x < x_boundary - voxel) {
      EXPECT_EQ(cloud.colours[i], kRed) << x;
    } else if (x > x_boundary + voxel) {
      EXPECT_EQ(cloud.colours[i], kBlue) << x;
    }
  }
}

TEST_P(ColourWall, ColourChangesNoDistanceAndAMapFusedWithoutColourHoldsNone) {
  std::unique_ptr<TsdfMap> grey = makeMap(config), coloured = makeMap(config);
  const Integrator integrator(IntegratorConfig{});
  const ColourImage colour = twoColoured(camera, 100);
  for (int n = 0; n < 2; ++n) {
    EXPECT_EQ(integrator.integrate(depth, camera, T_W_C, grey.get()),
              integrator.integrate(depth, camera, T_W_C, coloured.get(), &colour));
  }
  EXPECT_FALSE(grey->holdsColour());
  EXPECT_EQ(coloured->memoryBytes() - grey->memoryBytes(),
            coloured->voxelCount() * sizeof(VoxelColour))
      << "a colour costs 4 bytes a voxel, and only in a map that holds colour";
  const TsdfVolume a = toDenseVolume(*grey), b = toDenseVolume(*coloured);
  ASSERT_EQ(a.voxelCount(), b.voxelCount());
  for (size_t i = 0; i < a.voxelCount(); ++i) {
    ASSERT_EQ(a.voxel(i).distance_m, b.voxel(i).distance_m) << i;
    ASSERT_EQ(a.voxel(i).weight, b.voxel(i).weight) << i;
  }
  const TriangleMesh mesh = extractMesh(*grey);
  EXPECT_TRUE(mesh.colours.empty()) << "no colour: a mesh without vertex colours";
  EXPECT_EQ(extractMesh(*coloured).vertices_W, mesh.vertices_W);
}

TEST_P(ColourWall, TheBoundedWeightFollowsAChangeOfLightAndOnlyVoxelsNearTheSurfaceTakeColour) {
  IntegratorConfig bounded;
  bounded.max_colour_weight = 4;
  IntegratorConfig unbounded;
  unbounded.max_colour_weight = 255;
  std::unique_ptr<TsdfMap> follows = makeMap(config), averages = makeMap(config);
  for (int n = 0; n < 80; ++n) {
    const ColourImage light = filled(camera, n < 40 ? kRed : kBlue);
    Integrator(bounded).integrate(depth, camera, T_W_C, follows.get(), &light);
    Integrator(unbounded).integrate(depth, camera, T_W_C, averages.get(), &light);
  }
  const TsdfVolume f = toDenseVolume(*follows), a = toDenseVolume(*averages);
  int near_surface = 0;
  for (size_t i = 0; i < f.voxelCount(); ++i) {
    const Voxel v = f.voxel(i);
    const VoxelColour c = f.colour(i), c_avg = a.colour(i);
    const double band = kColourBandVoxels * config.voxel_size_m;
    if (v.weight <= 0.0f || std::fabs(v.distance_m) > band + 1e-4) {
      EXPECT_EQ(c.weight, 0) << "voxel " << i << " at " << v.distance_m << " m from the surface took colour";
      continue;
    }
    if (std::fabs(v.distance_m) > band - 1e-4) continue;  // on the band's edge: either
    ++near_surface;
    ASSERT_EQ(c.weight, 4) << "the weight stops at ColourMaxWeight";
    // The running average with weight 4 ends within its rounding (2 levels) of the new light.
    EXPECT_NEAR(c.b, kBlue[2], 2) << i;
    EXPECT_NEAR(c.r, kBlue[0], 2) << i;
    // Without a bound it is still about half the old light (each step rounds to a whole level).
    EXPECT_EQ(c_avg.weight, 80);
    EXPECT_NEAR(c_avg.r, (kRed[0] + kBlue[0]) / 2.0, 25.0) << i;
  }
  EXPECT_GT(near_surface, 1000);
}

TEST_P(ColourWall, AColourImageOfTheWrongSizeIsRefusedByNameChangingNothing) {
  std::unique_ptr<TsdfMap> map = makeMap(config);
  const ColourImage small(camera.width / 2, camera.height / 2);
  try {
    Integrator(IntegratorConfig{}).integrate(depth, camera, T_W_C, map.get(), &small);
    FAIL() << "a colour image half the depth's size was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("the colour image is 160x120, the depth image 320x240"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(map->observesNothing());
  EXPECT_FALSE(map->holdsColour());
}

INSTANTIATE_TEST_SUITE_P(BothMaps, ColourWall, ::testing::Values(MapType::kDense, MapType::kSparse),
                         [](const auto& param_info) { return std::string(toString(param_info.param)); });

/// A sparse map of the wall in two colours, fused a few times.
SparseTsdfMap colouredWallMap() {
  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = 0.02;
  const PinholeCamera camera = test::testCamera();
  synthetic::NoiseModel exact;
  exact.enabled = false;
  const DepthImage depth = synthetic::Scene::singleWall().render(camera, Eigen::Isometry3d::Identity(), exact, 0);
  SparseTsdfMap map(config);
  for (int n = 0; n < 3; ++n) {
    const ColourImage colour = twoColoured(camera, 100 + 40 * n);
    Integrator(IntegratorConfig{}).integrate(depth, camera, Eigen::Isometry3d::Identity(), &map, &colour);
  }
  return map;
}

void expectSameColours(const SparseTsdfMap& expected, const SparseTsdfMap& actual, const std::string& what) {
  ASSERT_TRUE(actual.holdsColour()) << what;
  ASSERT_EQ(actual.blockIndices(), expected.blockIndices()) << what;
  for (const auto& index : expected.blockIndices()) {
    ASSERT_EQ(actual.find(index)->colours, expected.find(index)->colours) << what << ": block " << index.transpose();
    ASSERT_EQ(actual.find(index)->voxels[100].distance_m, expected.find(index)->voxels[100].distance_m) << what;
  }
}

TEST(MapColour, IsKeptThroughCopiesSwapsMergesAndDenseGrids) {
  const SparseTsdfMap map = colouredWallMap();
  ASSERT_TRUE(map.holdsColour());
  SparseTsdfMap copied(map.config());
  copied.copyBlocksFrom(map, map.blockIndices());
  expectSameColours(map, copied, "copyBlocksFrom");
  // Through a dense grid (at the box around the blocks) and back.
  const TsdfVolume dense = toDenseVolume(map);
  Eigen::Vector3i first_voxel, dims;
  map.bounds(&first_voxel, &dims);
  ASSERT_TRUE(dense.holdsColour());
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) ASSERT_EQ(dense.colour(i, j, k), map.colour(first_voxel + Eigen::Vector3i(i, j, k)));
  const SparseTsdfMap from_dense = toSparseMap(dense);
  ASSERT_TRUE(from_dense.holdsColour());
  for (int k = 0; k < dims.z(); k += 3)
    for (int j = 0; j < dims.y(); j += 3)
      for (int i = 0; i < dims.x(); i += 3) {
        if (dense.voxel(i, j, k).weight > 0.0f) {
          ASSERT_EQ(from_dense.colour({i, j, k}), dense.colour(i, j, k));
        }
      }
  expectSameColours(map, mergeMaps({PlacedMap{&map, Eigen::Isometry3d::Identity()}}), "merged alone");

  // Merged with itself: the same colours (the average of two equal ones), their weights added.
  const SparseTsdfMap twice = mergeMaps({PlacedMap{&map}, PlacedMap{&map}});
  const auto first = map.blockIndices().front();
  for (int v = 0; v < kBlockVoxels; ++v) {
    const VoxelColour a = map.find(first)->colours[v], b = twice.find(first)->colours[v];
    EXPECT_EQ(std::make_tuple(a.r, a.g, a.b), std::make_tuple(b.r, b.g, b.b));
    EXPECT_EQ(b.weight, std::min(255, 2 * a.weight));
  }
  // Moved by a whole number of voxels: each voxel's colour is the one it moved from.
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(0.04, 0.0, 0.0);
  const SparseTsdfMap moved = mergeMaps({PlacedMap{&map, shift}});
  ASSERT_TRUE(moved.holdsColour());
  int compared = 0;
  for (const auto& index : map.blockIndices()) {
    for (int v = 0; v < kBlockVoxels; v += 7) {
      const Eigen::Vector3i voxel = SparseTsdfMap::firstVoxel(index) + Eigen::Vector3i(v % 8, v / 8 % 8, v / 64);
      const VoxelColour before = map.colour(voxel);
      // (A voxel whose eight neighbours are not all observed is not resampled.)
      if (before.weight == 0 || moved.voxel(voxel + Eigen::Vector3i(2, 0, 0)).weight <= 0.0f) continue;
      EXPECT_EQ(moved.colour(voxel + Eigen::Vector3i(2, 0, 0)), before);
      ++compared;
    }
  }
  EXPECT_GT(compared, 100);

  BlockSwapFile swap(test::scratchDirectory("colour_swap"));
  swap.put(7, *map.find(first));
  VoxelBlock back;
  ASSERT_TRUE(swap.read(7, &back));
  EXPECT_EQ(back.colours, map.find(first)->colours);
  VoxelBlock grey = *map.find(first);
  grey.colours.clear();
  swap.put(8, grey);
  ASSERT_TRUE(swap.read(8, &back));
  EXPECT_TRUE(back.colours.empty()) << "a block without colour comes back without";
}

TEST(MapColour, IsSavedInTheMapFilesAndTheMeshAndAnOlderMapFileLoadsWithout) {
  const std::string dir = test::scratchDirectory("colour_files");
  const SparseTsdfMap map = colouredWallMap();
  io::writeSparseMap(dir + "/map.sdfmap", map);
  expectSameColours(map, io::readSparseMap(dir + "/map.sdfmap"), ".sdfmap");

  const TsdfVolume dense = toDenseVolume(map);
  io::writeVti(dir + "/map.vti", dense);
  const TsdfVolume read = io::readVti(dir + "/map.vti");
  ASSERT_TRUE(read.holdsColour());
  for (size_t i = 0; i < dense.voxelCount(); ++i) ASSERT_EQ(read.colour(i), dense.colour(i)) << i;
  std::ifstream vti(dir + "/map.vti");
  const std::string head((std::istreambuf_iterator<char>(vti)), std::istreambuf_iterator<char>());
  EXPECT_NE(head.find("Name=\"colour\" NumberOfComponents=\"3\""), std::string::npos) << "ParaView's RGB array";

  const TriangleMesh mesh = extractMesh(map);
  io::writePly(dir + "/mesh.ply", mesh);
  const TriangleMesh loaded = io::readPlyMesh(dir + "/mesh.ply");
  EXPECT_EQ(loaded.colours, mesh.colours);
  io::writeObj(dir + "/mesh.obj", mesh);
  std::ifstream obj(dir + "/mesh.obj");
  std::string line;
  while (std::getline(obj, line) && line.rfind("v ", 0) != 0) {
  }
  std::istringstream words(line.substr(2));
  double values[6];
  for (double& value : values) ASSERT_TRUE(words >> value) << "v x y z r g b: " << line;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(values[3 + c], mesh.colours[0][c] / 255.0, 1e-3);

  // A version 3 file (before colour): the same blocks, no colour flag, no colours.
  const SparseTsdfMap grey_map = [&] {
    SparseTsdfMap grey(map.config());
    map.forEachBlock([&](const auto& index, const VoxelBlock& block) { grey.allocate(index).voxels = block.voxels; });
    return grey;
  }();
  io::writeSparseMap(dir + "/grey.sdfmap", grey_map);
  std::ofstream(dir + "/v3.sdfmap", std::ios::binary)
      << test::asOlderSdfmapVersion(test::readBytes(dir + "/grey.sdfmap"), 3, 0, 0);
  const SparseTsdfMap old = io::readSparseMap(dir + "/v3.sdfmap");
  EXPECT_FALSE(old.holdsColour());
  EXPECT_EQ(old.blockIndices(), map.blockIndices());
  EXPECT_NE(io::describeLoadedColour(old, true).find("holds no colour"), std::string::npos)
      << io::describeLoadedColour(old, true);
  EXPECT_EQ(io::describeLoadedColour(old, false), "") << "nothing to say with Colour off";
  EXPECT_EQ(io::describeLoadedColour(map, true), "");
}

/// A TUM folder of `frames` depth images of a flat wall 1.5 m in front of the test camera, 0.1 s
/// apart from first_s, with intrinsics.txt; given `colour`, that image with every frame in rgb.txt.
std::string wallFolder(const std::string& name, int frames, double first_s, const ColourImage* colour) {
  const std::string dir = test::scratchDirectory(name);
  const PinholeCamera camera = test::testCamera();
  std::filesystem::create_directories(dir + "/depth");
  std::filesystem::create_directories(dir + "/rgb");
  std::ofstream depth_list(dir + "/depth.txt"), colour_list;
  depth_list << "# depth maps\n";
  if (colour) colour_list.open(dir + "/rgb.txt");
  const DepthImage depth(camera.width, camera.height, 1.5f);
  for (int i = 0; i < frames; ++i) {
    const std::string stamp = std::to_string(first_s + i * 0.1);
    io::writeDepthPng(dir + "/depth/" + stamp + ".png", depth, 5000.0);
    depth_list << stamp << " depth/" << stamp << ".png\n";
    if (!colour) continue;
    io::writeColourImage(dir + "/rgb/" + stamp + ".png", *colour);
    colour_list << stamp << " rgb/" << stamp << ".png\n";
  }
  std::ofstream(dir + "/intrinsics.txt") << camera.fx << " " << camera.fy << " " << camera.cx << " " << camera.cy << " "
                                         << camera.width << " " << camera.height << " 5000\n";
  return dir;
}

TEST(TumColour, DepthAndColourArePairedClosestFirstOncePerImageWithinTwentyMilliseconds) {
  // associate.py's rule: the closest pairs first, each image in one pair at most.
  const std::vector<long> partner = associateByTime({1.000, 1.012, 1.100, 2.000}, {1.008, 1.050, 1.115, 2.0201}, 0.02);
  EXPECT_EQ(partner, (std::vector<long>{-1, 0, 2, -1}))
      << "1.012 takes 1.008 (4 ms, before 1.000's 8 ms), leaving 1.000 none within 20 ms; 1.100 takes 1.115; "
         "2.000 is 20.1 ms from 2.0201";
  EXPECT_EQ(associateByTime({1.0}, {1.0199}, 0.02), std::vector<long>{0});
  EXPECT_EQ(associateByTime({1.0}, {}, 0.02), std::vector<long>{-1});
}

TEST(TumColour, AFolderWithRgbTxtGivesEachDepthFrameItsColourImageAndNamesABadOne) {
  const std::string dir = wallFolder("tum_colour", 3, 10.0, nullptr);
  const PinholeCamera camera = test::testCamera();
  io::writeColourImage(dir + "/rgb/a.png", twoColoured(camera, 50));
  io::writeColourImage(dir + "/rgb/b.jpg", filled(camera, kBlue));
  io::writeColourImage(dir + "/rgb/small.png", ColourImage(camera.width / 2, camera.height / 2));
  std::ofstream(dir + "/rgb.txt") << "# color images\n10.012 rgb/a.png\n10.093 rgb/b.jpg\n10.2 rgb/small.png\n";

  const TumSequence sequence = TumSequence::open(dir);
  ASSERT_TRUE(sequence.hasColourList());
  EXPECT_EQ(sequence.colouredFrames(), 3u);
  EXPECT_DOUBLE_EQ(sequence.colourTimestamp(0), 10.012);
  const ColourImage png = *sequence.colour(0);
  EXPECT_EQ(Rgb({png.at(10, 10)[0], png.at(10, 10)[1], png.at(10, 10)[2]}), kRed) << "PNG exactly, as RGB";
  const ColourImage jpeg = *sequence.colour(1);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(jpeg.at(100, 100)[c], kBlue[c], 6) << "a JPEG, within its loss";
  try {
    sequence.colour(2);
    FAIL() << "a colour image of another size than the depth's was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("small.png: colour image is 160x120 but the depth images are 320x240"),
              std::string::npos)
        << e.what();
  }
  // A 16-bit PNG is a depth image, not colour.
  std::filesystem::copy_file(dir + "/depth/10.000000.png", dir + "/rgb/a.png",
                             std::filesystem::copy_options::overwrite_existing);
  try {
    sequence.colour(0);
    FAIL() << "a 16-bit PNG was taken for colour";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("8 bits a channel (got 16-bit greyscale)"), std::string::npos) << e.what();
  }
  // A list may name its files by absolute paths too.
  std::ofstream(dir + "/rgb.txt") << "10.2 " << dir << "/rgb/b.jpg\n";
  EXPECT_EQ(TumSequence::open(dir).colourPath(2), dir + "/rgb/b.jpg");
  std::filesystem::remove(dir + "/rgb.txt");
  EXPECT_FALSE(TumSequence::open(dir).hasColourList());
  EXPECT_FALSE(TumSequence::open(dir).colour(0)) << "no rgb.txt: no colour, and no error";
}

TEST(PipelineColour, TheTrajectoryIsTheSameWithColourAndWithoutAndABadColourImageLeavesTheFrameTracked) {
  const PinholeCamera camera = test::testCamera();
  PipelineConfig config;
  config.volume.type = MapType::kSparse;
  config.volume.voxel_size_m = 0.02;
  SdfPipeline grey(config), coloured(config);
  PipelineConfig off = config;
  off.fuse_colour = false;
  SdfPipeline ignored(off);
  const ColourImage colour = twoColoured(camera, 120);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 12; ++i) {
    T.translation() = Eigen::Vector3d(0.01 * i, 0.005 * i, 0.0);
    T.linear() = Eigen::AngleAxisd(0.01 * i, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const DepthImage depth = test::renderRoom(T, camera);
    const FrameReport a = grey.processFrame(depth, camera, 0.033 * i);
    const FrameReport b = coloured.processFrame(depth, camera, 0.033 * i, std::nullopt, &colour);
    const FrameReport c = ignored.processFrame(depth, camera, 0.033 * i, std::nullopt, &colour);
    ASSERT_TRUE(b.track.tracked());
    EXPECT_TRUE(b.coloured);
    EXPECT_FALSE(a.coloured);
    EXPECT_FALSE(c.coloured) << "Colour off: the image is ignored";
    ASSERT_EQ(a.track.T_W_C.matrix(), b.track.T_W_C.matrix()) << "frame " << i << ": colour moved the pose";
    ASSERT_EQ(a.track.T_W_C.matrix(), c.track.T_W_C.matrix()) << "frame " << i;
  }
  EXPECT_TRUE(coloured.map().holdsColour());
  EXPECT_FALSE(grey.map().holdsColour());
  EXPECT_FALSE(ignored.map().holdsColour());

  const ColourImage wrong(camera.width + 2, camera.height);
  const FrameReport bad = coloured.processFrame(test::renderRoom(T, camera), camera, 1.0, std::nullopt, &wrong);
  EXPECT_TRUE(bad.track.tracked()) << "the depth is tracked and fused all the same";
  EXPECT_FALSE(bad.coloured);
  EXPECT_NE(bad.colour_problem.find("the colour image is 322x240"), std::string::npos) << bad.colour_problem;
}

TEST(ColourAgreement, AMeshColouredFromItsImagesAgreesWithThemAndOneColouredWronglyDoesNot) {
  // A flat wall 1.5 m in front of the camera, half red and half blue, seen four times.
  const PinholeCamera camera = test::testCamera();
  const DepthImage depth(camera.width, camera.height, 1.5f);
  const ColourImage colour = twoColoured(camera, 150);
  const std::string dir = wallFolder("colour_agreement", 4, 20.0, &colour);
  std::vector<io::StampedPose> trajectory;
  for (int i = 0; i < 4; ++i) trajectory.push_back({20 + i * 0.1, Eigen::Isometry3d::Identity()});
  const TumSequence sequence = TumSequence::open(dir);

  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = 0.02;
  SparseTsdfMap map(config);
  for (int i = 0; i < 4; ++i) {
    Integrator(IntegratorConfig{}).integrate(depth, camera, Eigen::Isometry3d::Identity(), &map, &colour);
  }
  TriangleMesh mesh = extractMesh(map);
  const evaluation::ColourAgreement good = evaluation::compareMeshColours(mesh, sequence, trajectory, 1);
  EXPECT_EQ(good.frames, 4u);
  EXPECT_GT(good.comparisons, 4000u);
  EXPECT_LT(good.mean_channel_difference, 5.0) << "only vertices at the boundary differ";
  EXPECT_EQ(good.median_distance, 0.0);

  for (Rgb& c : mesh.colours) c = c == kRed ? kBlue : kRed;
  const evaluation::ColourAgreement swapped = evaluation::compareMeshColours(mesh, sequence, trajectory, 1);
  EXPECT_GT(swapped.mean_channel_difference, 100.0);
  mesh.colours.clear();
  EXPECT_THROW(evaluation::compareMeshColours(mesh, sequence, trajectory, 1), std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
