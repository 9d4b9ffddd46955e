// The map as submaps along the path: merging maps (as they are and moved), reading two as one,
// the pipeline's submaps, their handover or the recent ones tracked with the active one, a
// search in all of them, and the parameters that set them.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "sdf_tracker/map/map_merge.h"
#include "sdf_tracker/map/overlaid_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

VolumeConfig sparseLattice(double voxel_size_m = 0.02) {
  VolumeConfig config;
  config.type = MapType::kSparse;
  config.voxel_size_m = voxel_size_m;
  config.positive_truncation_m = 0.1;
  return config;
}

/// Sets one voxel of a sparse map (allocating its block).
void setVoxel(SparseTsdfMap* map, const Eigen::Vector3i& voxel, Voxel value) {
  map->allocate(SparseTsdfMap::blockOf(voxel)).voxels[VoxelBlock::index(SparseTsdfMap::localOf(voxel))] = value;
}

TEST(MapMerge, PartsAtTheIdentityAddUpAsFusionWouldHave) {
  SparseTsdfMap a(sparseLattice()), b(sparseLattice());
  setVoxel(&a, {1, 1, 1}, {0.02f, 2.0f});
  setVoxel(&b, {1, 1, 1}, {-0.01f, 1.0f});
  setVoxel(&b, {20, 0, 0}, {0.05f, 4.0f});  // a block only b holds
  const SparseTsdfMap merged = mergeMaps({{&a}, {&b}});
  const Voxel shared = merged.voxel({1, 1, 1});
  EXPECT_NEAR(shared.distance_m, (0.02 * 2.0 - 0.01 * 1.0) / 3.0, 1e-7);
  EXPECT_EQ(shared.weight, 3.0f);
  EXPECT_EQ(merged.voxel({20, 0, 0}).distance_m, 0.05f);
  EXPECT_EQ(merged.voxel({20, 0, 0}).weight, 4.0f);
  EXPECT_EQ(merged.voxel({2, 1, 1}).weight, 0.0f) << "a voxel neither observed stays unobserved";
  EXPECT_EQ(merged.blockCount(), 2u);
}

TEST(MapMerge, AMovedPartIsResampledWhereItLies) {
  // A field linear in space is what trilinear interpolation reproduces exactly, wherever the
  // samples fall: the merged field must be that field moved.
  SparseTsdfMap part(sparseLattice());
  const Eigen::Vector3f normal = Eigen::Vector3f(0.3f, 0.2f, 0.9f).normalized();
  auto field = [&](const Eigen::Vector3f& p) { return normal.dot(p) - 0.3f; };
  for (int z = 0; z < 32; ++z) {
    for (int y = 0; y < 32; ++y) {
      for (int x = 0; x < 32; ++x) setVoxel(&part, {x, y, z}, {field(part.position(x, y, z)), 1.0f});
    }
  }
  Eigen::Isometry3d T_target_part = Eigen::Isometry3d::Identity();
  T_target_part.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  T_target_part.translation() = Eigen::Vector3d(0.013, -0.021, 0.037);  // not whole voxels
  const SparseTsdfMap merged = mergeMaps({{&part, T_target_part}});
  const Eigen::Isometry3f T_part_target = T_target_part.inverse().cast<float>();
  int checked = 0;
  merged.forEachBlock([&](const SparseTsdfMap::BlockIndex& index, const VoxelBlock& block) {
    for (int i = 0; i < kBlockVoxels; ++i) {
      const Voxel& v = block.voxels[i];
      if (v.weight <= 0.0f) continue;
      const Eigen::Vector3i local(i % kBlockSide, (i / kBlockSide) % kBlockSide, i / (kBlockSide * kBlockSide));
      const Eigen::Vector3f p_target = merged.position(SparseTsdfMap::firstVoxel(index) + local);
      ASSERT_NEAR(v.distance_m, field(T_part_target * p_target), 2e-5) << "voxel at " << p_target.transpose();
      ASSERT_NEAR(v.weight, 1.0f, 1e-5);
      ++checked;
    }
  });
  // The part's interior cube (31 cells a side) moved holds about that many voxels of the merge.
  EXPECT_GT(checked, 25000);
  EXPECT_LT(checked, 31 * 31 * 31 + 1);
}

