// The sparse block map: addressing, sampling across block borders, fusion and surfaces equal to
// the dense grid's where both observe, live copies, block swapping and its settings. Whole
// sequences through it are in test/sequences/test_map_sequences.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <map>
#include <random>

#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/map/block_swap.h"
#include "sdf_tracker/map/block_table.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/surface/chunked_mesh.h"
#include "sdf_tracker/surface/surface.h"
#include "sdf_tracker/tracking/tracker.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

using BlockIndex = SparseTsdfMap::BlockIndex;

/// The room grid of the other tests as a sparse map on the same lattice.
VolumeConfig sparseRoom() {
  VolumeConfig config = test::roomVolume();
  config.type = MapType::kSparse;
  return config;
}

TEST(SparseMap, BlocksAndKeysAddressNegativeVoxelsToo) {
  EXPECT_EQ(SparseTsdfMap::blockOf(Eigen::Vector3i(0, 7, 8)), BlockIndex(0, 0, 1));
  EXPECT_EQ(SparseTsdfMap::blockOf(Eigen::Vector3i(-1, -8, -9)), BlockIndex(-1, -1, -2));
  EXPECT_EQ(SparseTsdfMap::localOf(Eigen::Vector3i(-1, -8, -9)), Eigen::Vector3i(7, 0, 7));
  for (const BlockIndex& b : {BlockIndex(0, 0, 0), BlockIndex(-1, 5, -300000), BlockIndex(1048575, -1048575, 7)}) {
    EXPECT_EQ(SparseTsdfMap::indexOf(SparseTsdfMap::keyOf(b)), b);
  }
  EXPECT_LT(SparseTsdfMap::keyOf(BlockIndex(5, 0, 0)), SparseTsdfMap::keyOf(BlockIndex(0, 0, 1))) << "z sorts first";
}

TEST(BlockTable, KeepsTheSameEntriesAsAnOrderedMapThroughInsertsErasesGrowthAndCopies) {
  // Few distinct keys clustered in runs, so probe runs collide, wrap and get erased in the middle.
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<uint64_t> pick_key(0, 3000);
  BlockTable<int> table;
  std::map<uint64_t, int> expected;
  for (int step = 0; step < 20000; ++step) {
    const uint64_t key = pick_key(rng) * (step % 3 == 0 ? 1 : 1ull << 21);
    if (rng() % 3 == 0) {
      EXPECT_EQ(table.erase(key), expected.erase(key) == 1) << "erase " << key;
    } else {
      const int value = step;
      int& stored = table.findOrInsert(key, [value] { return std::make_unique<int>(value); });
      expected.emplace(key, value);
      EXPECT_EQ(stored, expected.at(key)) << "insert " << key;
    }
    ASSERT_EQ(table.size(), expected.size());
  }
  EXPECT_LE(2 * table.size(), table.capacity()) << "at most half full";
  const BlockTable<int> copy = table;
  for (const BlockTable<int>* t : std::initializer_list<const BlockTable<int>*>{&table, &copy}) {
    std::map<uint64_t, int> listed;
    t->forEach([&listed](uint64_t key, int value) { listed.emplace(key, value); });
    EXPECT_EQ(listed, expected);
    for (uint64_t key = 0; key <= 3000; ++key) {
      const auto it = expected.find(key);
      const int* found = t->find(key);
      ASSERT_EQ(found != nullptr, it != expected.end()) << "find " << key;
      if (found) {
        EXPECT_EQ(*found, it->second);
      }
    }
  }
  BlockTable<int> moved = std::move(table);
  EXPECT_EQ(moved.size(), expected.size());
  EXPECT_EQ(table.size(), 0u);  // NOLINT(bugprone-use-after-move): a moved-from table is empty and usable
  EXPECT_EQ(table.find(expected.begin()->first), nullptr);
}

