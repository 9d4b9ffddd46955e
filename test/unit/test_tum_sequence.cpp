// The TUM folder reader: what a folder states about its camera (intrinsics.txt, a TUM download's
// name, nothing), and that a lens distortion comes only from what the data states.
#include <gtest/gtest.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/sim/relocalisation_cases.h"
#include "sdf_tracker/sim/synthetic.h"
#include "test_helpers.h"

namespace sdf_tracker {
namespace {

using test::writeFile;

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

TEST(TumSequence, AFolderNamedLikeATumDownloadGetsThatCamerasCalibration) {
  synthetic::SequenceSpec spec;
  spec.frames = 1;
  for (const std::string camera : {"freiburg1", "freiburg2", "freiburg3"}) {
    const std::string dir = test::scratchDirectory("rgbd_dataset_" + camera + "_desk");
    synthetic::writeSequence(dir, spec);
    std::remove((dir + "/intrinsics.txt").c_str());  // as TUM's downloads
    for (const std::string& path : {dir, dir + "/"}) {
      const TumSequence sequence = TumSequence::open(path);
      EXPECT_EQ(sequence.camera(), *PinholeCamera::tumCamera(camera)) << path << ": intrinsics and distortion";
      EXPECT_EQ(sequence.intrinsicsSource(), "TUM " + camera + "'s published calibration, from the folder's name");
      EXPECT_EQ(sequence.distortionSource(), sequence.intrinsicsSource());
      EXPECT_EQ(sequence.distortionHint(), "") << "the folder states the camera";
    }
  }
}

TEST(TumSequence, LensDistortionIsWhatTheDataStatesNeverInferredFromTheIntrinsics) {
  const std::string dir = test::scratchDirectory("seq_distortion");
  synthetic::SequenceSpec spec;
  spec.frames = 1;
  synthetic::writeSequence(dir, spec);  // 640x480 with TUM freiburg1's intrinsics, written with 0 distortion
  EXPECT_TRUE(TumSequence::open(dir).camera().distortion.isZero()) << "the file's explicit zeros hold";
  EXPECT_EQ(TumSequence::open(dir).distortionSource(), "intrinsics.txt");
  EXPECT_EQ(TumSequence::open(dir).distortionHint(), "") << "stated: nothing to suggest";

  // TUM's intrinsics, no distortion columns, stamped as TUM's recordings are: still none, and said.
  writeFile(dir + "/intrinsics.txt", "# fx fy cx cy width height depth_factor\n517.3 516.5 318.6 255.3 640 480 5000\n");
  const std::string first = TumSequence::open(dir).depthPath(0).substr(dir.size() + 1);
  writeFile(dir + "/depth.txt", "1305031102.160407 " + first + "\n");
  const TumSequence unstated = TumSequence::open(dir);
  EXPECT_TRUE(unstated.camera().distortion.isZero()) << "intrinsics that match are not a calibration";
  EXPECT_EQ(unstated.distortionSource(), "none stated");
  EXPECT_EQ(unstated.distortionHint(),
            "these are TUM freiburg1's intrinsics, but no lens distortion is stated, so none is removed; if the "
            "images are TUM's, state the distortion TUM publishes for them: 0.2624 -0.9531 -0.0054 0.0026 1.1633 as "
            "intrinsics.txt's last five columns, or sdf_tracker_offline --distortion "
            "0.2624,-0.9531,-0.0054,0.0026,1.1633");
  std::remove((dir + "/intrinsics.txt").c_str());
  EXPECT_TRUE(TumSequence::open(dir).camera().distortion.isZero()) << "the freiburg1 defaults: intrinsics only";
  EXPECT_NE(TumSequence::open(dir).distortionHint(), "");

  writeFile(dir + "/intrinsics.txt", "585 585 320 240 640 480 1000\n");
  EXPECT_TRUE(TumSequence::open(dir).camera().distortion.isZero()) << "another camera: none";
  EXPECT_EQ(TumSequence::open(dir).distortionSource(), "none stated");
  EXPECT_EQ(TumSequence::open(dir).distortionHint(), "") << "not a TUM camera's intrinsics";
  writeFile(dir + "/intrinsics.txt", "585 585 320 240 640 480 1000 0.1 -0.2 0.001 0.002 0.3\n");
  EXPECT_DOUBLE_EQ(TumSequence::open(dir).camera().distortion.p2, 0.002);
  SequenceOptions options;
  options.distortion = LensDistortion();
  EXPECT_TRUE(TumSequence::open(dir, options).camera().distortion.isZero()) << "the options win";

  for (const char* bad : {"585 585 320 240 640 480 1000 0.1\n", "585 585 320 240 640 480 1000 0.1 0 0 0 0 7\n",
                          "585 585 320 240 640 480 1000 0.1 0 0 0 nan\n"}) {
    writeFile(dir + "/intrinsics.txt", bad);
    try {
      TumSequence::open(dir);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("intrinsics"), std::string::npos) << e.what();
    }
  }
}

TEST(RelocalisationCase, IsWrittenAsTwoSessionsThatReadBackWithTheWholeCasesGroundTruth) {
  const synthetic::RelocalisationCase c = synthetic::relocalisationCase("half-new");
  synthetic::NoiseModel no_noise;
  no_noise.enabled = false;
  const PinholeCamera camera = PinholeCamera::tumFreiburg1().scaledTo(160, 120);
  const std::string dir = test::scratchDirectory("relocalisation_case");
  synthetic::writeRelocalisationCase(dir, c, camera, no_noise, 1);
  const TumSequence mapping = TumSequence::open(dir + "/mapping");
  const TumSequence session = TumSequence::open(dir + "/session");
  ASSERT_EQ(mapping.size(), c.mapping.size());
  ASSERT_EQ(session.size(), c.session.size());
  EXPECT_GT(session.timestamp(0), mapping.timestamp(mapping.size() - 1)) << "the second session comes later";
  for (const TumSequence* part : {&mapping, &session}) {
    EXPECT_EQ(part->groundTruth().size(), c.mapping.size() + c.session.size());
    EXPECT_EQ(part->camera().width, 160);
  }
  // The first session saw the left half only: its right half holds nothing, the second's does.
  const DepthImage first = mapping.depth(0), second = session.depth(0);
  int right_first = 0, right_second = 0;
  for (int v = 0; v < camera.height; ++v) {
    for (int u = camera.width / 2; u < camera.width; ++u) {
      right_first += first.at(u, v) > 0.0f;
      right_second += second.at(u, v) > 0.0f;
    }
  }
  EXPECT_EQ(right_first, 0);
  EXPECT_GT(right_second, camera.width * camera.height / 4);
  EXPECT_THROW(synthetic::relocalisationCase("three-rooms"), std::invalid_argument);
}

}  // namespace
}  // namespace sdf_tracker