TEST(MapMerge, RefusesPartsOnAnotherLatticeNamingThem) {
  SparseTsdfMap a(sparseLattice(0.02)), b(sparseLattice(0.03));
  EXPECT_THROW(mergeMaps({}), std::invalid_argument);
  try {
    mergeMaps({{&a}, {&b}});
    FAIL() << "a part of 3 cm voxels was merged into one of 2 cm";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("part 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(mergeMaps({{&a}, {nullptr}}), std::invalid_argument);
}

/// Every voxel of `expected` in `actual` (to float rounding), and no block besides.
void expectSameMap(const SparseTsdfMap& actual, const SparseTsdfMap& expected, const std::string& what) {
  EXPECT_EQ(actual.blockCount(), expected.blockCount()) << what;
  int differing = 0;
  expected.forEachBlock([&](const SparseTsdfMap::BlockIndex& index, const VoxelBlock& block) {
    const VoxelBlock* other = actual.find(index);
    for (int i = 0; i < kBlockVoxels; ++i) {
      const Voxel& v = block.voxels[i];
      const Voxel w = other ? other->voxels[i] : Voxel{0.0f, 0.0f};
      differing += std::fabs(v.weight - w.weight) > 1e-5f ||
                   (v.weight > 0.0f && std::fabs(v.distance_m - w.distance_m) > 1e-6f);
    }
  });
  EXPECT_EQ(differing, 0) << what << ": voxels that differ from the merge of every part";
}

TEST(MapMerge, AGrowingMergeMergesOnlyThePartsAddedUntilOneChangesOrMoves) {
  SparseTsdfMap a(sparseLattice()), b(sparseLattice()), c(sparseLattice());
  for (int x = 0; x < 12; ++x) {
    setVoxel(&a, {x, 1, 1}, {0.01f * x, 1.0f});
    setVoxel(&b, {x + 4, 1, 1}, {-0.005f * x, 2.0f});
    setVoxel(&c, {x + 8, 1, 2}, {0.002f * x, 0.5f});
  }
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translation() = Eigen::Vector3d(0.04, 0.0, 0.0);  // two voxels
  auto part = [](const SparseTsdfMap& map, const Eigen::Isometry3d& T, uint64_t revision = 1) {
    return GrowingMerge::Part{{&map, T}, map.identity(), revision};
  };
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  GrowingMerge merge;
  expectSameMap(merge.update({part(a, I), part(b, moved)}), mergeMaps({{&a, I}, {&b, moved}}), "two parts");
  EXPECT_EQ(merge.partsMerged(), 2u);
  merge.update({part(a, I), part(b, moved)});
  EXPECT_EQ(merge.partsMerged(), 0u) << "nothing changed";
  expectSameMap(merge.update({part(a, I), part(b, moved), part(c, I)}), mergeMaps({{&a, I}, {&b, moved}, {&c, I}}),
                "a part added");
  EXPECT_EQ(merge.partsMerged(), 1u) << "only the part added";
  expectSameMap(merge.update({part(a, I), part(b, I), part(c, I)}), mergeMaps({{&a, I}, {&b, I}, {&c, I}}),
                "a part moved");
  EXPECT_EQ(merge.partsMerged(), 3u) << "a part moved: all again";
  setVoxel(&a, {0, 5, 5}, {0.03f, 1.0f});
  expectSameMap(merge.update({part(a, I, 2), part(b, I), part(c, I)}), mergeMaps({{&a, I}, {&b, I}, {&c, I}}),
                "a part changed");
  EXPECT_EQ(merge.partsMerged(), 3u) << "a part changed: all again";
  expectSameMap(merge.update({part(a, I, 2), part(c, I)}), mergeMaps({{&a, I}, {&c, I}}), "a part gone");
  EXPECT_EQ(merge.partsMerged(), 2u);
  EXPECT_THROW(merge.update({}), std::invalid_argument);
}

/// Fills voxels [x0, x1) x [0, 8) x [0, 8) with the plane x = offset_m at one weight.
void fillPlane(SparseTsdfMap* map, int x0, int x1, float offset_m, float weight) {
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) {
      for (int x = x0; x < x1; ++x) setVoxel(map, {x, y, z}, {map->position(x, y, z).x() - offset_m, weight});
    }
  }
}

TEST(OverlaidMap, ReadsTwoMapsAsTheirMergeWould) {
  // Over holds x voxels [0, 16), under [8, 24): a plane each, 2 cm apart.
  SparseTsdfMap over(sparseLattice()), under(sparseLattice());
  constexpr float kOverWeight = 6.0f, kUnderWeight = 2.0f, kOverPlane = 0.1f, kUnderPlane = 0.12f;
  fillPlane(&over, 0, 16, kOverPlane, kOverWeight);
  fillPlane(&under, 8, 24, kUnderPlane, kUnderWeight);
  const OverlaidMap unsettled(over, under, 64.0f), settled(over, under, kOverWeight);
  const SparseTsdfMap merged = mergeMaps({{&over}, {&under}});
  const auto at = [](float x) { return Eigen::Vector3f(x, 0.071f, 0.053f); };
  const Eigen::AlignedBox3f region(Eigen::Vector3f::Zero(), Eigen::Vector3f::Constant(0.5f));
  for (const OverlaidMap* map : {&unsettled, &settled}) {
    const std::unique_ptr<FieldSampler> sampler = map->sampler(region);
    FieldSample s, r;
    // Only over holds x = 0.05 m (voxel 2.5), only under x = 0.4 m (voxel 20).
    ASSERT_TRUE(map->sample(at(0.05f), &s));
    EXPECT_NEAR(s.distance_m, 0.05f - kOverPlane, 1e-6);
    ASSERT_TRUE(map->sample(at(0.4f), &s));
    EXPECT_NEAR(s.distance_m, 0.4f - kUnderPlane, 1e-6);
    EXPECT_FALSE(map->sample(at(0.6f), &s)) << "neither holds x = 0.6 m";
    // Both hold x = 0.23 m (voxel 11.5).
    ASSERT_TRUE(map->sample(at(0.23f), &s));
    if (map == &unsettled) {
      const float expected = ((0.23f - kOverPlane) * kOverWeight + (0.23f - kUnderPlane) * kUnderWeight) /
                             (kOverWeight + kUnderWeight);
      EXPECT_NEAR(s.distance_m, expected, 1e-6) << "the weighted average where both hold the ground";
    } else {
      EXPECT_NEAR(s.distance_m, 0.23f - kOverPlane, 1e-6) << "over alone where its weight is settled";
    }
    EXPECT_NEAR(s.gradient.x(), 1.0f, 1e-4);
    EXPECT_NEAR(s.gradient.tail<2>().norm(), 0.0f, 1e-4);
    // A region's sampler reads as the map does, everywhere; unsettled, as the two maps merged.
    for (float x = -0.1f; x < 0.6f; x += 0.0137f) {
      const bool sampled = map->sample(at(x), &s);
      ASSERT_EQ(sampler->sample(at(x), &r), sampled) << "x = " << x;
      if (!sampled) continue;
      EXPECT_EQ(r.distance_m, s.distance_m) << "x = " << x;
      EXPECT_EQ(r.gradient, s.gradient) << "x = " << x;
      if (map != &unsettled) continue;
      FieldSample m;
      ASSERT_TRUE(merged.sample(at(x), &m)) << "x = " << x;
      EXPECT_NEAR(s.distance_m, m.distance_m, 1e-6) << "x = " << x;
      EXPECT_LT((s.gradient - m.gradient).norm(), 1e-4) << "x = " << x;
    }
  }
  EXPECT_TRUE(unsettled.holdableRegion().contains(over.holdableRegion()));
  EXPECT_TRUE(unsettled.holdableRegion().contains(under.holdableRegion()));
  EXPECT_EQ(unsettled.voxelCount(), over.voxelCount() + under.voxelCount());
}

