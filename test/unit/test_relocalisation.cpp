// Finding the camera again: the place descriptor, the place memory, the wide-basin field, and the
// verification of a pose by what the map has observed, the relocaliser's candidates and their confirmation (whole runs: test/sequences/test_relocalisation_runs.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/places/place_memory.h"
#include "sdf_tracker/relocalisation/coarse_field.h"
#include "sdf_tracker/relocalisation/relocaliser.h"
#include "sdf_tracker/relocalisation/view_agreement.h"
#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/sim/synthetic.h"
#include "sdf_tracker/util/se3.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

Eigen::Isometry3d deskPose(double t_s) { return synthetic::cameraPose(synthetic::Motion::kDesk, t_s, 10.0); }

/// The same pose turned by `angle_rad` about the camera's vertical axis.
Eigen::Isometry3d turned(const Eigen::Isometry3d& T, double angle_rad) {
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(angle_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T * turn;
}

TEST(PlaceDescriptor, NearbyViewsAnswerMostFernsAlikeAndOtherViewsDoNot) {
  const PlaceEncoder encoder{PlaceDescriptorConfig{}};
  const Eigen::Isometry3d T = deskPose(0.0);
  const PlaceCode code = encoder.encode(test::renderRoom(T));
  ASSERT_EQ(code.size(), 500u);
  EXPECT_EQ(PlaceEncoder::dissimilarity(code, code), 0.0);
  const double near = PlaceEncoder::dissimilarity(code, encoder.encode(test::renderRoom(test::perturbed(T, 0.03, 0.03))));
  const double away = PlaceEncoder::dissimilarity(code, encoder.encode(test::renderRoom(turned(T, M_PI))));
  EXPECT_LT(near, 0.3);
  EXPECT_GT(away, 0.45);
  EXPECT_GT(away, 2.0 * near);
  EXPECT_THROW(PlaceEncoder::dissimilarity(code, PlaceCode(10, 0)), std::invalid_argument);
}

TEST(PlaceDescriptor, TheTestsFollowFromTheSeedAndCellsAverageTheirMeasuredPixels) {
  PlaceDescriptorConfig config;
  const DepthImage view = test::renderRoom(deskPose(1.0));
  EXPECT_EQ(PlaceEncoder(config).encode(view), PlaceEncoder(config).encode(view));
  PlaceDescriptorConfig other = config;
  other.seed = 2;
  EXPECT_NE(PlaceEncoder(other).encode(view), PlaceEncoder(config).encode(view));

  // 640x480 on 40x30 cells: 16x16 pixels each.
  DepthImage image(640, 480, 2.0f);
  for (int v = 0; v < 16; ++v) {
    for (int u = 0; u < 16; ++u) image.at(u, v) = (u + v) % 4 == 0 ? 2.0f : std::nanf("");  // a quarter measured ...
    for (int u = 32; u < 48; ++u) image.at(u, v) = u == 32 ? 2.0f : 0.0f;                   // ... an eighth
    for (int u = 16; u < 32; ++u) image.at(u, v) = u < 24 ? 1.0f : 3.0f;
  }
  const std::vector<float> cells = PlaceEncoder(config).cellDepths(image);
  ASSERT_EQ(cells.size(), 1200u);
  EXPECT_FLOAT_EQ(cells[0], 2.0f);
  EXPECT_FLOAT_EQ(cells[1], 2.0f) << "the mean of 1 m and 3 m halves";
  EXPECT_EQ(cells[2], 0.0f) << "fewer than a quarter of its pixels measured: a hole";
  EXPECT_FLOAT_EQ(cells[3], 2.0f);

  config.fern_count = 0;
  config.tests_per_fern = 9;
  try {
    PlaceEncoder{config};
    FAIL() << "an invalid descriptor";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fern_count"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("tests_per_fern must be in [1, 8] (got 9)"), std::string::npos) << e.what();
  }
}

TEST(PlaceMemory, KeyframesFollowThePathNotTheFramesAndStayBounded) {
  // The desk path's first 8 s at 5 Hz.
  std::vector<std::pair<Eigen::Isometry3d, DepthImage>> frames;
  for (int n = 0; n < 40; ++n) frames.emplace_back(deskPose(n / 5.0), test::renderRoom(deskPose(n / 5.0)));
  PlaceMemory places;
  for (int n = 0; n < 30; ++n) places.offer(frames[0].second, frames[0].first);
  EXPECT_EQ(places.keyframes().size(), 1u) << "a camera standing still is one place";
  for (const auto& [T, depth] : frames) places.offer(depth, T);
  const size_t count = places.keyframes().size();
  EXPECT_GT(count, 5u);
  EXPECT_LT(count, 35u) << "not every frame";
  for (size_t a = 0; a < count; ++a) {
    for (size_t b = a + 1; b < count; ++b) {
      const Eigen::Isometry3d offset = places.keyframes()[a].T_W_C.inverse() * places.keyframes()[b].T_W_C;
      const bool near = offset.translation().norm() < places.config().keyframe_spacing_m &&
                        rotationAngle(offset) < places.config().keyframe_spacing_rad;
      EXPECT_FALSE(near && PlaceEncoder::dissimilarity(places.keyframes()[a].code, places.keyframes()[b].code) <
                               places.config().min_novelty)
          << "keyframes " << a << " and " << b << " are the same place";
    }
  }
  // A view near a keyframe finds it (or one as near) first.
  const Eigen::Isometry3d query = test::perturbed(places.keyframes()[count / 2].T_W_C, 0.02, 0.02);
  const std::vector<PlaceMemory::Match> alike = places.mostAlike(places.encoder().encode(test::renderRoom(query)), 3);
  ASSERT_EQ(alike.size(), 3u);
  EXPECT_LE(alike[0].dissimilarity, alike[1].dissimilarity);
  EXPECT_LT((places.keyframes()[alike[0].keyframe].T_W_C.translation() - query.translation()).norm(), 0.15);
  EXPECT_EQ(places.bytesPerKeyframe(), sizeof(Keyframe) + 500u);

  PlaceMemoryConfig small;
  small.max_keyframes = 3;
  PlaceMemory bounded(small);
  for (const auto& [T, depth] : frames) bounded.offer(depth, T);
  EXPECT_EQ(bounded.keyframes().size(), 3u);
  EXPECT_THROW(bounded.add(places.keyframes()[0]), std::invalid_argument) << "full";
  EXPECT_THROW(places.add(Keyframe{Eigen::Isometry3d::Identity(), PlaceCode(7, 0)}), std::invalid_argument)
      << "a code of another descriptor";
}

/// A dense grid holding the plane z = 1 m (normal towards the camera at the origin).
TsdfVolume planeVolume() {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(64, 64, 64);
  config.voxel_size_m = 0.02;
  config.origin_W = Eigen::Vector3d(-0.64, -0.64, 0.36);
  config.positive_truncation_m = 0.1;
  TsdfVolume volume(config);
  for (int k = 0; k < 64; ++k) {
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        const float d = 1.0f - volume.position(i, j, k).z();
        if (std::fabs(d) < 0.1f) volume.setVoxel(i, j, k, Voxel{d, 1.0f});
      }
    }
  }
  return volume;
}

