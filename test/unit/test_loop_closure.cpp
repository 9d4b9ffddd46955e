// Loop closure between submaps: the edges' uncertainty, the loop detector's search (in a submap in
// memory or in the swap file), and the parameters that set it. A camera that comes back to where
// it started, in whole runs: test/sequences/test_loop_closure_runs.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/pipeline/loop_closure.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/pipeline/tracked_path.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/tracking/tracker.h"
#include "sdf_tracker/util/se3.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

TEST(LoopClosure, OdometryIsTrustedLessTheFurtherItGoesAndALoopByItsFit) {
  LoopClosureConfig config;
  Eigen::Isometry3d metre = Eigen::Isometry3d::Identity();
  metre.translation() = Eigen::Vector3d(0.6, 0.0, 0.8);
  const PoseInformation one_metre = odometryEdgeInformation(config, metre);
  const double sigma_m = config.odometry_floor_m + config.odometry_drift * 1.0;
  const double sigma_rad = (config.odometry_floor_deg + config.odometry_drift_deg_per_m * 1.0) * M_PI / 180.0;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(one_metre(i, i), 1.0 / (sigma_m * sigma_m), 1e-6);
    EXPECT_NEAR(one_metre(i + 3, i + 3), 1.0 / (sigma_rad * sigma_rad), 1e-3);
  }
  EXPECT_EQ((one_metre - PoseInformation(one_metre.diagonal().asDiagonal())).norm(), 0.0) << "diagonal";
  // Standing still: the floors, not infinite trust.
  const PoseInformation still = odometryEdgeInformation(config, Eigen::Isometry3d::Identity());
  EXPECT_NEAR(still(0, 0), 1.0 / (config.odometry_floor_m * config.odometry_floor_m), 1e-6);
  EXPECT_GT(still(0, 0), one_metre(0, 0));
  // A fit as good as exact, the camera at both submaps' anchors: the loop's own sigma in every
  // direction.
  const Eigen::Isometry3d at_anchor = Eigen::Isometry3d::Identity();
  const Eigen::Matrix<double, 6, 6> exact = Eigen::Matrix<double, 6, 6>::Zero();
  const PoseInformation loop = loopEdgeInformation(config, at_anchor, at_anchor, exact, at_anchor);
  const double loop_sigma_rad = config.loop_sigma_deg * M_PI / 180.0;
  EXPECT_NEAR(loop(2, 2), 1.0 / (config.loop_sigma_m * config.loop_sigma_m), 1e-3);
  EXPECT_NEAR(loop(5, 5), std::pow(loop_sigma_rad, -2), 1e-3);
  // The camera a metre from the anchor of the submap it was tracked in, or found a metre from the
  // old submap's: the drift over that metre besides (without the floors, which the loop's own sigma
  // is).
  const double drift_m = config.odometry_drift * 1.0;
  const double drift_rad = config.odometry_drift_deg_per_m * 1.0 * M_PI / 180.0;
  for (const PoseInformation& stretched : {loopEdgeInformation(config, at_anchor, at_anchor, exact, metre),
                                           loopEdgeInformation(config, at_anchor, metre, exact, metre)}) {
    EXPECT_NEAR(stretched(2, 2), 1.0 / (config.loop_sigma_m * config.loop_sigma_m + drift_m * drift_m), 1e-3);
    EXPECT_NEAR(stretched(5, 5), 1.0 / (loop_sigma_rad * loop_sigma_rad + drift_rad * drift_rad), 1e-3);
  }
}