TEST(OverlaidMap, ReadsACellWhoseVoxelsEachMapHoldsOnlyPartOf) {
  // Over holds x voxels [0, 8), under [8, 16): the cell between voxels 7 and 8 lies in both.
  SparseTsdfMap over(sparseLattice()), under(sparseLattice());
  fillPlane(&over, 0, 8, 0.1f, 3.0f);
  fillPlane(&under, 8, 16, 0.1f, 3.0f);
  const OverlaidMap overlay(over, under, 64.0f);
  const Eigen::Vector3f p(0.15f, 0.071f, 0.053f);  // voxel 7.5
  FieldSample s;
  EXPECT_FALSE(over.sample(p, &s));
  EXPECT_FALSE(under.sample(p, &s));
  ASSERT_TRUE(overlay.sample(p, &s));
  EXPECT_NEAR(s.distance_m, 0.05f, 1e-6);
  ASSERT_TRUE(overlay.sampler(Eigen::AlignedBox3f(p, p))->sample(p, &s));
  EXPECT_NEAR(s.distance_m, 0.05f, 1e-6);
}

TEST(OverlaidMap, IsAReadOnlyViewOfOneLattice) {
  SparseTsdfMap a(sparseLattice(0.02)), b(sparseLattice(0.03));
  EXPECT_THROW(OverlaidMap(a, b, 64.0f), std::invalid_argument);
  EXPECT_THROW(OverlaidMap(a, a, 0.0f), std::invalid_argument);
  OverlaidMap view(a, a, 64.0f);
  EXPECT_THROW(view.clear(), std::logic_error);
  EXPECT_THROW(view.enableColour(), std::logic_error);
  EXPECT_THROW(view.clone(), std::logic_error);
  EXPECT_EQ(view.memoryBytes(), 0u) << "under holds no block: the overlay holds none of its own";
}

/// The overlay's field at lattice voxel (x, 1, 1) (at a voxel, its value there): distance, and
/// weight 1 when it was sampled.
Voxel overlayVoxel(const OverlaidMap& overlay, int x) {
  FieldSample s;
  const bool sampled = overlay.sample(overlay.position(x, 1, 1), &s);
  return {s.distance_m, sampled ? 1.0f : 0.0f};
}

/// fillPlane() as a frame fused into `map` would leave it: its blocks stamped with a new revision.
void fusePlane(SparseTsdfMap* map, int x0, int x1, float offset_m, float weight) {
  const uint64_t revision = map->beginRevision();
  fillPlane(map, x0, x1, offset_m, weight);
  map->forEachBlock([revision](const SparseTsdfMap::BlockIndex&, VoxelBlock& block) { block.changed_at = revision; });
}

TEST(OverlaidMap, TakesInWhatTheMapUnderItChangedOnUpdate) {
  SparseTsdfMap over(sparseLattice()), under(sparseLattice());
  fillPlane(&over, 0, 16, 0.1f, 6.0f);
  OverlaidMap overlay(over, under, 64.0f);
  const auto at = [](float x) { return Eigen::Vector3f(x, 0.071f, 0.053f); };
  const Eigen::AlignedBox3f region(Eigen::Vector3f::Zero(), Eigen::Vector3f::Constant(0.5f));
  FieldSample s, m;
  EXPECT_FALSE(overlay.sample(at(0.4f), &s)) << "x = 0.4 m (voxel 20): over holds none, under nothing yet";
  EXPECT_EQ(overlay.memoryBytes(), 0u);

  // A frame fused into under: read only once the overlay is updated.
  fusePlane(&under, 8, 24, 0.12f, 2.0f);
  EXPECT_THROW(overlay.sample(at(0.4f), &s), std::logic_error) << "sampled before update()";
  EXPECT_THROW(overlay.sampler(region), std::logic_error) << "sampled before update()";
  overlay.update();
  EXPECT_GT(overlay.memoryBytes(), 0u) << "a block of its own for each block both maps hold";
  const SparseTsdfMap merged = mergeMaps({{&over}, {&under}});
  const std::unique_ptr<FieldSampler> sampler = overlay.sampler(region);
  for (float x = -0.1f; x < 0.6f; x += 0.0137f) {
    const bool sampled = merged.sample(at(x), &m);
    ASSERT_EQ(overlay.sample(at(x), &s), sampled) << "x = " << x;
    ASSERT_EQ(sampler->sample(at(x), &s), sampled) << "x = " << x;
    if (sampled) {
      EXPECT_NEAR(s.distance_m, m.distance_m, 1e-6) << "x = " << x;
    }
  }

  // A second frame that changes only the block of voxels 16-23 (the plane moved, more weight):
  // that block is read anew, the others are kept as they were read.
  const Voxel before = overlayVoxel(overlay, 12);
  const uint64_t revision = under.beginRevision();
  // (Voxels 8-15 are written too, but their block is not stamped as changed: not read again.)
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) setVoxel(&under, {12, y, z}, {0.05f, 9.0f});
  }
  for (int z = 0; z < 8; ++z) {
    for (int y = 0; y < 8; ++y) {
      for (int x = 16; x < 24; ++x) setVoxel(&under, {x, y, z}, {under.position(x, y, z).x() - 0.13f, 4.0f});
    }
  }
  under.find(SparseTsdfMap::blockOf({16, 0, 0}))->changed_at = revision;
  overlay.update();
  ASSERT_TRUE(overlay.sample(at(0.4f), &s));
  EXPECT_NEAR(s.distance_m, 0.4f - 0.13f, 1e-6) << "the changed block";
  const Voxel after = overlayVoxel(overlay, 12);
  EXPECT_EQ(after.distance_m, before.distance_m) << "a block not stamped as changed";
  EXPECT_EQ(after.weight, before.weight);

  // A block both maps held that under no longer holds (swapped out) is over's alone again; the
  // overlay's own block of it goes.
  under.remove(SparseTsdfMap::blockOf({12, 0, 0}));
  overlay.update();
  ASSERT_TRUE(overlay.sample(at(0.23f), &s));
  EXPECT_NEAR(s.distance_m, 0.23f - 0.1f, 1e-6) << "voxel 11.5's block is over's alone";
  ASSERT_TRUE(overlay.sample(at(0.4f), &s));
  EXPECT_NEAR(s.distance_m, 0.4f - 0.13f, 1e-6) << "voxel 20's block is still under's";
  // Fused again, then cleared: over's alone.
  fusePlane(&under, 8, 24, 0.12f, 2.0f);
  overlay.update();
  ASSERT_TRUE(overlay.sample(at(0.23f), &s));
  EXPECT_NEAR(s.distance_m, ((0.23f - 0.1f) * 6.0f + (0.23f - 0.12f) * 2.0f) / 8.0f, 1e-6)
      << "voxel 11.5's block is both maps' again";
  under.clear();
  overlay.update();
  ASSERT_TRUE(overlay.sample(at(0.23f), &s));
  EXPECT_NEAR(s.distance_m, 0.23f - 0.1f, 1e-6) << "under cleared: over alone";
  EXPECT_FALSE(overlay.sample(at(0.4f), &s)) << "under cleared: nothing at voxel 20";

  // Where over's voxels are settled (weight 6 here), what under takes in changes nothing there.
  OverlaidMap settled(over, under, 6.0f);
  fusePlane(&under, 8, 24, 0.12f, 2.0f);
  settled.update();
  ASSERT_TRUE(settled.sample(at(0.23f), &s));
  EXPECT_NEAR(s.distance_m, 0.23f - 0.1f, 1e-6) << "over settled: over alone";
  ASSERT_TRUE(settled.sample(at(0.4f), &s));
  EXPECT_NEAR(s.distance_m, 0.4f - 0.12f, 1e-6) << "under alone where over holds nothing";
}

