// Whole sequences through the sparse block map: it tracks as the dense grid does, a saved map is
// tracked in after loading, the house walk's path, and a memory budget that swaps blocks to disk
// without changing a pose. Seconds to a minute each: run in the release build only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <iostream>
#include <memory>
#include <vector>

#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

using BlockIndex = SparseTsdfMap::BlockIndex;
/// The desk path's pose at frame i (30 Hz), in the room.
Eigen::Isometry3d deskPose(int i) { return synthetic::cameraPose(synthetic::Motion::kDesk, i / 30.0, 10.0); }

/// The room seen from deskPose(i) with Kinect-like noise (a fixed seed per frame).
DepthImage noisyDeskFrame(const PinholeCamera& camera, int i) {
  static const synthetic::Scene room = synthetic::Scene::indoorRoom();
  return room.render(camera, deskPose(i), synthetic::NoiseModel(), static_cast<uint32_t>(i));
}

TEST(SparseMap, TracksTheDeskPathAsTheDenseGridDoes) {
  const PinholeCamera camera = test::testCamera();
  Settings settings = preset("default");
  // A dense grid that holds the whole room, so that both maps see the same walls.
  settings.pipeline.volume.dims = Eigen::Vector3i(160, 160, 160);
  settings.pipeline.volume.voxel_size_m = 0.04;
  settings.pipeline.initial_camera_in_grid = Eigen::Vector3d(0.5, 0.5, 0.4);
  // One map in each storage (the dense grid holds no submaps).
  setParameter(&settings, "SubmapSize", 0.0);
  setParameter(&settings, "LoopClosure", false);
  setParameter(&settings, "MapType", std::string("dense"));
  SdfPipeline dense(settings.pipeline);
  setParameter(&settings, "MapType", std::string("sparse"));
  SdfPipeline sparse(settings.pipeline);
  ASSERT_EQ(sparse.map().type(), MapType::kSparse);
  double worst_m = 0.0;
  for (int i = 0; i < 60; ++i) {
    const DepthImage depth = noisyDeskFrame(camera, i);
    const FrameReport a = dense.processFrame(depth, camera, i / 30.0);
    const FrameReport b = sparse.processFrame(depth, camera, i / 30.0);
    ASSERT_TRUE(a.track.tracked() && b.track.tracked()) << "frame " << i;
    worst_m = std::max(worst_m, (dense.pose().translation() - sparse.pose().translation()).norm());
  }
  EXPECT_LT(worst_m, 1e-3) << "trajectories of the two storages part by " << worst_m << " m";
  EXPECT_LT(sparse.map().memoryBytes(), dense.map().memoryBytes() / 4);
}

TEST(SparseMap, ASavedMapIsTrackedAfterLoadingAsBeforeSaving) {
  const PinholeCamera camera = test::testCamera();
  Settings settings = preset("default");
  setParameter(&settings, "MapType", std::string("sparse"));
  SdfPipeline mapper(settings.pipeline);
  // The pipeline's world is the first camera's frame.
  auto truth = [](int i) { return deskPose(0).inverse() * deskPose(i); };
  double mapping_worst_m = 0.0;
  for (int i = 0; i < 45; ++i) {
    ASSERT_TRUE(mapper.processFrame(noisyDeskFrame(camera, i), camera, i / 30.0).track.tracked()) << "frame " << i;
    mapping_worst_m = std::max(mapping_worst_m, (mapper.pose().translation() - truth(i).translation()).norm());
  }
  const std::string path = test::scratchDirectory("tracked_map") + "/map.sdfmap";
  io::writeMap(path, *mapper.copyWholeMap());

  // A new session (dense by its settings) loads the file and tracks the same frames in it. Where
  // it starts is not known: the map's origin (the first camera's pose) is tried first, and
  // confirmed over RelocaliseConfirmFrames frames before anything is fused.
  SdfPipeline session(preset("default").pipeline);
  session.setMap(io::readMap(path));
  EXPECT_EQ(session.map().type(), MapType::kSparse) << "the file's storage replaces the configured one";
  EXPECT_EQ(session.map().voxelCount(), mapper.map().voxelCount()) << "every block loaded";
  double worst_m = 0.0;
  int searched = 0;
  for (int i = 0; i < 45; i += 3) {
    const FrameReport report = session.processFrame(noisyDeskFrame(camera, i), camera, i / 30.0);
    if (report.track.status == TrackStatus::kRelocalising) {
      ++searched;
      EXPECT_FALSE(report.fused) << "frame " << i;
      continue;
    }
    ASSERT_TRUE(report.track.tracked()) << "frame " << i << ": " << report.track.message;
    worst_m = std::max(worst_m, (session.pose().translation() - truth(i).translation()).norm());
  }
  EXPECT_EQ(searched, session.config().relocaliser.confirm_frames - 1);
  std::cout << "error against the truth: " << mapping_worst_m * 1e3 << " mm while mapping, " << worst_m * 1e3
            << " mm in the loaded map\n";
  EXPECT_LT(worst_m, mapping_worst_m + 1e-3) << "tracking in the loaded map is worse than while mapping";
}