TEST(LoopClosure, ALoopHoldsNothingAlongADirectionItsFitLeftUnconstrained) {
  // The camera found in the old submap S at T_S_C; the edge's `to` node elsewhere (a lever of
  // more than a metre, turned), as a loop's anchor is.
  LoopClosureConfig config;
  const Eigen::Isometry3d T_S_C = expSe3((Twist() << 0.1, -0.4, 0.2, 0.5, 0.1, 1.2).finished());
  const Eigen::Isometry3d T_S_to = expSe3((Twist() << -0.3, 0.2, 0.1, -0.6, 0.3, 0.4).finished());
  const double sigma2_m = config.loop_sigma_m * config.loop_sigma_m;
  // Each direction of the camera's small motion xi = [w; v] about its centre (the tracker's
  // covariance's), left unconstrained in turn.
  for (int d = 0; d < 6; ++d) {
    Twist xi = Twist::Zero();
    xi(d) = 1e-6;
    Eigen::Matrix<double, 6, 6> fit = 1e-8 * Eigen::Matrix<double, 6, 6>::Identity();
    fit(d, d) = kUnconstrainedVariance;
    const PoseInformation information = loopEdgeInformation(config, T_S_C, T_S_C, fit, T_S_to);
    // The edge's error if the camera were moved by xi (T = Tr(c) exp(xi) Tr(-c) T_S_C): the `to`
    // node moves with it.
    Eigen::Isometry3d to_centre = Eigen::Isometry3d::Identity(), from_centre = Eigen::Isometry3d::Identity();
    to_centre.translation() = T_S_C.translation();
    from_centre.translation() = -T_S_C.translation();
    const Eigen::Isometry3d moved = to_centre * expSe3(xi) * from_centre;
    const Twist log = logSe3(T_S_to.inverse() * moved * T_S_to);  // [rotation; translation]
    Eigen::Matrix<double, 6, 1> error;
    error << log.tail<3>(), log.head<3>();  // the graph's order: translation first
    const double held = error.dot(information * error);
    EXPECT_LT(held, 1e-3 * error.squaredNorm() / sigma2_m) << "direction " << d << " is still held";
    // Any other direction is held as the loop's sigma says.
    Twist other = Twist::Zero();
    other((d + 1) % 6) = 1e-6;
    const Eigen::Isometry3d other_moved = to_centre * expSe3(other) * from_centre;
    const Twist other_log = logSe3(T_S_to.inverse() * other_moved * T_S_to);
    Eigen::Matrix<double, 6, 1> other_error;
    other_error << other_log.tail<3>(), other_log.head<3>();
    EXPECT_GT(other_error.dot(information * other_error), 1e-3 * other_error.squaredNorm() / sigma2_m)
        << "direction " << (d + 1) % 6 << " is not held";
  }
}

/// An old submap (0) of the room mapped along the desk path, one after it (1) that saw nothing
/// alike, and the active one (2), 5 m of path on: the camera back on the desk path. With
/// `swapped_out`, submap 0 is in a swap file (as MaxMemoryMB leaves a submap far from the camera).
struct DeskSubmaps {
  PipelineConfig config = preset("default").pipeline;
  PinholeCamera camera = test::testCamera();
  SdfPipeline mapping{config};
  SubmapStore closed;
  SubmapPlace active;
  std::vector<int> keyframe_submaps;

  static Eigen::Isometry3d desk(double t_s) { return synthetic::cameraPose(synthetic::Motion::kDesk, t_s, 10.0); }

  explicit DeskSubmaps(bool swapped_out = false)
      : closed(swapped_out ? std::make_unique<BlockSwapFile>(test::scratchDirectory("desk_swap")) : nullptr) {
    for (double t = 0.0; t < 3.0; t += 1.0 / 6.0) mapping.processFrameAtPose(test::renderRoom(desk(t), camera), camera, desk(t), t);
    closed.add(Submap{mapping.copyWholeMap(), SubmapPlace()});
    SubmapPlace after;
    after.node = 1;
    after.path_m = 1.0;
    closed.add(Submap{makeMap(config.volume), after});
    if (swapped_out) closed.swapOut(0);
    active.node = 2;
    active.path_m = 5.0;
    keyframe_submaps.assign(mapping.places().keyframes().size(), 0);
  }
};

TEST(LoopDetector, SearchesAFrameInTheBackgroundAndReportsItAtALaterOne) {
  // The graph (no correction yet) puts the camera where it is in submap 0, which is in the swap
  // file: the search reads it back on its own thread.
  const DeskSubmaps desks(/*swapped_out=*/true);
  ASSERT_TRUE(desks.closed.swapped(0));
  ASSERT_FALSE(desks.keyframe_submaps.empty());

  LoopClosureConfig loops;
  loops.check_interval_frames = 1;
  LoopDetector detector(loops, desks.config.relocaliser, desks.config.tracker, desks.config.places);
  std::vector<Eigen::Isometry3d> handed;  // every frame's pose, in order
  std::optional<LoopDetector::Step> found;
  int searched = 0;
  for (int frame = 0; frame < 90 && !found; ++frame) {
    const Eigen::Isometry3d T_W_C = DeskSubmaps::desk(1.5 + frame / 30.0);
    const LoopDetector::Step step = detector.step(test::renderRoom(T_W_C, desks.camera), desks.camera, T_W_C,
                                                  desks.active, desks.closed, desks.mapping.places(),
                                                  desks.keyframe_submaps);
    handed.push_back(T_W_C);
    if (!step.searched) continue;
    ++searched;
    EXPECT_EQ(step.submap, 0);
    EXPECT_EQ(step.frame_submap, 2);
    // The frame it looked at is an earlier one, handed over while no search step ran.
    const auto earlier = std::find_if(handed.begin(), handed.end() - 1,
                                      [&](const Eigen::Isometry3d& T) { return T.isApprox(step.T_W_C); });
    EXPECT_NE(earlier, handed.end() - 1) << "frame " << frame << ": a step on a frame not handed over before";
    if (step.match) found = step;
  }
  if (!found) {
    const LoopDetector::Step last = detector.finish();
    if (last.match) found = last;
  }
  ASSERT_TRUE(found) << "the camera back on the mapped path was not found (" << searched << " frames searched)";
  EXPECT_EQ(found->match->submap, 0);
  // Submap 0's frame is the one the camera was tracked in: the match is that frame's pose.
  const Eigen::Isometry3d error = found->T_W_C.inverse() * found->match->T_S_C;
  EXPECT_LT(error.translation().norm(), 0.01);
  EXPECT_LT(rotationAngle(error), 0.01);
  detector.reset();
  EXPECT_FALSE(detector.finish().searched) << "reset() ends the search, and drops its running step";
  EXPECT_TRUE(desks.closed.swapped(0)) << "what the search read back was a copy; the submap stays in the file";
  EXPECT_EQ(desks.closed.memoryBytes(), desks.closed.inMemory(1)->memoryBytes()) << "the search let go of its copy";
}