constexpr double kFramePeriod_s = 1.0 / 30.0;
constexpr double kDeskDuration_s = 10.0;

/// The default preset (a sparse map) of 3 cm voxels without loop closure, with submaps every `size_m`, each tracked
/// against the one before for `handover_frames` and then alone, or (track_recent_m) with the
/// submaps the camera left within that path.
PipelineConfig submapPipeline(double size_m, int handover_frames, double track_recent_m = 0.0) {
  PipelineConfig config = preset("default").pipeline;
  config.volume.voxel_size_m = 0.03;
  config.submaps.max_distance_m = size_m;
  config.submaps.handover_frames = handover_frames;
  config.submaps.track_recent_m = track_recent_m;
  config.loops.enabled = false;  // the submaps alone
  return config;
}

/// Where the desk path is at frame i, in the tracker's world (the first camera's frame).
Eigen::Isometry3d deskPose(int i) {
  const Eigen::Isometry3d T_scene_W = synthetic::cameraPose(synthetic::Motion::kDesk, 0.0, kDeskDuration_s);
  return T_scene_W.inverse() * synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s);
}
DepthImage deskFrame(int i, const PinholeCamera& camera) {
  return test::renderRoom(synthetic::cameraPose(synthetic::Motion::kDesk, i * kFramePeriod_s, kDeskDuration_s), camera);
}

TEST(Submaps, ANewSubmapStartsAlongThePathAndTracksAgainstTheOneBeforeFirst) {
  constexpr int kHandover = 5, kFrames = 60;
  const PinholeCamera camera = test::testCamera().scaledTo(160, 120);
  SdfPipeline pipeline(submapPipeline(0.1, kHandover));
  SdfPipeline one_map(submapPipeline(0.0, kHandover));
  int started = 0, in_previous = 0;
  double worst_m = 0.0, worst_one_map_m = 0.0;
  for (int i = 0; i < kFrames; ++i) {
    const DepthImage depth = deskFrame(i, camera);
    const FrameReport report = pipeline.processFrame(depth, camera, i * kFramePeriod_s);
    ASSERT_TRUE(report.track.ok()) << "frame " << i << ": " << report.track.message;
    ASSERT_TRUE(one_map.processFrame(depth, camera, i * kFramePeriod_s).track.ok()) << i;
    if (report.started_submap) {
      ++started;
      EXPECT_TRUE(report.fused) << "a submap starts with the frame that starts it";
      EXPECT_GT((pipeline.activeSubmapAnchor().translation() - pipeline.closedSubmaps().newestPlace().T_W_anchor.translation())
                    .norm(),
                0.1)
          << "frame " << i << " started a submap before the camera left the last";
    }
    in_previous += report.tracked_in_previous_submap;
    worst_m = std::max(worst_m, (pipeline.pose().translation() - deskPose(i).translation()).norm());
    worst_one_map_m = std::max(worst_one_map_m, (one_map.pose().translation() - deskPose(i).translation()).norm());
  }
  std::cout << "[ figures  ] " << pipeline.submapCount() << " submaps; worst position error " << worst_m * 1e3
            << " mm (one map: " << worst_one_map_m * 1e3 << " mm)\n";
  ASSERT_GE(started, 2) << "the desk path goes further than 0.2 m";
  EXPECT_EQ(pipeline.submapCount(), static_cast<size_t>(started) + 1);
  EXPECT_EQ(pipeline.closedSubmaps().place(0).T_W_anchor.matrix(), Eigen::Matrix4d::Identity())
      << "the first submap starts at the first frame";
  // The frame that starts a submap is tracked in the active one; the next kHandover - 1 in the
  // one it closed (unless the sequence ends first).
  EXPECT_LE(in_previous, started * (kHandover - 1));
  EXPECT_GE(in_previous, (started - 1) * (kHandover - 1));
  EXPECT_LT(worst_m, 2.0 * worst_one_map_m + 0.005) << "submaps made the path much worse than one map";

  // The whole map is every submap's measurements in one: weights add up, nothing is lost.
  double weight = test::totalWeight(pipeline.map());
  for (int node = 0; node < static_cast<int>(pipeline.closedSubmaps().size()); ++node) {
    weight += test::totalWeight(*pipeline.closedSubmaps().map(node));
  }
  EXPECT_NEAR(test::totalWeight(*pipeline.copyWholeMap()), weight, 1e-6 * weight);
  EXPECT_GT(pipeline.mapMemoryBytes(), pipeline.map().memoryBytes());
}

