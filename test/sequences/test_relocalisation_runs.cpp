// Finding the camera again in whole runs of the pipeline: after a kidnap, and in a second session
// in a saved map (found by itself, or told where it is).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <optional>
#include <vector>

#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/relocalisation/view_agreement.h"
#include "sdf_tracker/sim/relocalisation_cases.h"
#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

/// Frames of the loop around the desk (12 s per lap) at 15 Hz, from t0_s to t1_s.
std::vector<double> loopTimes(double t0_s, double t1_s) {
  std::vector<double> times;
  for (double t = t0_s; t < t1_s; t += 1.0 / 15.0) times.push_back(t);
  return times;
}
Eigen::Isometry3d loopPose(double t_s) { return synthetic::cameraPose(synthetic::Motion::kLoop, t_s, 12.0); }
DepthImage loopView(double t_s) {
  synthetic::NoiseModel no_noise;
  no_noise.enabled = false;
  return synthetic::Scene::forMotion(synthetic::Motion::kLoop).render(test::testCamera(), loopPose(t_s), no_noise, 0);
}

/// After a kidnap or in a second session: the frames until the camera is found, each fused frame's
/// error, and the error of the frames after it was found.
struct Recovery {
  int frames_until_found = -1;
  double worst_fused_error_m = 0.0;
  double worst_error_after_m = 0.0;
};
Recovery recover(SdfPipeline* pipeline, const std::vector<double>& times, const Eigen::Isometry3d& T_map_world) {
  Recovery r;
  for (size_t n = 0; n < times.size(); ++n) {
    const FrameReport report = pipeline->processFrame(loopView(times[n]), test::testCamera(), times[n]);
    const double error = (pipeline->pose().translation() - (T_map_world * loopPose(times[n])).translation()).norm();
    if (report.fused) r.worst_fused_error_m = std::max(r.worst_fused_error_m, error);
    if (r.frames_until_found < 0 && report.track.tracked()) r.frames_until_found = static_cast<int>(n);
    if (r.frames_until_found >= 0) r.worst_error_after_m = std::max(r.worst_error_after_m, error);
    EXPECT_TRUE(report.fused || !report.track.tracked() || report.track.status == TrackStatus::kDegenerate);
    if (r.frames_until_found < 0) {
      EXPECT_TRUE(report.track.status == TrackStatus::kRelocalising || report.track.status == TrackStatus::kAmbiguous)
          << "frame " << n << ": " << report.track.message;
      EXPECT_FALSE(report.fused);
    }
  }
  return r;
}

TEST(PipelineRelocalisation, AKidnappedCameraIsFoundAgainAndNothingIsFusedBeforeItIs) {
  SdfPipeline pipeline(preset("default").pipeline);
  ASSERT_TRUE(pipeline.config().relocalise);
  for (double t : loopTimes(0.0, 4.0)) pipeline.processFrame(loopView(t), test::testCamera(), t);
  ASSERT_EQ(pipeline.consecutiveFailures(), 0);
  const Eigen::Isometry3d T_map_world = pipeline.pose() * loopPose(4.0 - 1.0 / 15.0).inverse();
  // Carried round the desk out of view: it comes back 150 degrees round the loop from where the
  // tracker last saw it, looking at the desk from near where the first lap began.
  const Recovery r = recover(&pipeline, loopTimes(11.0, 13.0), T_map_world);
  ASSERT_GE(r.frames_until_found, 0) << "never found";
  EXPECT_LE(r.frames_until_found, 12);
  EXPECT_LT(r.worst_fused_error_m, 0.02);
  EXPECT_LT(r.worst_error_after_m, 0.02);
}