TEST(CoarseField, HoldsTheDistanceToTheNearestSurfaceUpToItsReach) {
  const TsdfVolume field = buildCoarseField(planeVolume(), 0.08, 0.6);
  EXPECT_NEAR(field.voxelSize(), 0.08, 1e-6);
  EXPECT_NEAR(field.positiveTruncation(), 0.6, 1e-6);
  float d = 0.0f;
  for (const float z : {0.55f, 0.7f, 0.85f, 1.2f, 1.45f}) {
    ASSERT_TRUE(field.sampleDistance(Eigen::Vector3f(0.1f, -0.2f, z), &d)) << z;
    EXPECT_NEAR(d, std::fabs(1.0f - z), 0.03f) << "at z = " << z << " (cell " << field.voxelSize() << ", origin "
                                                << field.position(0, 0, 0).transpose() << ")";
  }
  ASSERT_TRUE(field.sampleDistance(Eigen::Vector3f(0.0f, 0.0f, 1.0f), &d));
  EXPECT_LT(d, 0.04f) << "on the surface, within half a cell";
  EXPECT_THROW(buildCoarseField(TsdfVolume(planeVolume().config()), 0.08, 0.6), std::invalid_argument)
      << "an empty map has no surface to be near";
  EXPECT_THROW(buildCoarseField(planeVolume(), 0.08, 0.05), std::invalid_argument) << "a reach within a cell";
  // A lattice too fine for the bound grows its cell.
  const TsdfVolume bounded = buildCoarseField(planeVolume(), 0.01, 0.3, 20000);
  EXPECT_GT(bounded.voxelSize(), 0.01);
  EXPECT_LE(bounded.voxelCount(), 30000u);
}

/// A map on the default preset's lattice with `depth` fused from T_W_C.
std::unique_ptr<TsdfMap> mapOf(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C) {
  const PipelineConfig config = preset("default").pipeline;
  std::unique_ptr<TsdfMap> map = makeMap(config.volume);
  Integrator(config.integrator).integrate(depth, camera, T_W_C, map.get());
  return map;
}