TEST(Submaps, RecentSubmapsAreTrackedWithTheActiveOneAsOneMap) {
  // The desk path passes over the same ground again and again: with the submaps left within 4 m
  // overlaid on the active one, each frame is tracked against what one map would hold there, and
  // no frame needs a handover.
  constexpr int kFrames = 90;
  const PinholeCamera camera = test::testCamera().scaledTo(160, 120);
  SdfPipeline recent(submapPipeline(0.1, 5, 4.0)), alone(submapPipeline(0.1, 5, 0.0)), one_map(submapPipeline(0.0, 5));
  double worst_recent_m = 0.0, worst_alone_m = 0.0, worst_one_map_m = 0.0;
  int started = 0, fused = 0;
  for (int i = 0; i < kFrames; ++i) {
    const DepthImage depth = deskFrame(i, camera);
    const double t_s = i * kFramePeriod_s;
    const FrameReport report = recent.processFrame(depth, camera, t_s);
    ASSERT_TRUE(report.track.ok()) << "frame " << i << ": " << report.track.message;
    EXPECT_FALSE(report.tracked_in_previous_submap) << "frame " << i << " was handed over";
    started += report.started_submap;
    fused += report.fused;
    ASSERT_TRUE(alone.processFrame(depth, camera, t_s).track.ok()) << i;
    ASSERT_TRUE(one_map.processFrame(depth, camera, t_s).track.ok()) << i;
    const Eigen::Vector3d truth = deskPose(i).translation();
    worst_recent_m = std::max(worst_recent_m, (recent.pose().translation() - truth).norm());
    worst_alone_m = std::max(worst_alone_m, (alone.pose().translation() - truth).norm());
    worst_one_map_m = std::max(worst_one_map_m, (one_map.pose().translation() - truth).norm());
  }
  std::cout << "[ figures  ] " << recent.submapCount() << " submaps; worst position error " << worst_recent_m * 1e3
            << " mm with the recent ones, " << worst_alone_m * 1e3 << " mm alone, " << worst_one_map_m * 1e3
            << " mm in one map\n";
  ASSERT_GE(started, 3);
  EXPECT_LT(worst_recent_m, worst_one_map_m + 0.002) << "tracked with the recent submaps, no worse than one map";
  // Each fused frame went into one submap only: no handover fuses it into two.
  int fused_in_submaps = 0;
  for (int node = 0; node < static_cast<int>(recent.submapCount()); ++node) {
    fused_in_submaps += recent.submapPlace(node).frames_fused;
  }
  EXPECT_EQ(fused_in_submaps, fused);
}

TEST(Submaps, ACameraLostAndBackInAnOldSubmapIsFoundInTheWholeMap) {
  PipelineConfig config = submapPipeline(0.1, 5);
  config.relocalise = true;
  SdfPipeline pipeline(config);
  const PinholeCamera camera = test::testCamera().scaledTo(160, 120);
  std::vector<Eigen::Isometry3d> tracked;
  int i = 0;
  for (; i < 60; ++i) {
    ASSERT_TRUE(pipeline.processFrame(deskFrame(i, camera), camera, i * kFramePeriod_s).track.ok()) << i;
    tracked.push_back(pipeline.pose());
  }
  ASSERT_GE(pipeline.closedSubmaps().size(), 2u);
  const size_t submaps_before = pipeline.submapCount();
  // The camera's pose is forgotten, and it views what the first submap holds: the search looks in
  // every submap.
  pipeline.relocalise();
  int found_at = -1;
  for (int k = 0; k < 30 && found_at < 0; ++k) {
    const FrameReport report = pipeline.processFrame(deskFrame(2 + k % 3, camera), camera, (i + k) * kFramePeriod_s);
    if (report.relocalisation.outcome == Relocaliser::Outcome::kAccepted) {
      found_at = k;
      EXPECT_TRUE(report.started_submap) << "found in the whole map: a new submap starts there";
    }
  }
  ASSERT_GE(found_at, 0) << "not found in the merged submaps";
  // Where the map has the view: where the camera was tracked to when it mapped it, within a voxel
  // (the submaps that hold it drifted apart by as much).
  EXPECT_LT((pipeline.pose().translation() - tracked[2 + found_at % 3].translation()).norm(), 0.02);
  EXPECT_EQ(pipeline.submapCount(), submaps_before + 1);
  const FrameReport next = pipeline.processFrame(deskFrame(3, camera), camera, (i + found_at + 1) * kFramePeriod_s);
  EXPECT_TRUE(next.track.ok()) << next.track.message;
  EXPECT_TRUE(next.tracked_in_previous_submap) << "the new submap's first frames track in the map the camera was found in";
}