TEST(SparseMap, HoldsOnlyTheBlocksItWasGivenAndFindsVoxelsThroughThem) {
  SparseTsdfMap map(sparseRoom());
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.voxel(Eigen::Vector3i(3, 3, 3)).weight, 0.0f);
  VoxelBlock& block = map.allocate(BlockIndex(-1, 0, 2));
  EXPECT_EQ(&map.allocate(BlockIndex(-1, 0, 2)), &block) << "allocating twice gives the same block";
  block.voxels[VoxelBlock::index(7, 1, 2)] = Voxel{0.01f, 3.0f};
  EXPECT_EQ(map.voxel(Eigen::Vector3i(-1, 1, 18)).weight, 3.0f);
  EXPECT_EQ(map.voxelCount(), static_cast<size_t>(kBlockVoxels));
  EXPECT_GE(map.memoryBytes(), sizeof(VoxelBlock));
  map.remove(BlockIndex(-1, 0, 2));
  EXPECT_EQ(map.find(BlockIndex(-1, 0, 2)), nullptr);
  EXPECT_THROW(map.allocate(BlockIndex(1 << 20, 0, 0)), std::out_of_range);
}

TEST(SparseMap, SamplesExactlyAsTheDenseGridAcrossBlockBorders) {
  // The same smooth field in both storages on the same lattice.
  const VolumeConfig sparse_config = sparseRoom();
  VolumeConfig dense_config = sparse_config;
  dense_config.type = MapType::kDense;
  dense_config.dims = Eigen::Vector3i(32, 32, 32);
  TsdfVolume dense(dense_config);
  SparseTsdfMap sparse(sparse_config);
  auto field = [](const Eigen::Vector3f& p) { return 0.05f * std::sin(3.0f * p.x()) + 0.02f * p.y() - 0.03f * p.z(); };
  for (int k = 0; k < 32; ++k)
    for (int j = 0; j < 32; ++j)
      for (int i = 0; i < 32; ++i) {
        const Voxel v{field(dense.position(i, j, k)), 1.0f};
        dense.setVoxel(i, j, k, v);
        sparse.allocate(SparseTsdfMap::blockOf({i, j, k})).voxels[VoxelBlock::index(SparseTsdfMap::localOf({i, j, k}))] = v;
      }
  ASSERT_EQ(sparse.blockCount(), 64u);
  int compared = 0;
  for (float x = 0.0f; x < 31.0f; x += 0.37f) {
    for (float y : {0.5f, 7.5f, 7.99f, 15.2f}) {  // inside blocks and straddling their borders
      for (float z : {3.25f, 7.75f, 23.9f}) {
        const Eigen::Vector3f p = dense.position(0, 0, 0) + dense.voxelSize() * Eigen::Vector3f(x, y, z);
        FieldSample a, b;
        ASSERT_TRUE(dense.sample(p, &a));
        ASSERT_TRUE(sparse.sample(p, &b)) << p.transpose();
        EXPECT_FLOAT_EQ(a.distance_m, b.distance_m);
        EXPECT_TRUE(a.gradient.isApprox(b.gradient, 1e-5f));
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 900);
  FieldSample s;
  EXPECT_FALSE(sparse.sample(dense.position(40, 3, 3), &s)) << "no block there";
  EXPECT_FALSE(sparse.sample(Eigen::Vector3f::Constant(std::nanf("")), &s));
  EXPECT_FALSE(sparse.sample(Eigen::Vector3f::Constant(1e9f), &s));
}

TEST(SparseMap, ARegionsSamplerAgreesWithTheMapInsideAndOutsideItsRegion) {
  SparseTsdfMap map(sparseRoom());
  for (int k = -4; k < 28; ++k)
    for (int j = 0; j < 24; ++j)
      for (int i = 0; i < 40; ++i) {
        if ((i / kBlockSide + k) % 5 == 0) continue;  // leave some blocks out
        map.allocate(SparseTsdfMap::blockOf({i, j, k})).voxels[VoxelBlock::index(SparseTsdfMap::localOf({i, j, k}))] =
            Voxel{0.001f * (i - j + 2 * k), 1.0f};
      }
  // A region over part of the blocks (indexed by probing its cells), one far larger than the map
  // (indexed by scanning the map) and none: the sampler must match the map everywhere.
  const Eigen::AlignedBox3f region(map.position(5, 2, 0), map.position(20, 18, 12));
  const Eigen::AlignedBox3f wide(map.position(-200, -200, -200), map.position(200, 200, 200));
  for (const Eigen::AlignedBox3f& box : {region, wide, Eigen::AlignedBox3f()}) {
    const std::unique_ptr<FieldSampler> sampler = map.sampler(box);
    int both_valid = 0, both_invalid = 0;
    for (float x = -2.0f; x < 42.0f; x += 0.61f) {
      for (float y = -1.0f; y < 25.0f; y += 0.93f) {
        for (float z = -6.0f; z < 30.0f; z += 1.07f) {
          const Eigen::Vector3f p = map.position(0, 0, 0) + map.voxelSize() * Eigen::Vector3f(x, y, z);
          FieldSample a, b;
          const bool in_map = map.sample(p, &a), in_sampler = sampler->sample(p, &b);
          ASSERT_EQ(in_map, in_sampler) << "at lattice " << x << " " << y << " " << z;
          if (!in_map) {
            ++both_invalid;
            continue;
          }
          ++both_valid;
          EXPECT_EQ(a.distance_m, b.distance_m);
          EXPECT_EQ(a.gradient, b.gradient);
        }
      }
    }
    EXPECT_GT(both_valid, 5000);
    EXPECT_GT(both_invalid, 5000);
  }
  // The default sampler of a dense grid reads through the grid itself.
  const TsdfVolume dense = toDenseVolume(map);
  FieldSample a, b;
  const Eigen::Vector3f p = map.position(10, 10, 10) + Eigen::Vector3f::Constant(0.3f * map.voxelSize());
  ASSERT_TRUE(dense.sample(p, &a));
  ASSERT_TRUE(dense.sampler(region)->sample(p, &b));
  EXPECT_EQ(a.distance_m, b.distance_m);
}

/// The room's grid at 2 cm: the storages are compared voxel by voxel, which needs no fine lattice
/// (and an eighth of the voxels keeps these tests quick under the sanitizers).
VolumeConfig coarseRoom(MapType type) {
  VolumeConfig config = test::roomVolume();
  config.voxel_size_m *= 2.0;
  config.dims /= 2;
  config.type = type;
  return config;
}

/// Frames of the synthetic room along the desk path, fused into a dense grid and a sparse map on
/// the same lattice.
struct FusionFixture : public ::testing::Test {
  void SetUp() override {
    const Integrator integrator(IntegratorConfig{});
    for (int n = 0; n < 3; ++n) {
      poses.push_back(synthetic::cameraPose(synthetic::Motion::kDesk, n * 0.5, 10.0));
      const DepthImage depth = test::renderRoom(poses.back(), camera);
      integrator.integrate(depth, camera, poses.back(), &dense);
      integrator.integrate(depth, camera, poses.back(), &sparse);
    }
  }
  /// Whether voxel (i, j, k) projects within 1e-3 pixels of a pixel border in some frame: there the
  /// float rounding of either storage's voxel positions may pick the neighbouring pixel.
  bool nearPixelBorder(int i, int j, int k) const {
    const Eigen::Vector3d p_W = dense.config().origin_W + dense.config().voxel_size_m * Eigen::Vector3d(i, j, k);
    for (const Eigen::Isometry3d& T_W_C : poses) {
      const Eigen::Vector3d p_C = T_W_C.inverse() * p_W;
      for (const double pixel : {camera.fx * p_C.x() / p_C.z() + camera.cx + 0.5,
                                 camera.fy * p_C.y() / p_C.z() + camera.cy + 0.5}) {
        if (std::fabs(pixel - std::round(pixel)) < 1e-3) return true;
      }
    }
    return false;
  }
  PinholeCamera camera = test::testCamera();
  std::vector<Eigen::Isometry3d> poses;
  TsdfVolume dense{coarseRoom(MapType::kDense)};
  SparseTsdfMap sparse{coarseRoom(MapType::kSparse)};
};

TEST_F(FusionFixture, FusedVoxelsEqualTheDenseGridsAndCoverItsTruncationBand) {
  constexpr float kSameValue_m = 1e-4f;  // a tenth of a millimetre
  const Eigen::Vector3i dims = dense.dims();
  size_t band = 0, covered = 0, same_history = 0, comparable = 0, same_value = 0, sparse_only = 0;
  for (int k = 0; k < dims.z(); ++k)
    for (int j = 0; j < dims.y(); ++j)
      for (int i = 0; i < dims.x(); ++i) {
        const Voxel d = dense.voxel(i, j, k);
        const Voxel s = sparse.voxel({i, j, k});
        sparse_only += s.weight > 0.0f && d.weight <= 0.0f;  // only where rounding moved a voxel into the image
        if (d.weight > 0.0f && d.distance_m < dense.positiveTruncation()) {
          ++band;
          covered += s.weight > 0.0f;
          // Fused from the same frames (weights count them): the same value, unless rounding put
          // the voxel's centre on the other side of a pixel border in one of them. The dense grid
          // steps along its rows by adding one voxel at a time, which moves centres by up to
          // ~1e-5 m at the far end of a 256-voxel row.
          same_history += d.weight == s.weight;
          if (d.weight == s.weight && !nearPixelBorder(i, j, k)) {
            ++comparable;
            same_value += std::fabs(d.distance_m - s.distance_m) < kSameValue_m;
          }
        }
      }
  EXPECT_GT(band, 20000u);
  // Only depth edges narrower than the allocation's ray spacing may miss a block in some frame.
  EXPECT_GE(static_cast<double>(covered), 0.999 * band) << covered << " of " << band << " voxels in the band";
  EXPECT_GE(static_cast<double>(same_history), 0.995 * band) << same_history << " of " << band;
  EXPECT_GT(static_cast<double>(comparable), 0.8 * band);
  EXPECT_GE(static_cast<double>(same_value), 0.999 * comparable) << same_value << " of " << comparable;
  EXPECT_LE(static_cast<double>(sparse_only), 1e-4 * band) << sparse_only << " voxels observed by the sparse map alone";
  EXPECT_LT(sparse.memoryBytes(), dense.memoryBytes() / 2) << "memory follows the surface, not the extent";
}

TEST_F(FusionFixture, SurfacesMatchTheDenseGrids) {
  // The sparse map also holds the far walls, beyond the dense grid: compare inside the grid only
  // (a cell short of its faces, where the dense grid has no neighbours to mesh with).
  const Eigen::AlignedBox3f grid(dense.position(1, 1, 1), dense.position(dense.dims() - 2 * Eigen::Vector3i::Ones()));
  const SurfaceCloud a = extractSurfaceCloud(dense), b = extractSurfaceCloud(sparse);
  auto countInside = [&grid](const std::vector<Eigen::Vector3f>& points) {
    return static_cast<double>(std::count_if(points.begin(), points.end(), [&](const auto& p) { return grid.contains(p); }));
  };
  const double points_dense = countInside(a.points_W), points_sparse = countInside(b.points_W);
  ASSERT_GT(points_dense, 5000);
  EXPECT_NEAR(points_sparse, points_dense, 0.002 * points_dense);
  const TriangleMesh mesh_a = extractMesh(dense), mesh_b = extractMesh(sparse);
  auto trianglesInside = [&grid](const TriangleMesh& mesh) {
    return static_cast<double>(std::count_if(mesh.triangles.begin(), mesh.triangles.end(), [&](const auto& t) {
      return grid.contains(mesh.vertices_W[t[0]]) && grid.contains(mesh.vertices_W[t[1]]) &&
             grid.contains(mesh.vertices_W[t[2]]);
    }));
  };
  const double triangles_dense = trianglesInside(mesh_a);
  EXPECT_NEAR(trianglesInside(mesh_b), triangles_dense, 0.002 * triangles_dense);
  // Every block's piece is a closed part of the whole: the pieces add up to the mesh.
  size_t triangles = 0;
  for (const BlockIndex& b_index : sparse.blockIndices()) triangles += extractBlockMesh(sparse, b_index).triangles.size();
  EXPECT_EQ(triangles, mesh_b.triangles.size());
}

TEST_F(FusionFixture, ARegionOfEitherStorageExportsAsTheVoxelsInsideIt) {
  // Around an observed voxel c: a box from a little below lattice voxel c - (10, 7, 13) to a
  // little beyond c + (9, 6, 13).
  Eigen::Vector3i c = dense.dims() / 2;
  for (int k = 0; k < dense.dims().z() && dense.voxel(c.x(), c.y(), c.z()).weight <= 0.0f; ++k) c.z() = k;
  ASSERT_GT(dense.voxel(c.x(), c.y(), c.z()).weight, 0.0f);
  c = c.cwiseMax(Eigen::Vector3i(10, 7, 13)).cwiseMin(dense.dims() - Eigen::Vector3i(10, 7, 14));
  const double v = dense.config().voxel_size_m;
  const Eigen::Vector3d lo = dense.config().origin_W + v * ((c - Eigen::Vector3i(10, 7, 13)).cast<double>() - Eigen::Vector3d(0.3, 0.8, 0.1));
  const Eigen::Vector3d hi = dense.config().origin_W + v * ((c + Eigen::Vector3i(9, 6, 13)).cast<double>() + Eigen::Vector3d(0.4, 0.0, 0.6));
  const Eigen::Vector3i first = c - Eigen::Vector3i(10, 7, 13);
  for (const TsdfMap* map : std::initializer_list<const TsdfMap*>{&dense, &sparse}) {
    const TsdfVolume region = toDenseVolume(*map, Eigen::AlignedBox3d(lo, hi));
    ASSERT_EQ(region.dims(), Eigen::Vector3i(20, 14, 27)) << toString(map->type());
    EXPECT_TRUE(region.position(0, 0, 0).isApprox(dense.position(first)));
    int observed = 0;
    for (int k = 0; k < 27; ++k) {
      for (int j = 0; j < 14; ++j) {
        for (int i = 0; i < 20; ++i) {
          const Eigen::Vector3i at = first + Eigen::Vector3i(i, j, k);
          const Voxel expected = map == &dense ? dense.voxel(at.x(), at.y(), at.z()) : sparse.voxel(at);
          ASSERT_EQ(region.voxel(i, j, k).weight, expected.weight) << i << " " << j << " " << k;
          if (expected.weight > 0.0f) {
            ASSERT_EQ(region.voxel(i, j, k).distance_m, expected.distance_m);
            ++observed;
          }
        }
      }
    }
    EXPECT_GT(observed, 100);
  }
  // A dense grid's region is clipped to the grid; one too thin for a volume is refused by name.
  const Eigen::Vector3d beyond = dense.config().origin_W + v * Eigen::Vector3d(-50.0, -50.0, -50.0);
  EXPECT_EQ(toDenseVolume(dense, Eigen::AlignedBox3d(beyond, lo)).dims(), first);
  try {
    toDenseVolume(sparse, Eigen::AlignedBox3d(lo, lo + Eigen::Vector3d(0.5 * v, 1.0, 1.0)));
    FAIL() << "a region without two voxels along x";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a volume needs 2 to 4096 along each axis"), std::string::npos) << e.what();
  }
}

TEST_F(FusionFixture, TheChunkedMeshFollowsTheMapSendingOnlyWhatChanged) {
  ChunkedMesher mesher;
  std::map<uint64_t, size_t> shown;  // chunk key -> triangles, as a viewer would hold them
  auto apply = [&shown](const std::vector<ChunkedMesher::Chunk>& chunks) {
    for (const ChunkedMesher::Chunk& chunk : chunks) {
      const uint64_t key = SparseTsdfMap::keyOf(chunk.index);
      if (chunk.mesh.triangles.empty()) {
        EXPECT_EQ(shown.erase(key), 1u) << "an empty chunk is sent only to take away what was shown";
      } else {
        shown[key] = chunk.mesh.triangles.size();
      }
    }
  };
  auto shownTriangles = [&shown] {
    size_t n = 0;
    for (const auto& entry : shown) n += entry.second;
    return n;
  };
  apply(mesher.update(sparse, sparse.revision()));
  EXPECT_TRUE(mesher.restarted()) << "the first update meshes everything";
  EXPECT_GT(shown.size(), 20u);
  EXPECT_EQ(shownTriangles(), extractMesh(sparse).triangles.size());
  const size_t all_chunks = shown.size();

  EXPECT_TRUE(mesher.update(sparse, sparse.revision()).empty()) << "nothing changed, nothing sent";
  EXPECT_FALSE(mesher.restarted());

  // A frame that measures only a small patch changes a small part of the map: the chunks sent
  // are a few of all, and the viewer's mesh is again the map's.
  const Integrator integrator(IntegratorConfig{});
  const Eigen::Isometry3d pose = synthetic::cameraPose(synthetic::Motion::kDesk, 4.0, 10.0);
  DepthImage patch = test::renderRoom(pose, camera);
  for (int v = 0; v < patch.height(); ++v) {
    for (int u = 0; u < patch.width(); ++u) {
      if (std::abs(u - patch.width() / 2) > 30 || std::abs(v - patch.height() / 2) > 30) patch.at(u, v) = 0.0f;
    }
  }
  integrator.integrate(patch, camera, pose, &sparse);
  const std::vector<ChunkedMesher::Chunk> changed = mesher.update(sparse, sparse.revision());
  EXPECT_FALSE(mesher.restarted());
  EXPECT_GT(changed.size(), 0u);
  EXPECT_LT(changed.size(), all_chunks / 4);
  apply(changed);
  // Chunk by chunk, what the viewer holds is what meshing the map afresh gives (which is the
  // whole mesh, as the first update showed).
  std::map<uint64_t, size_t> expected;
  for (const ChunkedMesher::Chunk& chunk : ChunkedMesher().update(sparse, sparse.revision())) {
    expected[SparseTsdfMap::keyOf(chunk.index)] = chunk.mesh.triangles.size();
  }
  EXPECT_EQ(shown, expected);

  // A change in the first voxel layer of a block at a chunk's lower x face moves triangles of
  // the chunk below: that chunk is sent too.
  BlockIndex moved(0, 0, 0);
  bool found = false;
  for (const BlockIndex& b : sparse.blockIndices()) {
    const BlockIndex below = b - BlockIndex(1, 0, 0);
    if (SparseTsdfMap::chunkOf(b) != SparseTsdfMap::chunkOf(below) && sparse.find(below) &&
        !extractBlockMesh(sparse, below).triangles.empty()) {
      moved = b;
      found = true;
      break;
    }
  }
  ASSERT_TRUE(found);
  VoxelBlock& block = *sparse.find(moved);
  for (int z = 0; z < kBlockSide; ++z) {
    for (int y = 0; y < kBlockSide; ++y) block.voxels[VoxelBlock::index(0, y, z)] = Voxel{-0.01f, 1.0f};
  }
  block.changed_at = sparse.beginRevision();
  const std::vector<ChunkedMesher::Chunk> layer = mesher.update(sparse, sparse.revision());
  EXPECT_TRUE(std::any_of(layer.begin(), layer.end(), [&](const ChunkedMesher::Chunk& chunk) {
    return chunk.index == SparseTsdfMap::chunkOf(moved - BlockIndex(1, 0, 0));
  }));
  apply(layer);
  expected.clear();
  for (const ChunkedMesher::Chunk& chunk : ChunkedMesher().update(sparse, sparse.revision())) {
    expected[SparseTsdfMap::keyOf(chunk.index)] = chunk.mesh.triangles.size();
  }
  EXPECT_EQ(shown, expected);

  sparse.clear();
  EXPECT_TRUE(mesher.update(sparse, sparse.revision()).empty());
  EXPECT_TRUE(mesher.restarted()) << "a cleared map starts the viewer over";
}

TEST_F(FusionFixture, ADenseRegionAndALiveCopyHoldTheSameVoxels) {
  Eigen::Vector3i first, dims;
  sparse.bounds(&first, &dims);
  const TsdfVolume region = sparse.toDense(first, dims);
  for (const Eigen::Vector3i& v : {Eigen::Vector3i(0, 0, 0), Eigen::Vector3i(dims / 2), Eigen::Vector3i(dims.x() - 1, 3, 9)}) {
    const Voxel a = region.voxel(v.x(), v.y(), v.z()), b = sparse.voxel(first + v);
    EXPECT_EQ(a.distance_m, b.distance_m);
    EXPECT_EQ(a.weight, b.weight);
    EXPECT_TRUE(region.position(v.x(), v.y(), v.z()).isApprox(sparse.position(first + v), 1e-5f));
  }

  // A copy kept up to date from the blocks changed since it was taken.
  SparseTsdfMap copy(sparse);
  const uint64_t synced = sparse.revision();
  const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kDesk, 4.0, 10.0);
  Integrator(IntegratorConfig{}).integrate(test::renderRoom(T_W_C, camera), camera, T_W_C, &sparse);
  const std::vector<BlockIndex> changed = sparse.changedSince(synced);
  ASSERT_FALSE(changed.empty());
  EXPECT_EQ(sparse.removedAt(), 0u) << "the blocks a fusion adds and leaves unobserved were never a reader's: "
                                       "dropping them is no removal to look for";
  EXPECT_LT(changed.size(), sparse.blockCount());
  copy.copyBlocksFrom(sparse, changed);
  EXPECT_EQ(copy.blockCount(), sparse.blockCount());
  EXPECT_EQ(test::totalWeight(copy), test::totalWeight(sparse));
  sparse.clear();
  EXPECT_EQ(sparse.blockCount(), 0u);
  EXPECT_GT(sparse.clearedAt(), synced) << "a reader can tell that its copy is stale";
}

TEST(BlockSwap, GivesBlocksBackExactlyAndReusesTheRecordsOfThoseTaken) {
  BlockSwapFile swap(test::scratchDirectory("swap"));
  auto blockOf = [](float seed) {
    VoxelBlock block;
    for (int n = 0; n < kBlockVoxels; ++n) block.voxels[n] = Voxel{seed + 1e-3f * n, seed * n};
    block.changed_at = static_cast<uint64_t>(seed);
    return block;
  };
  for (int key = 0; key < 3; ++key) swap.put(key, blockOf(key + 1.0f));
  EXPECT_EQ(swap.size(), 3u);
  const size_t bytes = swap.bytesOnDisk();
  VoxelBlock back;
  ASSERT_TRUE(swap.read(1, &back));
  EXPECT_EQ(std::memcmp(back.voxels.data(), blockOf(2.0f).voxels.data(), sizeof(back.voxels)), 0);
  EXPECT_EQ(back.changed_at, 2u);
  swap.erase(1);
  EXPECT_FALSE(swap.read(1, &back));
  swap.put(7, blockOf(9.0f));
  swap.put(0, blockOf(5.0f));  // replaces
  EXPECT_EQ(swap.bytesOnDisk(), bytes) << "the freed record is reused, a replaced one rewritten";
  ASSERT_TRUE(swap.read(0, &back));
  EXPECT_EQ(back.voxels[100].weight, blockOf(5.0f).voxels[100].weight);
  try {
    BlockSwapFile nowhere("/nonexistent/sdf_tracker");
    FAIL() << "a swap file in a missing directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/sdf_tracker"), std::string::npos) << e.what();
  }
}