TEST(ViewAgreement, ARightPoseWithHalfTheViewNewContradictsNothingAndAWrongOneDoes) {
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d truth = deskPose(0.0);
  const DepthImage view = test::renderRoom(truth);
  // The map saw only the left half of this view.
  const std::unique_ptr<TsdfMap> map = mapOf(synthetic::withoutRightHalf(view), camera, truth);
  const ViewAgreement right = measureViewAgreement(view, camera, *map, truth, 4);
  EXPECT_GT(right.points, 4000);
  EXPECT_NEAR(right.mappedShare(), 0.5, 0.1) << "the right half is new ground";
  EXPECT_GT(right.tightShare(), 0.95);
  EXPECT_LT(right.contradictionShare(), 0.002);
  // The same view 10 cm and 3 degrees off: its points leave the surfaces, into the free space
  // the map saw in front of them.
  const ViewAgreement wrong = measureViewAgreement(view, camera, *map, test::perturbed(truth, 0.1, 0.05), 4);
  EXPECT_GT(wrong.contradictionShare(), 0.1);
  EXPECT_THROW(measureViewAgreement(view, camera, *map, truth, 0), std::invalid_argument);
}

/// From the origin along +z: a wall 2.5 m ahead and, with `panel`, a panel 1 m ahead in front of
/// its left half.
DepthImage wallAndPanel(bool panel, const Eigen::Isometry3d& T_W_C) {
  synthetic::Scene scene;
  synthetic::Primitive wall;
  wall.centre_W = Eigen::Vector3d(0.0, 0.0, 2.6);
  wall.half_extent_m = Eigen::Vector3d(4.0, 4.0, 0.1);
  scene.add(wall);
  if (panel) {
    synthetic::Primitive near;
    near.centre_W = Eigen::Vector3d(-1.0, 0.0, 1.05);
    near.half_extent_m = Eigen::Vector3d(1.0, 2.0, 0.05);
    scene.add(near);
  }
  synthetic::NoiseModel no_noise;
  no_noise.enabled = false;
  return scene.render(test::testCamera(), T_W_C, no_noise, 0);
}

TEST(ViewAgreement, APoseThatFitsOneSurfaceButLooksThroughOrPastAnotherIsContradicted) {
  const PinholeCamera camera = test::testCamera();
  const Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  const std::unique_ptr<TsdfMap> map = mapOf(wallAndPanel(true, origin), camera, origin);
  const ViewAgreement same = measureViewAgreement(wallAndPanel(true, origin), camera, *map, origin, 4);
  EXPECT_GT(same.mappedShare(), 0.95);
  EXPECT_LT(same.contradictionShare(), 0.02) << "rays grazing the panel's edge, at most";
  // A view of the wall alone placed here: the wall's right half fits, the left half is seen
  // through the panel.
  const ViewAgreement through = measureViewAgreement(wallAndPanel(false, origin), camera, *map, origin, 4);
  EXPECT_GT(through.contradictionShare(), 0.3);
  // The same view from 15 cm further on, placed here: the wall's points lie in the free space the
  // map saw in front of it.
  Eigen::Isometry3d ahead = Eigen::Isometry3d::Identity();
  ahead.translation() = Eigen::Vector3d(0.0, 0.0, 0.15);
  const ViewAgreement short_of = measureViewAgreement(wallAndPanel(false, ahead), camera, *map, origin, 4);
  EXPECT_GT(short_of.in_free_space, short_of.points / 4);
  EXPECT_GT(short_of.contradictionShare(), 0.6);
}

/// The room fused along the desk path's first `seconds` (at 6 Hz), on the default preset's
/// lattice, with the place memory the pipeline builds.
struct MappedRoom {
  explicit MappedRoom(double seconds) : pipeline(preset("default").pipeline) {
    for (double t = 0.0; t < seconds; t += 1.0 / 6.0) {
      const FrameReport report = pipeline.processFrameAtPose(test::renderRoom(deskPose(t)), camera, deskPose(t), t);
      EXPECT_TRUE(report.fused);
    }
  }
  PinholeCamera camera = test::testCamera();
  SdfPipeline pipeline;
};