TEST(Submaps, SavedSubmapsAreTakenUpWhereTheirGraphPlacedThemOrMergedWhereTheyCannotBe) {
  // Two submaps 10 m apart (the second placed there by its graph), one observed block each.
  SubmapGraph saved;
  for (int i = 0; i < 2; ++i) {
    auto map = std::make_unique<SparseTsdfMap>(sparseLattice(0.03));
    for (Voxel& voxel : map->allocate(SparseTsdfMap::BlockIndex(0, 0, 0)).voxels) voxel = Voxel{0.01f, 4.0f};
    SubmapPlace place;
    place.node = i;
    place.T_W_anchor.translation() = Eigen::Vector3d(10.0 * i, 0.0, 0.0);
    place.T_map_W.translation() = Eigen::Vector3d(10.0 * i, 0.0, 0.0);
    saved.submaps.push_back(Submap{std::move(map), place});
  }
  const Eigen::Isometry3d motion = saved.submaps[0].place.T_W_anchor.inverse() * saved.submaps[1].place.T_W_anchor;
  saved.edges.push_back(PoseEdge{0, 1, motion, PoseInformation::Identity(), PoseEdgeKind::kOdometry});
  auto copy = [&saved] {
    SubmapGraph c;
    for (const Submap& submap : saved.submaps) c.submaps.push_back(Submap{submap.map->clone(), submap.place});
    c.edges = saved.edges;
    return c;
  };

  PipelineConfig config = submapPipeline(1.0, 10);
  SdfPipeline pipeline(config);
  pipeline.setSubmaps(copy());
  ASSERT_EQ(pipeline.submapCount(), 2u);
  EXPECT_TRUE(pipeline.submapPlace(1).T_map_W.isApprox(saved.submaps[1].place.T_map_W));
  EXPECT_EQ(pipeline.poseGraph().edges().size(), 1u);
  EXPECT_FALSE(pipeline.poseKnown());
  EXPECT_TRUE(pipeline.mapPose().isApprox(Eigen::Isometry3d::Identity())) << "the search starts at the map's start";
  // A pose given by hand is in the map frame: beside a submap where the graph placed it (the
  // active one, whose own frame puts its voxels 10 m away), or beside another, but not beside none.
  for (const double x : {11.0, -1.0}) {
    Eigen::Isometry3d beside = Eigen::Isometry3d::Identity();
    beside.translation() = Eigen::Vector3d(x, 0.0, -1.0);
    EXPECT_NO_THROW(pipeline.relocalise(beside)) << "at x " << x << " m";
  }
  Eigen::Isometry3d nowhere = Eigen::Isometry3d::Identity();
  nowhere.translation() = Eigen::Vector3d(0.0, 40.0, 0.0);
  EXPECT_THROW(pipeline.relocalise(nowhere), std::invalid_argument);

  // Without submaps, or without the search that finds the camera in them: one map, merged.
  for (const bool submaps_off : {true, false}) {
    PipelineConfig one = config;
    if (submaps_off) one.submaps.max_distance_m = 0.0;
    else one.relocalise = false;
    one.loops.enabled = false;
    SdfPipeline merged(one);
    merged.setSubmaps(copy());
    EXPECT_EQ(merged.submapCount(), 1u);
    float distance_m = 0.0f;
    EXPECT_TRUE(merged.map().sampleDistance(Eigen::Vector3f(10.1f, 0.1f, 0.1f), &distance_m))
        << "the second submap's block where its graph placed it";
    EXPECT_NEAR(distance_m, 0.01f, 1e-5f);
  }
  // Submaps that cannot be a map's change nothing.
  SubmapGraph unjoined = copy();
  unjoined.edges.clear();
  EXPECT_THROW(pipeline.setSubmaps(std::move(unjoined)), std::invalid_argument);
  EXPECT_EQ(pipeline.submapCount(), 2u);
}

TEST(Submaps, ParametersRefuseWhatSubmapsCannotDoYetByName) {
  Settings dense = preset("default");
  setParameterFromText(&dense, "MapType", "dense");
  setParameterFromText(&dense, "SubmapSize", "2");
  const std::vector<std::string> dense_errors = dense.validate();
  ASSERT_EQ(dense_errors.size(), 1u);
  EXPECT_EQ(dense_errors[0], "SubmapSize=2 applies to MapType=sparse only");

  Settings swapping = preset("default");
  setParameterFromText(&swapping, "SubmapSize", "2");
  setParameterFromText(&swapping, "MaxMemoryMB", "64");
  EXPECT_TRUE(swapping.validate().empty()) << "submaps go to the swap file whole: " << swapping.validate()[0];

  Settings unused = preset("default");
  setParameterFromText(&unused, "SubmapSize", "0");
  setParameterFromText(&unused, "SubmapTurn", "30");
  const std::vector<std::string> notes = unused.withoutEffect({"SubmapSize", "SubmapTurn"});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("SubmapTurn=30 has no effect without SubmapSize"), std::string::npos) << notes[0];
  EXPECT_THROW(setParameterFromText(&unused, "SubmapTurn", "0"), std::invalid_argument);
  EXPECT_THROW(setParameterFromText(&unused, "SubmapHandoverFrames", "0"), std::invalid_argument);
  setParameterFromText(&unused, "SubmapTrackRecent", "2");
  ASSERT_EQ(unused.withoutEffect({"SubmapTrackRecent"}).size(), 1u);
  EXPECT_THROW(setParameterFromText(&unused, "SubmapTrackRecent", "-1"), std::invalid_argument);
}