TEST(LoopDetector, RefusesAPlaceFurtherFromTheGraphsGuessThanTheDriftCanBe) {
  // The graph puts submap 0 1 m from where the camera's path really lies in it: its keyframes are
  // within LoopSearchRadius of the camera, so it is searched, and the relocaliser finds the camera
  // from them; found 1 m from the graph's guess, the place is a loop only if max_drift_m reaches it.
  for (const double max_drift_m : {0.5, 2.0}) {
    DeskSubmaps desks;
    ASSERT_FALSE(desks.keyframe_submaps.empty());
    desks.closed.place(0).T_map_W.translation() = Eigen::Vector3d(1.0, 0.0, 0.0);
    LoopClosureConfig loops;
    loops.check_interval_frames = 1;
    loops.max_drift_m = max_drift_m;
    LoopDetector detector(loops, desks.config.relocaliser, desks.config.tracker, desks.config.places);
    std::optional<LoopDetector::Step> ended;  // the first search that ended: a match or why not
    for (int frame = 0; frame < 90 && !ended; ++frame) {
      const Eigen::Isometry3d T_W_C = DeskSubmaps::desk(1.5 + frame / 30.0);
      const LoopDetector::Step step = detector.step(test::renderRoom(T_W_C, desks.camera), desks.camera, T_W_C,
                                                    desks.active, desks.closed, desks.mapping.places(),
                                                    desks.keyframe_submaps);
      if (step.searched && (step.match || !step.message.empty())) ended = step;
    }
    if (!ended) ended = detector.finish();
    ASSERT_TRUE(ended && ended->searched) << "max_drift_m " << max_drift_m << ": no search ended";
    if (max_drift_m < 1.0) {
      EXPECT_FALSE(ended->match) << "a place 1 m from the graph's guess was taken with max_drift_m " << max_drift_m;
      EXPECT_NE(ended->message.find("beyond LoopMaxDrift (0.5 m)"), std::string::npos)
          << "named as the user types it: " << ended->message;
    } else {
      ASSERT_TRUE(ended->match) << "max_drift_m " << max_drift_m << ": " << ended->message;
      const Eigen::Isometry3d error = ended->T_W_C.inverse() * ended->match->T_S_C;
      EXPECT_LT(error.translation().norm(), 0.01);
    }
  }
}

TEST(LoopClosure, ParametersRefuseLoopsWithoutSubmapsByName) {
  Settings settings = preset("default");
  setParameterFromText(&settings, "SubmapSize", "0");
  setParameterFromText(&settings, "LoopClosure", "true");
  const std::vector<std::string> errors = settings.validate();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("LoopClosure=true needs SubmapSize > 0"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("SubmapSize=0"), std::string::npos) << errors[0];
  setParameterFromText(&settings, "SubmapSize", "2");
  EXPECT_TRUE(settings.validate().empty());

  Settings unused = preset("default");
  setParameterFromText(&unused, "LoopClosure", "false");
  setParameterFromText(&unused, "LoopSearchRadius", "3");
  const std::vector<std::string> notes = unused.withoutEffect({"LoopClosure", "LoopSearchRadius"});
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("LoopSearchRadius=3 has no effect without LoopClosure=true"), std::string::npos) << notes[0];
  EXPECT_THROW(setParameterFromText(&unused, "LoopSearchRadius", "0"), std::invalid_argument);
  EXPECT_THROW(setParameterFromText(&unused, "LoopCheckFrames", "0"), std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