TEST(SparseMap, AMemoryBudgetIsRefusedForTheDenseGridAndWithoutAPlaceForItsFile) {
  Settings settings = preset("default");
  setParameter(&settings, "MapType", std::string("dense"));
  setParameter(&settings, "MaxMemoryMB", 100.0);
  ASSERT_TRUE(settings.keepToOneMapWhereNeeded({"MapType", "MaxMemoryMB"}, false)) << "one map, as the user is told";
  const std::vector<std::string> violations = settings.validate();
  ASSERT_EQ(violations.size(), 1u);
  EXPECT_NE(violations[0].find("MaxMemoryMB=100 applies to MapType=sparse"), std::string::npos) << violations[0];
  setParameter(&settings, "MapType", std::string("sparse"));
  setParameter(&settings, "SwapDirectory", std::string("/nonexistent/swap"));
  try {
    SdfPipeline pipeline(settings.pipeline);
    FAIL() << "a pipeline without a place for its swap file";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SwapDirectory"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("/nonexistent/swap"), std::string::npos) << e.what();
  }
}

TEST(SparseMap, SettingsRefuseCompactVoxelsForTheSparseMap) {
  Settings settings = preset("default");
  setParameter(&settings, "MapType", std::string("sparse"));
  setParameter(&settings, "CompactVoxels", true);
  const std::vector<std::string> errors = settings.validate();
  ASSERT_FALSE(errors.empty());
  EXPECT_NE(errors.front().find("CompactVoxels"), std::string::npos) << errors.front();
  EXPECT_NE(errors.front().find("MapType"), std::string::npos) << errors.front();
  EXPECT_THROW(setParameter(&settings, "MapType", std::string("octree")), std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