TEST(Submaps, TheDefaultPresetClosesLoopsWhereTheMapCanHoldSubmapsAndSaysWhereItCannot) {
  const Settings defaults = preset("default");
  EXPECT_GT(defaults.pipeline.submaps.max_distance_m, 0.0);
  EXPECT_TRUE(defaults.pipeline.loops.enabled);
  for (const char* name : {"paper", "reference"}) {
    EXPECT_FALSE(preset(name).pipeline.submaps.enabled()) << name << ": the paper's one map";
    EXPECT_FALSE(preset(name).pipeline.loops.enabled) << name;
  }

  Settings sparse = defaults;
  EXPECT_FALSE(sparse.keepToOneMapWhereNeeded({"MapType"}, false).has_value());
  EXPECT_TRUE(sparse.pipeline.loops.enabled);
  EXPECT_TRUE(sparse.validate().empty());

  // Each map that cannot hold submaps, when SubmapSize was left to the preset: one map, no
  // loops, said once, and the settings valid.
  Settings dense = defaults;
  setParameterFromText(&dense, "MapType", "dense");
  const auto dense_note = dense.keepToOneMapWhereNeeded({"MapType"}, false);
  ASSERT_TRUE(dense_note.has_value());
  EXPECT_NE(dense_note->find("MapType=dense"), std::string::npos) << *dense_note;
  EXPECT_NE(dense_note->find("LoopClosure=false"), std::string::npos) << *dense_note;
  EXPECT_FALSE(dense.pipeline.submaps.enabled());
  EXPECT_FALSE(dense.pipeline.loops.enabled);
  EXPECT_TRUE(dense.validate().empty()) << dense.validate()[0];

  // A memory bound keeps the submaps and loops: whole submaps go to the swap file.
  Settings swapping = defaults;
  setParameterFromText(&swapping, "MaxMemoryMB", "64");
  EXPECT_FALSE(swapping.keepToOneMapWhereNeeded({"MaxMemoryMB"}, false).has_value());
  EXPECT_TRUE(swapping.pipeline.submaps.enabled());
  EXPECT_TRUE(swapping.pipeline.loops.enabled);
  EXPECT_TRUE(swapping.validate().empty());

  Settings no_loops = defaults;
  setParameterFromText(&no_loops, "LoopClosure", "false");
  const auto no_loops_note = no_loops.keepToOneMapWhereNeeded({"LoopClosure"}, false);
  ASSERT_TRUE(no_loops_note.has_value()) << "submaps without loops only cost";
  EXPECT_NE(no_loops_note->find("LoopClosure=false"), std::string::npos) << *no_loops_note;
  EXPECT_FALSE(no_loops.pipeline.submaps.enabled());
  Settings submaps_alone = defaults;
  setParameterFromText(&submaps_alone, "LoopClosure", "false");
  EXPECT_FALSE(submaps_alone.keepToOneMapWhereNeeded({"LoopClosure", "SubmapSize"}, false).has_value());
  EXPECT_TRUE(submaps_alone.pipeline.submaps.enabled()) << "submaps alone, when both are typed";

  Settings loading_grid = defaults;
  const auto grid_note = loading_grid.keepToOneMapWhereNeeded({}, true);
  ASSERT_TRUE(grid_note.has_value());
  EXPECT_NE(grid_note->find(".vti"), std::string::npos) << *grid_note;
  EXPECT_FALSE(loading_grid.pipeline.submaps.enabled());

  // What the user typed stands, and is refused by the parameter they typed.
  Settings typed_size = defaults;
  setParameterFromText(&typed_size, "MapType", "dense");
  EXPECT_FALSE(typed_size.keepToOneMapWhereNeeded({"MapType", "SubmapSize"}, false).has_value());
  ASSERT_EQ(typed_size.validate().size(), 1u);
  EXPECT_NE(typed_size.validate()[0].find("SubmapSize=1 applies to MapType=sparse only"), std::string::npos);

  // LoopClosure typed with a map that holds no submaps: refused by the two the user typed, not by
  // the SubmapSize the note set.
  const auto refusalWithLoopsTyped = [&](const char* name, const char* value) {
    Settings typed = defaults;
    setParameterFromText(&typed, name, value);
    EXPECT_TRUE(typed.keepToOneMapWhereNeeded({name, "LoopClosure"}, false).has_value()) << name << ": one map, said";
    const std::vector<std::string> errors = typed.validate();
    return errors.size() == 1 ? errors[0] : std::to_string(errors.size()) + " errors, not one";
  };
  const std::string dense_refusal = refusalWithLoopsTyped("MapType", "dense");
  EXPECT_NE(dense_refusal.find("LoopClosure=true applies to MapType=sparse only"), std::string::npos) << dense_refusal;

  // One map typed: loop closure goes with the submaps, said once, unless it was typed too.
  Settings one_map = defaults;
  setParameterFromText(&one_map, "SubmapSize", "0");
  const auto one_map_note = one_map.keepToOneMapWhereNeeded({"SubmapSize"}, false);
  ASSERT_TRUE(one_map_note.has_value()) << "SubmapSize=0 alone asks for one map";
  EXPECT_NE(one_map_note->find("LoopClosure=false"), std::string::npos) << *one_map_note;
  EXPECT_FALSE(one_map.pipeline.loops.enabled);
  EXPECT_TRUE(one_map.validate().empty()) << one_map.validate()[0];
  Settings one_map_with_loops = defaults;
  setParameterFromText(&one_map_with_loops, "SubmapSize", "0");
  EXPECT_FALSE(one_map_with_loops.keepToOneMapWhereNeeded({"SubmapSize", "LoopClosure"}, false).has_value());
  ASSERT_EQ(one_map_with_loops.validate().size(), 1u);
  EXPECT_NE(one_map_with_loops.validate()[0].find("LoopClosure=true needs SubmapSize > 0"), std::string::npos);
  Settings paper = preset("paper");
  EXPECT_FALSE(paper.keepToOneMapWhereNeeded({}, false).has_value()) << "the paper's one map needs no note";
}

/// Whether two sparse maps hold the same blocks, voxel for voxel and colour for colour.
::testing::AssertionResult sameBlocks(const TsdfMap& a_map, const TsdfMap& b_map) {
  const auto& a = static_cast<const SparseTsdfMap&>(a_map);
  const auto& b = static_cast<const SparseTsdfMap&>(b_map);
  if (a.blockIndices() != b.blockIndices()) return ::testing::AssertionFailure() << "different blocks";
  if (a.holdsColour() != b.holdsColour()) return ::testing::AssertionFailure() << "colour held by one only";
  for (const SparseTsdfMap::BlockIndex& index : a.blockIndices()) {
    const VoxelBlock& x = *a.find(index);
    const VoxelBlock& y = *b.find(index);
    for (int v = 0; v < kBlockVoxels; ++v) {
      if (x.voxels[v].distance_m != y.voxels[v].distance_m || x.voxels[v].weight != y.voxels[v].weight) {
        return ::testing::AssertionFailure() << "block " << index.transpose() << " voxel " << v << " differs";
      }
    }
    if (x.colours != y.colours) return ::testing::AssertionFailure() << "block " << index.transpose() << ": colours";
  }
  return ::testing::AssertionSuccess();
}