TEST(Relocaliser, FindsTheCameraFromAKeyframeAwayConfirmsItAndWritesNothing) {
  const MappedRoom room(3.0);
  const SdfPipeline& pipeline = room.pipeline;
  ASSERT_GT(pipeline.places().keyframes().size(), 3u);
  const double weight_before = test::totalWeight(pipeline.map());
  Relocaliser relocaliser(pipeline.config().relocaliser, pipeline.config().tracker);
  relocaliser.begin(pipeline.map());
  // Where the path was at 1.5 s, but 0.2 m and 9 degrees off it (turned towards walls never seen:
  // an eighth of the view is unmapped), and moving on slowly.
  Relocaliser::Step step;
  Eigen::Isometry3d truth;
  for (int frame = 0; frame < 10 && step.outcome != Relocaliser::Outcome::kAccepted; ++frame) {
    truth = test::perturbed(deskPose(1.5 + frame / 30.0), 0.2, 0.15);
    step = relocaliser.step(test::renderRoom(truth), room.camera, pipeline.map(), pipeline.places(), {});
  }
  ASSERT_EQ(step.outcome, Relocaliser::Outcome::kAccepted) << step.message;
  EXPECT_EQ(step.confirmed, pipeline.config().relocaliser.confirm_frames);
  EXPECT_LE(relocaliser.framesSpent(), 6);
  const Eigen::Isometry3d error = truth.inverse() * step.T_W_C;
  EXPECT_LT(error.translation().norm(), 0.01);
  EXPECT_LT(rotationAngle(error), 0.01);
  EXPECT_FALSE(relocaliser.searching()) << "an accepted candidate ends the search";
  EXPECT_EQ(test::totalWeight(pipeline.map()), weight_before) << "the search never writes into the map";
}

TEST(Relocaliser, FollowsAPlaceByTheCameraMotionItIsGiven) {
  // Frames far apart, as a loop search in the background takes them (those it has time for):
  // between two the camera turns 8 degrees and moves 6 cm, as the tracker measured. Given that
  // motion, the place found on the first frame is followed over the next ones and confirmed;
  // tracked from where it was, it is lost each frame and found anew, and never confirmed.
  const MappedRoom room(3.0);
  const SdfPipeline& pipeline = room.pipeline;
  const int confirm_frames = pipeline.config().relocaliser.confirm_frames;
  Eigen::Isometry3d motion = turned(Eigen::Isometry3d::Identity(), 8.0 * M_PI / 180.0);
  motion.translation() = Eigen::Vector3d(0.06, 0.0, 0.0);
  for (const bool given : {true, false}) {
    Relocaliser relocaliser(pipeline.config().relocaliser, pipeline.config().tracker);
    relocaliser.begin(pipeline.map());
    Relocaliser::Step step;
    Eigen::Isometry3d truth = deskPose(1.5);
    for (int frame = 0; frame < confirm_frames; ++frame) {
      if (frame > 0) truth = truth * motion;
      step = relocaliser.step(test::renderRoom(truth), room.camera, pipeline.map(), pipeline.places(), {},
                              given ? motion : Eigen::Isometry3d::Identity());
    }
    if (given) {
      ASSERT_EQ(step.outcome, Relocaliser::Outcome::kAccepted) << step.message;
      const Eigen::Isometry3d error = truth.inverse() * step.T_W_C;
      EXPECT_LT(error.translation().norm(), 0.01);
      EXPECT_LT(rotationAngle(error), 0.01);
    } else {
      EXPECT_NE(step.outcome, Relocaliser::Outcome::kAccepted)
          << "followed without the motion: the test shows nothing (" << step.confirmed << " confirmed)";
    }
  }
}

TEST(Relocaliser, AViewOfNoMappedPlaceOrOfOneWallIsNeverAccepted) {
  const MappedRoom room(2.0);
  const SdfPipeline& pipeline = room.pipeline;
  Relocaliser relocaliser(pipeline.config().relocaliser, pipeline.config().tracker);
  relocaliser.begin(pipeline.map());
  int candidates = 0;
  for (int frame = 0; frame < 6; ++frame) {
    // Turned away from everything mapped (the wall behind the camera was never seen) ...
    const Eigen::Isometry3d behind = turned(deskPose(frame / 30.0), M_PI);
    Relocaliser::Step step = relocaliser.step(test::renderRoom(behind), room.camera, pipeline.map(), pipeline.places(),
                                              {pipeline.pose()});
    EXPECT_EQ(step.outcome, Relocaliser::Outcome::kNotFound) << "frame " << frame;
    EXPECT_NE(step.message.find("no candidate fits"), std::string::npos) << step.message;
    candidates += step.candidates_tried;
    // ... and a flat wall, which fixes three directions of six: nothing to confirm a place by.
    step = relocaliser.step(DepthImage(room.camera.width, room.camera.height, 1.6f), room.camera, pipeline.map(),
                            pipeline.places(), {pipeline.pose()});
    EXPECT_EQ(step.outcome, Relocaliser::Outcome::kNotFound) << "frame " << frame;
  }
  EXPECT_EQ(relocaliser.candidatesTried(), 2 * candidates);
  EXPECT_GE(candidates, 6 * (1 + pipeline.config().relocaliser.candidates_per_frame))
      << "the held pose and a full turn of keyframes each frame";
}

}  // namespace
}  // namespace sdf_tracker