TEST(PipelineRelocalisation, ASecondSessionInASavedMapFindsItsPlaceOrIsToldIt) {
  const std::string path = test::scratchDirectory("second_session") + "/map.sdfmap";
  Eigen::Isometry3d T_map_world;
  {
    SdfPipeline first(preset("default").pipeline);
    for (double t : loopTimes(0.0, 4.0)) first.processFrame(loopView(t), test::testCamera(), t);
    T_map_world = first.pose() * loopPose(4.0 - 1.0 / 15.0).inverse();
    io::writeMap(path, *first.copyWholeMap(), first.placesInMapFrame().get());
  }
  auto session = [&](const std::optional<Eigen::Isometry3d>& told, double t0) {
    auto pipeline = std::make_unique<SdfPipeline>(preset("default").pipeline);
    std::unique_ptr<PlaceMemory> places;
    std::unique_ptr<TsdfMap> map = io::readMap(path, false, &places);  // before places is handed on
    pipeline->setMap(std::move(map), std::move(places));
    EXPECT_FALSE(pipeline->places().empty());
    EXPECT_TRUE(pipeline->relocalising()) << "a loaded map does not say where the camera is";
    if (told) pipeline->relocalise(*told);
    return std::make_pair(std::move(pipeline), t0);
  };
  {
    auto [pipeline, t0] = session(std::nullopt, 1.5);
    const Recovery r = recover(pipeline.get(), loopTimes(t0, t0 + 1.5), T_map_world);
    ASSERT_GE(r.frames_until_found, 0) << "never found";
    EXPECT_LE(r.frames_until_found, 12);
    EXPECT_LT(r.worst_fused_error_m, 0.02);
  }
  {
    // Told where it is, a little off: verified, then found at once.
    auto [pipeline, t0] = session(test::perturbed(T_map_world * loopPose(2.5), 0.1, 0.1), 2.5);
    const Recovery r = recover(pipeline.get(), loopTimes(t0, t0 + 0.5), T_map_world);
    EXPECT_EQ(r.frames_until_found, pipeline->config().relocaliser.confirm_frames - 1);
    EXPECT_LT(r.worst_fused_error_m, 0.02);
  }
  SdfPipeline off(preset("paper").pipeline);
  EXPECT_THROW(off.relocalise(), std::logic_error) << "the paper's preset has no relocaliser";
}

/// A second session's pipeline in the map and place memory `first` built (saved and loaded, as a
/// user's second session is).
std::unique_ptr<SdfPipeline> secondSession(const SdfPipeline& first, const std::string& name) {
  const std::string path = test::scratchDirectory(name) + "/map.sdfmap";
  io::writeMap(path, *first.copyWholeMap(), first.placesInMapFrame().get());
  auto pipeline = std::make_unique<SdfPipeline>(preset("default").pipeline);
  std::unique_ptr<PlaceMemory> places;
  std::unique_ptr<TsdfMap> map = io::readMap(path, false, &places);
  pipeline->setMap(std::move(map), std::move(places));
  return pipeline;
}