TEST(HouseWalk, WalksAtHalfAMetrePerSecondInsideTheHouseAndAlwaysSeesIt) {
  // 2,600 frames at 30 Hz cover about 43 m; the path must be at least that long.
  double length_m = 0.0;
  Eigen::Vector3d previous = synthetic::cameraPose(synthetic::Motion::kWalk, 0.0, 0.0).translation();
  const synthetic::Scene house = synthetic::Scene::forMotion(synthetic::Motion::kWalk);
  synthetic::NoiseModel exact;
  exact.enabled = false;
  const PinholeCamera camera = test::testCamera();
  for (int i = 1; i <= 2600; ++i) {
    const Eigen::Isometry3d T_W_C = synthetic::cameraPose(synthetic::Motion::kWalk, i / 30.0, 0.0);
    const Eigen::Vector3d here = T_W_C.translation();
    const double step_m = (here - previous).norm();
    ASSERT_LT(step_m, 0.03) << "frame " << i << ": faster than a walk";
    length_m += step_m;
    previous = here;
    ASSERT_TRUE(here.x() > 0.4 && here.x() < 11.6 && here.z() > -3.6 && here.z() < 5.6) << "frame " << i;
    if (i % 200 == 0) {
      const DepthImage depth = house.render(camera, T_W_C, exact, 0);
      EXPECT_GT(depth.countMeasurements(), depth.width() * depth.height() / 2) << "frame " << i << " sees little";
    }
  }
  EXPECT_GT(length_m, 43.0);
}

TEST(SparseMap, AMemoryBudgetSwapsBlocksOutAndBackWithoutChangingTheTrajectoryOrTheMap) {
  // The first 12 s of the house walk: down the corridor, turning into rooms.
  const PinholeCamera camera = test::testCamera();
  const synthetic::Scene house = synthetic::Scene::forMotion(synthetic::Motion::kWalk);
  synthetic::NoiseModel exact;
  exact.enabled = false;
  Settings settings = preset("default");
  setParameter(&settings, "MapType", std::string("sparse"));
  // One map: swapping keeps to one (a bound with submaps is refused).
  setParameter(&settings, "SubmapSize", 0.0);
  setParameter(&settings, "LoopClosure", false);
  SdfPipeline unbounded(settings.pipeline);
  std::vector<DepthImage> frames;
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < 360; i += 2) {
    frames.push_back(house.render(camera, synthetic::cameraPose(synthetic::Motion::kWalk, i / 30.0, 0.0), exact, 0));
    ASSERT_TRUE(unbounded.processFrame(frames.back(), camera, i / 30.0).track.tracked()) << "frame " << i;
    poses.push_back(unbounded.pose());
  }
  const double full_mb = unbounded.map().memoryBytes() / 1048576.0;

  setParameter(&settings, "MaxMemoryMB", 0.3 * full_mb);
  setParameter(&settings, "SwapDirectory", test::scratchDirectory("budget"));
  SdfPipeline bounded(settings.pipeline);
  size_t swapped_out = 0, swapped_in = 0;
  bool was_over = false;
  for (size_t f = 0; f < frames.size(); ++f) {
    const FrameReport report = bounded.processFrame(frames[f], camera, 2.0 * f / 30.0);
    ASSERT_TRUE(report.track.tracked()) << "frame " << 2 * f;
    ASSERT_TRUE(report.swap_error.empty()) << report.swap_error;
    // The first view alone needs more than the bound: the user is told once, when it is overrun.
    const bool over = bounded.map().memoryBytes() > 0.3 * full_mb * 1048576.0;
    EXPECT_EQ(!report.swap_warning.empty(), over && !was_over) << "frame " << 2 * f << ": " << report.swap_warning;
    was_over = over;
    swapped_out += report.blocks_swapped_out;
    swapped_in += report.blocks_swapped_in;
    ASSERT_TRUE(bounded.pose().isApprox(poses[f], 1e-12)) << "frame " << 2 * f << " moved by the budget";
  }
  std::cout << "map " << full_mb << " MiB unbounded, " << bounded.map().memoryBytes() / 1048576.0 << " MiB under "
            << 0.3 * full_mb << " MiB; blocks swapped out " << swapped_out << ", read back " << swapped_in << "\n";
  EXPECT_LE(bounded.map().memoryBytes(), 0.3 * full_mb * 1048576.0);
  EXPECT_GT(swapped_out, 0u);
  EXPECT_GT(swapped_in, 0u) << "the walk turns back towards swapped blocks";
  // Swapped blocks included, the map is the unbounded one, voxel for voxel.
  const std::unique_ptr<TsdfMap> whole = bounded.copyWholeMap();
  const auto& a = static_cast<const SparseTsdfMap&>(unbounded.map());
  const auto& b = static_cast<const SparseTsdfMap&>(*whole);
  ASSERT_EQ(a.blockIndices(), b.blockIndices());
  for (const BlockIndex& index : a.blockIndices()) {
    ASSERT_EQ(std::memcmp(a.find(index)->voxels.data(), b.find(index)->voxels.data(), sizeof(VoxelBlock::voxels)), 0)
        << "block " << index.transpose();
  }

  // After a reset the map starts anew, and so does its swapping: the user is told again.
  bounded.reset();
  bool told_again = false;
  for (size_t f = 0; f < frames.size() && !told_again; ++f) {
    told_again = !bounded.processFrame(frames[f], camera, 100.0 + 2.0 * f / 30.0).swap_notice.empty();
  }
  EXPECT_TRUE(told_again) << "no notice that the new map swaps";
}

}  // namespace
}  // namespace sdf_tracker