TEST(SubmapStore, ASubmapSwappedOutComesBackVoxelForVoxelWhileSomeoneHoldsIt) {
  const PinholeCamera camera = test::testCamera().scaledTo(160, 120);
  const PipelineConfig config = submapPipeline(0.0, 0);
  // Three submaps of the desk path's first, middle and last frames; the first holds colour.
  SubmapStore store(std::make_unique<BlockSwapFile>(test::scratchDirectory("submap_store")));
  std::vector<std::unique_ptr<TsdfMap>> originals;
  for (int n = 0; n < 3; ++n) {
    auto map = std::make_unique<SparseTsdfMap>(config.volume);
    Integrator(config.integrator).integrate(deskFrame(20 * n, camera), camera, deskPose(20 * n), map.get());
    if (n == 0) {
      map->enableColour();
      map->forEachBlock([](const SparseTsdfMap::BlockIndex&, VoxelBlock& block) { block.colours[7] = {200, 10, 30, 3}; });
    }
    originals.push_back(map->clone());
    SubmapPlace place;
    place.node = n;
    store.add(Submap{std::move(map), place});
  }
  const size_t all_bytes = store.memoryBytes();
  const size_t first_bytes = originals[0]->memoryBytes();
  const Eigen::AlignedBox3f first_box = store.mappedBox(0);

  store.swapOut(0);
  EXPECT_TRUE(store.swapped(0));
  EXPECT_EQ(store.inMemory(0), nullptr);
  EXPECT_EQ(store.swappedCount(), 1);
  EXPECT_EQ(store.memoryBytes(), all_bytes - first_bytes);
  EXPECT_GT(store.bytesOnDisk(), 0u);
  EXPECT_TRUE(store.mappedBox(0).isApprox(first_box)) << "its box is kept (a relocalisation guess is checked by it)";
  {
    const std::shared_ptr<const TsdfMap> back = store.map(0);
    EXPECT_TRUE(sameBlocks(*back, *originals[0]));
    EXPECT_EQ(store.map(0).get(), back.get()) << "read once while held: readers share it";
    EXPECT_EQ(store.memoryBytes(), all_bytes) << "the copy held counts";
    EXPECT_TRUE(store.swapped(0)) << "the submap stays in the file";
  }
  EXPECT_EQ(store.memoryBytes(), all_bytes - first_bytes) << "let go: freed";
  EXPECT_TRUE(sameBlocks(*store.map(1), *originals[1])) << "one in memory is handed as it is";

  store.swapOut(0);  // swapped already: nothing
  EXPECT_THROW(store.swapOut(2), std::logic_error) << "the newest may still be fused into";
  EXPECT_THROW(store.map(3), std::out_of_range);
  SubmapStore without_file;
  auto map = std::make_unique<SparseTsdfMap>(config.volume);
  without_file.add(Submap{std::move(map), SubmapPlace()});
  without_file.add(Submap{std::make_unique<SparseTsdfMap>(config.volume), SubmapPlace()});
  EXPECT_THROW(without_file.swapOut(0), std::logic_error);

  store.clear();
  EXPECT_TRUE(store.empty());
  EXPECT_EQ(store.bytesOnDisk(), 0u);
}

TEST(Submaps, AMemoryBoundSwapsWholeClosedSubmapsWithoutChangingThePathOrTheMap) {
  // Without recent submaps merged in the background or loops, a run is the same every time: with
  // a bound that holds about a third of the submaps, every pose and the whole map (the swapped
  // submaps read back) are those of the run without one, and the map stays within the bound.
  constexpr int kFrames = 60;
  const PinholeCamera camera = test::testCamera().scaledTo(160, 120);
  PipelineConfig config = submapPipeline(0.05, 3);
  SdfPipeline unbounded(config);
  std::vector<DepthImage> frames;
  std::vector<Eigen::Isometry3d> poses;
  size_t peak_bytes = 0;
  for (int i = 0; i < kFrames; ++i) {
    frames.push_back(deskFrame(i, camera));
    ASSERT_TRUE(unbounded.processFrame(frames.back(), camera, i * kFramePeriod_s).track.ok()) << i;
    poses.push_back(unbounded.pose());
    peak_bytes = std::max(peak_bytes, unbounded.mapMemoryBytes());
  }
  ASSERT_GE(unbounded.submapCount(), 6u);
  config.max_map_memory_mb = 0.4 * peak_bytes / 1048576.0;
  config.swap_directory = test::scratchDirectory("submap_budget");
  SdfPipeline bounded(config);
  int swapped_out = 0, notices = 0;
  bool was_over = false;
  for (int i = 0; i < kFrames; ++i) {
    const FrameReport report = bounded.processFrame(frames[i], camera, i * kFramePeriod_s);
    ASSERT_TRUE(report.track.ok()) << i;
    ASSERT_TRUE(report.swap_error.empty()) << report.swap_error;
    ASSERT_TRUE(bounded.pose().isApprox(poses[i], 1e-12)) << "frame " << i << " moved by the bound";
    swapped_out += report.submaps_swapped_out;
    notices += !report.swap_notice.empty();
    // Over the bound after swapping (the active and newest submaps alone need more): said once.
    const bool over = bounded.mapMemoryBytes() > config.max_map_memory_mb * 1048576.0;
    EXPECT_EQ(!report.swap_warning.empty(), over && !was_over) << "frame " << i << ": " << report.swap_warning;
    was_over = over;
  }
  std::cout << "[ figures  ] " << bounded.submapCount() << " submaps, " << bounded.closedSubmaps().swappedCount()
            << " in the swap file; map " << bounded.mapMemoryBytes() / 1048576.0 << " MiB under "
            << config.max_map_memory_mb << " MiB (unbounded peak " << peak_bytes / 1048576.0 << " MiB)\n";
  EXPECT_GT(swapped_out, 0);
  EXPECT_EQ(notices, 1) << "the user is told once that submaps go to the swap file";
  EXPECT_LE(bounded.mapMemoryBytes(), config.max_map_memory_mb * 1048576.0);
  EXPECT_GE(bounded.closedSubmaps().swappedCount(), 2);
  EXPECT_TRUE(sameBlocks(*bounded.copyWholeMap(), *unbounded.copyWholeMap()));
  const SubmapGraph saved = bounded.copySubmaps();
  ASSERT_EQ(saved.submaps.size(), bounded.submapCount());
  for (int node = 0; node + 1 < static_cast<int>(saved.submaps.size()); ++node) {
    EXPECT_TRUE(sameBlocks(*saved.submaps[node].map, *unbounded.closedSubmaps().map(node))) << "submap " << node;
  }
}

}  // namespace
}  // namespace sdf_tracker