/// A relocalisation case's first session fused at its true poses (the map is in the world's
/// frame), and its second session run in that map; what the second session did.
struct CaseRun {
  int frames = 0;
  int frames_until_found = -1;
  int ambiguous_frames = 0;
  int fused_frames = 0;
  double worst_error_after_m = 0.0;  ///< of the frames from the one found on
  ViewAgreement first_view_at_truth;
};
CaseRun runCase(const synthetic::RelocalisationCase& c) {
  synthetic::NoiseModel no_noise;
  no_noise.enabled = false;
  const PinholeCamera camera = test::testCamera();
  SdfPipeline first(preset("default").pipeline);
  for (size_t i = 0; i < c.mapping.size(); ++i) {
    first.processFrameAtPose(c.mappingView(i, camera, no_noise, 0), camera, c.mapping[i].T_W_C, c.mapping[i].timestamp_s);
  }
  std::unique_ptr<SdfPipeline> session = secondSession(first, c.name);
  CaseRun run;
  run.frames = static_cast<int>(c.session.size());
  run.first_view_at_truth = measureViewAgreement(c.sessionView(0, camera, no_noise, 0), camera, session->map(),
                                                 c.session.front().T_W_C, 4);
  for (size_t i = 0; i < c.session.size(); ++i) {
    const FrameReport report =
        session->processFrame(c.sessionView(i, camera, no_noise, 0), camera, c.session[i].timestamp_s);
    const std::string frame = c.name + " frame " + std::to_string(i) + ": " + report.track.message;
    if (report.fused) ++run.fused_frames;
    if (run.frames_until_found < 0 && report.track.tracked()) run.frames_until_found = static_cast<int>(i);
    if (run.frames_until_found >= 0) {
      const double error = (session->pose().translation() - c.session[i].T_W_C.translation()).norm();
      run.worst_error_after_m = std::max(run.worst_error_after_m, error);
      EXPECT_TRUE(report.fused || report.track.status == TrackStatus::kDegenerate) << frame;
    } else {
      EXPECT_TRUE(report.track.status == TrackStatus::kRelocalising || report.track.status == TrackStatus::kAmbiguous)
          << frame;
      EXPECT_FALSE(report.fused) << frame;
    }
    if (report.track.status == TrackStatus::kAmbiguous) {
      ++run.ambiguous_frames;
      EXPECT_GE(report.relocalisation.places_fitting, 2) << frame;
      EXPECT_NE(report.track.message.find(std::to_string(report.relocalisation.places_fitting) + " places fit"),
                std::string::npos)
          << frame;
    }
  }
  std::cout << "[ figures  ] relocalisation case " << c.name << ": first view " << std::lround(100 * run.first_view_at_truth.mappedShare())
            << " % mapped; found on frame " << run.frames_until_found << " (-1: never) of " << run.frames << ", "
            << run.ambiguous_frames << " frames ambiguous, worst error once found " << 1000 * run.worst_error_after_m
            << " mm\n";
  return run;
}

TEST(PipelineRelocalisation, ASecondSessionWhoseFirstViewIsHalfNewIsFoundAtOnce) {
  const CaseRun run = runCase(synthetic::relocalisationCase("half-new"));
  ASSERT_LT(run.first_view_at_truth.mappedShare(), 0.6) << "the case is a view with much of it new";
  EXPECT_LT(run.first_view_at_truth.contradictionShare(), 0.005);
  ASSERT_GE(run.frames_until_found, 0) << "never found";
  EXPECT_LE(run.frames_until_found, preset("default").pipeline.relocaliser.confirm_frames);
  EXPECT_LT(run.worst_error_after_m, 0.02);
}

TEST(PipelineRelocalisation, InTwoIdenticalRoomsNothingIsAcceptedAndTheStatusSaysAmbiguous) {
  const CaseRun run = runCase(synthetic::relocalisationCase("two-rooms"));
  EXPECT_EQ(run.frames_until_found, -1) << "a place was accepted in one of two identical rooms";
  EXPECT_EQ(run.fused_frames, 0);
  EXPECT_GE(run.ambiguous_frames, 2 * run.frames / 3) << "of " << run.frames << " frames, the status says why";
}

TEST(PipelineRelocalisation, InARoomAHalfTurnMapsOntoItselfNothingIsAcceptedAndTheStatusSaysAmbiguous) {
  const CaseRun run = runCase(synthetic::relocalisationCase("symmetric-room"));
  EXPECT_EQ(run.frames_until_found, -1) << "a place was accepted in a room whose half turn looks the same";
  EXPECT_EQ(run.fused_frames, 0);
  EXPECT_GE(run.ambiguous_frames, 2 * run.frames / 3) << "of " << run.frames << " frames, the status says why";
}

TEST(PipelineRelocalisation, OfTwoIdenticalDesksTheOneWhoseSurroundingsFitIsFound) {
  const CaseRun run = runCase(synthetic::relocalisationCase("two-desks"));
  ASSERT_GE(run.frames_until_found, 0) << "never found";
  EXPECT_LE(run.frames_until_found, 10);
  // The first desk is 2.5 m away: any frame fused there, or accepted there, is far beyond this.
  EXPECT_LT(run.worst_error_after_m, 0.02);
}

}  // namespace
}  // namespace sdf_tracker
