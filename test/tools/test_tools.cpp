// The command-line tools' contract with their user: exit codes, refused options, valid JSON, and
// an output folder that never holds half-written or mixed results.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/cli/odometry_track.h"
#include "sdf_tracker/cli/option_values.h"
#include "sdf_tracker/cli/output_folder.h"
#include "sdf_tracker/cli/report.h"
#include "sdf_tracker/cli/tracker_alone.h"
#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/io/sdfmap_file.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/sim/synthetic.h"
#include "run_command.h"
#include "test_helpers.h"

namespace sdf_tracker::tools {
namespace {

namespace fs = std::filesystem;

using ToolRun = test::CommandResult;

/// Runs the offline runner with `arguments` (already quoted for the shell).
ToolRun offline(const std::string& arguments) {
  return test::runCommand(std::string(SDF_TRACKER_OFFLINE) + " --quiet " + arguments);
}

/// Runs the offline runner on `sequence` with `arguments` and expects it to refuse them: exit
/// code 1, and each of `said` in what it printed.
void expectRefused(const std::string& sequence, const std::string& arguments, std::initializer_list<std::string> said) {
  const ToolRun run = offline("--sequence " + sequence + " --output " + test::scratchDirectory("refused") + " " + arguments);
  EXPECT_EQ(run.exit_code, 1) << arguments << ":\n" << run.output;
  for (const std::string& text : said) EXPECT_NE(run.output.find(text), std::string::npos) << run.output;
}

/// A short synthetic QVGA sequence with ground truth.
std::string shortSequence(int frames) {
  const std::string dir = test::scratchDirectory("cli_sequence");
  synthetic::SequenceSpec spec;
  spec.frames = frames;
  spec.camera = test::testCamera();
  synthetic::writeSequence(dir, spec);
  return dir;
}

TEST(Json, StringsAreEscapedAndNonFiniteNumbersAreNull) {
  EXPECT_EQ(jsonString("a\tb\"c\\d\n"), "\"a\\u0009b\\\"c\\\\d\\u000a\"");
  EXPECT_EQ(jsonNumber(0.25), "0.25");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(jsonNumber(std::nan("")), "null");
}

TEST(CommandLine, WholeNumbersBeyondIntAreRefused) {
  const char* argv[] = {"tool", "--frames", "1e10"};
  const CommandLine args(3, const_cast<char**>(argv), {"frames"}, {});
  EXPECT_THROW(args.getInt("frames", 0), std::invalid_argument);
}

TEST(CommandLine, AnOptionGivenTwiceWithTwoValuesIsRefusedNotOneOfThemTaken) {
  // Issue 44: --initial-pose and --odometry given twice used one of the two without a word.
  const char* argv[] = {"tool", "--odometry", "a.txt", "--param", "A=1", "--odometry", "b.txt", "--param", "B=2"};
  const CommandLine args(9, const_cast<char**>(argv), {"odometry", "param"}, {});
  try {
    args.get("odometry");
    ADD_FAILURE() << "one of two values was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--odometry is given twice (\"a.txt\" and \"b.txt\"): give it once");
  }
  EXPECT_EQ(args.getAll("param"), (std::vector<std::string>{"A=1", "B=2"})) << "repeatable options repeat";
  const char* same[] = {"tool", "--odometry", "a.txt", "--odometry", "a.txt"};
  EXPECT_EQ(CommandLine(5, const_cast<char**>(same), {"odometry"}, {}).get("odometry"), "a.txt") << "no ambiguity";
}

TEST(OptionValues, EachValueIsReadWholeOrRefusedNamingTheOptionAndTheText) {
  using namespace sdf_tracker::tools;
  const Eigen::Isometry3d pose = parsePose("--initial-pose", "0.5,0,-1,0,0,0.7071068,0.7071068");
  EXPECT_TRUE(pose.translation().isApprox(Eigen::Vector3d(0.5, 0, -1)));
  EXPECT_NEAR(Eigen::AngleAxisd(pose.linear()).angle(), M_PI / 2, 1e-6);
  auto refusal = [](const auto& parse) -> std::string {
    try {
      parse();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_NE(refusal([] { parsePose("--initial-pose", "0,0,0,0,0,0,2"); }).find("--initial-pose 0,0,0,0,0,0,2: the quaternion"),
            std::string::npos);
  EXPECT_NE(refusal([] { parsePose("--initial-pose", "1,2,3"); }).find("expected TX,TY,TZ,QX,QY,QZ,QW"),
            std::string::npos);
  EXPECT_NE(refusal([] { parseBox("--volume-region", "0,0,0,-1,1,1"); }).find("--volume-region: expected"),
            std::string::npos) << "X0 < X1";
  EXPECT_NE(refusal([] { parseNumberList("--distortion", "0.1,x"); }).find("--distortion"), std::string::npos);
  // Issue 44: a trailing comma was taken where an empty field inside was refused.
  EXPECT_EQ(refusal([] { parsePose("--initial-pose", "0,0,0,0,0,0,1,"); }), "--initial-pose: expected a number, got \"\"");
  EXPECT_EQ(refusal([] { parsePose("--initial-pose", ",0,0,0,0,0,0,1"); }), "--initial-pose: expected a number, got \"\"");
  EXPECT_EQ(refusal([] { parsePose("--initial-pose", "0,0,,0,0,0,1"); }), "--initial-pose: expected a number, got \"\"");
  const sdf_tracker::PinholeCamera camera =
      parseIntrinsics("--intrinsics", "500,501,320,240,320,240", sdf_tracker::PinholeCamera::tumFreiburg1());
  EXPECT_EQ(camera.width, 320);
  EXPECT_DOUBLE_EQ(camera.fy, 501.0);
  EXPECT_NE(refusal([] { parseIntrinsics("--intrinsics", "500,501,320,240,3.5,240", {}); }).find("the width W"),
            std::string::npos);
}

TEST(OdometryTrack, PosesBetweenTheRecordedOnesAreInterpolatedAndGapsAndBadFilesAreNot) {
  const std::string path = ::testing::TempDir() + "/sdf_tracker_odometry.txt";
  Eigen::Isometry3d turned = Eigen::Isometry3d::Identity();
  turned.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  turned.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  sdf_tracker::io::writeTrajectory(path, {{1.0, Eigen::Isometry3d::Identity()}, {1.04, turned}, {2.0, turned}});
  const auto track = sdf_tracker::tools::OdometryTrack::read(path);
  const std::optional<Eigen::Isometry3d> middle = track.at(1.01);
  ASSERT_TRUE(middle);
  EXPECT_NEAR(middle->translation().x(), 0.025, 1e-6);
  EXPECT_NEAR(Eigen::AngleAxisd(middle->linear()).angle(), 0.05, 1e-6);
  EXPECT_TRUE(track.at(1.04)->isApprox(turned, 1e-6)) << "a recorded stamp gives its pose";
  EXPECT_FALSE(track.at(1.5)) << "0.96 s between two poses says nothing about the motion";
  EXPECT_FALSE(track.at(0.9)) << "before the first pose";
  sdf_tracker::io::writeTrajectory(path, {{1.0, turned}, {0.5, turned}});
  try {
    sdf_tracker::tools::OdometryTrack::read(path);
    ADD_FAILURE() << "stamps that go back were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--odometry " + path + ": the stamps do not increase"), std::string::npos)
        << e.what();
  }
}

TEST(OdometryTrack, AJumpIsSaidAndATrackThatMeetsNoFrameIsRefused) {
  // Issue 44: an odometry on another clock was used for no frame with exit 0 and no word, and a
  // jump of 100 m between two poses passed without a warning.
  const std::string path = ::testing::TempDir() + "/sdf_tracker_odometry_jump.txt";
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(100.0, 0.0, 0.0);
  sdf_tracker::io::writeTrajectory(path, {{1.0, Eigen::Isometry3d::Identity()}, {1.033, far}, {1.066, far}});
  const auto track = sdf_tracker::tools::OdometryTrack::read(path);
  EXPECT_EQ(track.jumps(), "--odometry " + path + ": 1 jump faster than 10 m/s, the largest 100 m in 0.033 s at "
                           "1.033 s (a reset or a glitch of the odometry? the tracker takes it as a prediction only)");
  EXPECT_EQ(track.requireCoverage({1.0, 1.05, 5.0}), 2u) << "frames outside the track have none";
  try {
    track.requireCoverage({1001.0, 1002.0});
    ADD_FAILURE() << "a track that meets no frame was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "--odometry " + path + ": its 3 poses (1.000 .. 1.066 s) give a pose for none of "
                                     "the 2 frames (1001.000 .. 1002.000 s): another clock, or gaps longer than "
                                     "0.100 s everywhere");
  }
  sdf_tracker::io::writeTrajectory(path, {{1.0, Eigen::Isometry3d::Identity()}, {1.033, Eigen::Isometry3d::Identity()}});
  EXPECT_EQ(sdf_tracker::tools::OdometryTrack::read(path).jumps(), "");
}

TEST(TrackerAlone, AnErrorCountsAsWithinTwoSigmaByTheCovarianceOfItsDirection) {
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  covariance.bottomRightCorner<3, 3>().diagonal() << 1e-6, 1e-6, 1e-2;  // 1 mm across, 10 cm along z
  EXPECT_NEAR(squaredMahalanobisOfPosition(Eigen::Vector3d(0.002, 0.0, 0.0), covariance), 4.0, 1e-9);
  EXPECT_NEAR(squaredMahalanobisOfPosition(Eigen::Vector3d(0.0, 0.0, 0.2), covariance), 4.0, 1e-9);
  EXPECT_TRUE(std::isinf(squaredMahalanobisOfPosition(Eigen::Vector3d(0.0, 0.0, 0.2),
                                                      Eigen::Matrix<double, 6, 6>::Zero())))
      << "no covariance stated: no error is within it";
  const SingleFrameErrors errors({0.001, 0.002, 0.003, 0.2}, {1.0, 4.0, 9.0, kTwoSigmaSquared3d});
  EXPECT_EQ(errors.within_two_sigma, 3u);
  EXPECT_NE(errors.summaryLine(0).find("within the stated covariance's 2 sigma: 75 %"), std::string::npos)
      << errors.summaryLine(0);
}

TEST(Offline, AnImageSizeNoIntHoldsIsRefusedByName) {
  const ToolRun run = offline("--sequence " + shortSequence(2) + " --output " + test::scratchDirectory("huge") +
                              " --intrinsics 585,585,320,240,1e20,1e20");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("--intrinsics: the width W: expected a whole number, got \"585,585,320,240,1e20,1e20\""),
            std::string::npos)
      << run.output;
}

TEST(OutputFolder, ResultsAppearOnlyOnCommitAndReplaceThePreviousRunsWhole) {
  const std::string dir = test::scratchDirectory("output_folder");
  {
    OutputFolder first(dir, {"a.txt", "b.txt", "summary.txt"});
    io::writeTextFile(first.path("a.txt"), "first a");
    io::writeTextFile(first.path("b.txt"), "first b");
    io::writeTextFile(first.path("summary.txt"), "first summary");
    EXPECT_FALSE(fs::exists(dir + "/a.txt")) << "nothing in place before commit";
    first.commit({"summary.txt"});
  }
  {
    // A run killed (or failing) before it commits leaves the previous results as they were.
    OutputFolder failing(dir, {"a.txt", "b.txt", "summary.txt"});
    io::writeTextFile(failing.path("a.txt"), "half-done");
  }
  std::ifstream a(dir + "/a.txt");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), "first a");
  {
    OutputFolder second(dir, {"a.txt", "b.txt", "summary.txt"});
    io::writeTextFile(second.path("a.txt"), "second a");
    io::writeTextFile(second.path("summary.txt"), "second summary");
    second.commit({"summary.txt"});
  }
  EXPECT_FALSE(fs::exists(dir + "/b.txt")) << "a result of the previous run that this one did not write";
  for (const auto& entry : fs::directory_iterator(dir)) {
    EXPECT_TRUE(entry.path().filename() == "a.txt" || entry.path().filename() == "summary.txt") << entry.path();
  }
}

TEST(OutputFolder, StagingFoldersOfKilledRunsAreRemovedAtTheNextStart) {
  const std::string dir = test::scratchDirectory("output_stale");
  const std::string stale = dir + "/.sdf_tracker_staging-2147483000";  // no such process
  fs::create_directories(stale);
  io::writeTextFile(stale + "/mesh.ply.tmp", std::string(1000, 'x'));
  OutputFolder next(dir, {"mesh.ply"});
  EXPECT_FALSE(fs::exists(stale));
}

TEST(Offline, AnEmptyOutputFolderIsRefusedAndNothingIsWritten) {
  const std::string sequence = shortSequence(3);
  const ToolRun run = offline("--sequence " + sequence + " --output ''");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("--output must name a folder"), std::string::npos) << run.output;
  EXPECT_FALSE(fs::exists("/trajectory.txt"));
}

TEST(Offline, AbsurdThreadCountsAreRefusedWithTheLimit) {
  const ToolRun run = offline("--sequence " + shortSequence(3) + " --output " + test::scratchDirectory("o") +
                          " --threads 100000");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("--threads must be in [1, "), std::string::npos) << run.output;
  EXPECT_EQ(run.output.rfind("sdf_tracker_offline: error: ", 0), 0u) << "the first line, not after an empty one:\n"
                                                                      << run.output;
}

TEST(Offline, NodeOnlyParametersAreRefusedNotIgnored) {
  const ToolRun run = offline("--sequence " + shortSequence(3) + " --output " + test::scratchDirectory("o") +
                          " --param FocalLengthX=-5 --param ImageWidth=123");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("FocalLengthX: read by the ROS node only"), std::string::npos) << run.output;
}

TEST(Offline, FuseGroundTruthMeasuresTheTrackerAloneAndNeedsGroundTruth) {
  const std::string sequence = shortSequence(8);
  const std::string out = test::scratchDirectory("fuse_gt");
  const ToolRun run = offline("--sequence " + sequence + " --output " + out + " --fuse-ground-truth");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // Exact ground truth and a desk scene that constrains every direction: no frame is off by 1 cm.
  EXPECT_NE(run.output.find("tracker alone (--fuse-ground-truth): translation error per frame (mm) mean "),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("over 1 cm: 0 of 7 frames; within the stated covariance's 2 sigma: "), std::string::npos)
      << run.output;
  std::ifstream json(out + "/summary.json");
  const std::string summary((std::istreambuf_iterator<char>(json)), std::istreambuf_iterator<char>());
  EXPECT_NE(summary.find("\"single_frame_error_m\""), std::string::npos) << summary;

  fs::remove(sequence + "/groundtruth.txt");
  expectRefused(sequence, "--fuse-ground-truth", {"--fuse-ground-truth needs the sequence's groundtruth.txt"});
}

TEST(Offline, TooFewFramesForAccuracyStillSucceedWithASummary) {
  const std::string out = test::scratchDirectory("few");
  const ToolRun run = offline("--sequence " + shortSequence(5) + " --output " + out + " --frames 2");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("accuracy not evaluated"), std::string::npos) << run.output;
  EXPECT_TRUE(fs::exists(out + "/summary.json"));
  // The default preset closes loops: with none, the summary says so, not a solve of 0 ms.
  EXPECT_NE(run.output.find("the graph was never solved (no loop)"), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("graph solved"), std::string::npos) << run.output;
}

TEST(Offline, ARunInWhichNoFrameCouldBeTrackedFails) {
  // Every frame after the first holds no depth at all.
  const std::string sequence = shortSequence(3);
  const DepthImage empty(test::testCamera().width, test::testCamera().height, 0.0f);
  std::ifstream list(sequence + "/depth.txt");
  std::string line;
  int frame = 0;
  while (std::getline(list, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (frame++ > 0) io::writeDepthPng(sequence + "/" + line.substr(line.find(' ') + 1), empty, 5000.0);
  }
  const ToolRun run = offline("--sequence " + sequence + " --output " + test::scratchDirectory("none"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("no frame could be tracked after the first: accuracy not evaluated"), std::string::npos)
      << run.output;
  EXPECT_EQ(run.output.find("ATE"), std::string::npos) << "an error of poses never tracked:\n" << run.output;
}

TEST(Offline, AnUnreadableImageIsABadFrameAndTheRunGoesOn) {
  const std::string sequence = shortSequence(4);
  std::ifstream list(sequence + "/depth.txt");
  std::string line, third;
  for (int frame = 0; std::getline(list, line);) {
    if (!line.empty() && line[0] != '#' && frame++ == 2) third = sequence + "/" + line.substr(line.find(' ') + 1);
  }
  std::ofstream(third, std::ios::trunc) << "not a PNG";
  const std::string output = test::scratchDirectory("unreadable");
  const ToolRun run = offline("--sequence " + sequence + " --output " + output);
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("frame 2: " + third + ": not a PNG file (no PNG signature and header): skipped"),
            std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("failed 1\n1 frame could not be read and counted as failed (bad_input), the first: " +
                            third),
            std::string::npos)
      << run.output;
  EXPECT_EQ(io::readTrajectory(output + "/trajectory.txt").size(), 3u)
      << "estimates only: the unreadable frame has none (README: \"Estimates and held poses\")";
}

TEST(Offline, ARunInWhichNotEvenTheFirstFrameHoldsDepthFails) {
  const std::string sequence = shortSequence(3);
  const DepthImage empty(test::testCamera().width, test::testCamera().height, 0.0f);
  std::ifstream list(sequence + "/depth.txt");
  std::string line;
  while (std::getline(list, line)) {
    if (!line.empty() && line[0] != '#') io::writeDepthPng(sequence + "/" + line.substr(line.find(' ') + 1), empty, 5000.0);
  }
  const ToolRun run = offline("--sequence " + sequence + " --output " + test::scratchDirectory("no_depth"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("tracked ok 0, failed 3"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("no frame could be tracked"), std::string::npos) << run.output;
}

TEST(Offline, AnOdometryOnAnotherClockIsRefusedByName) {
  const std::string sequence = shortSequence(3);
  const std::string odometry = test::scratchDirectory("odometry_clock") + "/odometry.txt";
  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(100.0, 0.0, 0.0);
  io::writeTrajectory(odometry, {{5000.0, Eigen::Isometry3d::Identity()}, {5000.033, far}});
  const ToolRun run = offline("--sequence " + sequence + " --output " + test::scratchDirectory("odometry_clock_run") +
                              " --odometry " + odometry);
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("--odometry " + odometry + ": its 2 poses (5000.000 .. 5000.033 s) give a pose for none of "
                            "the 3 frames"),
            std::string::npos)
      << run.output;
}

TEST(Offline, ARunInWhichNoFrameFitsTheLoadedMapFails) {
  // A valid map that holds no surface, only free space 50 m away: every frame, the first too, is
  // tracked in it and fits nowhere, and the search has nothing to search.
  VolumeConfig config;
  config.type = MapType::kSparse;
  SparseTsdfMap far_free_space(config);
  for (Voxel& voxel : far_free_space.allocate(SparseTsdfMap::BlockIndex(300, 0, 0)).voxels) voxel = {0.1f, 1.0f};
  const std::string dir = test::scratchDirectory("no_surface_map");
  io::writeMap(dir + "/free.sdfmap", far_free_space);
  const std::string output = test::scratchDirectory("missed");
  const ToolRun run =
      offline("--sequence " + shortSequence(3) + " --output " + output + " --load-volume " + dir + "/free.sdfmap");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_NE(run.output.find("tracked ok 0, failed 3"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("no frame could be tracked in the loaded map: accuracy not evaluated"), std::string::npos)
      << run.output;
  // Issue 44: every frame says why it failed (the first one was bad_input with no message).
  std::ifstream frames(output + "/frames.csv");
  std::string line;
  std::getline(frames, line);
  for (int i = 0; i < 3 && std::getline(frames, line); ++i) {
    EXPECT_EQ(line.find("bad_input"), std::string::npos) << line;
    EXPECT_NE(line.back(), ',') << "a message ends the row: " << line;
  }

  // An empty map is refused when loaded, before any frame: no run in it could ever track.
  VolumeConfig empty_config;
  empty_config.type = MapType::kSparse;
  io::writeSparseMap(dir + "/empty.sdfmap", SparseTsdfMap(empty_config));
  const ToolRun empty = offline("--sequence " + shortSequence(3) + " --output " + test::scratchDirectory("empty_load") +
                                " --load-volume " + dir + "/empty.sdfmap");
  EXPECT_EQ(empty.exit_code, 1) << empty.output;
  EXPECT_NE(empty.output.find("empty.sdfmap: an empty map: no voxel holds an observation"), std::string::npos)
      << empty.output;
}

TEST(Offline, ASavedMapIsLoadedByTheNextRunAndACorruptOneIsRefusedByName) {
  const std::string sequence = shortSequence(6);
  const std::string first = test::scratchDirectory("save_map");
  const ToolRun mapping =
      offline("--sequence " + sequence + " --output " + first + " --save-map --param MapType=sparse");
  ASSERT_EQ(mapping.exit_code, 0) << mapping.output;
  ASSERT_TRUE(fs::exists(first + "/map.sdfmap"));
  const std::string reuse_dir = test::scratchDirectory("load_map");
  const ToolRun reuse =
      offline("--sequence " + sequence + " --output " + reuse_dir + " --load-volume " + first + "/map.sdfmap");
  EXPECT_EQ(reuse.exit_code, 0) << reuse.output;
  EXPECT_NE(reuse.output.find("sparse map of 0.02 m voxels"), std::string::npos)
      << "the file's storage replaces the configured dense grid:\n" << reuse.output;
  // Where the camera is in it is not known: the first frames search for it and fuse nothing, and
  // the frame that confirms the third fit is tracked.
  EXPECT_NE(reuse.output.find("tracked ok 4, failed 2"), std::string::npos) << reuse.output;
  EXPECT_NE(reuse.output.find("holds 1 keyframes in its place memory"), std::string::npos) << reuse.output;
  EXPECT_NE(reuse.output.find("relocalisation: 3 frames searched the map for the camera"), std::string::npos)
      << reuse.output;
  EXPECT_NE(reuse.output.find("1 found it"), std::string::npos) << reuse.output;
  // Issue 44: the searching frames have no pose; the held one was written as if estimated.
  EXPECT_EQ(io::readTrajectory(reuse_dir + "/trajectory.txt").size(), 4u) << "estimates only";
  const ToolRun held = offline("--sequence " + sequence + " --output " + test::scratchDirectory("load_map_held") +
                               " --load-volume " + first + "/map.sdfmap --param Relocalise=false");
  EXPECT_NE(held.output.find("tracked ok 6"), std::string::npos) << "without the search, the first frame is tracked "
                                                                   "from the map's start pose:\n"
                                                                << held.output;
  // A pose given by hand is verified like any candidate; it needs a loaded map and the search.
  const ToolRun told = offline("--sequence " + sequence + " --output " + test::scratchDirectory("told") +
                               " --load-volume " + first + "/map.sdfmap --initial-pose 0.01,0,0,0,0,0,1");
  EXPECT_NE(told.output.find("tracked ok 4, failed 2"), std::string::npos) << told.output;
  // Issue 44: a pose far from the map was taken and logged with 300 digits.
  const ToolRun far = offline("--sequence " + sequence + " --output " + test::scratchDirectory("told_far") +
                              " --load-volume " + first + "/map.sdfmap --initial-pose 1e300,0,0,0,0,0,1");
  EXPECT_EQ(far.exit_code, 1) << far.output;
  EXPECT_NE(far.output.find("--initial-pose 1e300,0,0,0,0,0,1: the camera at (1e+300"), std::string::npos) << far.output;
  EXPECT_NE(far.output.find(") m would be 1e+300 m from the map"), std::string::npos) << far.output;
  EXPECT_NE(far.output.find("beyond MaxDepth 8 m"), std::string::npos) << far.output;
  for (const auto& [options, message] : std::vector<std::pair<std::string, std::string>>{
           {" --initial-pose 0,0,0,0,0,0,1", "--initial-pose places the camera in a loaded map (--load-volume)"},
           {" --load-volume " + first + "/map.sdfmap --initial-pose 0,0,0,0,0,0,1 --param Relocalise=false",
            "--initial-pose is verified by the relocaliser, which --param Relocalise=false turns off"},
           {" --load-volume " + first + "/map.sdfmap --initial-pose 0,0,0,0,0,0,2",
            "--initial-pose 0,0,0,0,0,0,2: the quaternion QX,QY,QZ,QW has norm 2.000000, not 1"},
           {" --load-volume " + first + "/map.sdfmap --initial-pose 0,0,0,1", "expected TX,TY,TZ,QX,QY,QZ,QW"}}) {
    const ToolRun refused = offline("--sequence " + sequence + " --output " + test::scratchDirectory("refused") + options);
    EXPECT_EQ(refused.exit_code, 1) << refused.output;
    EXPECT_NE(refused.output.find(message), std::string::npos) << refused.output;
  }

  fs::resize_file(first + "/map.sdfmap", fs::file_size(first + "/map.sdfmap") - 10);
  const ToolRun corrupt = offline("--sequence " + sequence + " --output " + test::scratchDirectory("bad_map") +
                                  " --load-volume " + first + "/map.sdfmap");
  EXPECT_EQ(corrupt.exit_code, 1) << corrupt.output;
  EXPECT_NE(corrupt.output.find(first + "/map.sdfmap: its header lists"), std::string::npos) << corrupt.output;
}

TEST(Offline, AMemoryBoundIsReportedAndRefusedWhereItCannotHold) {
  const std::string sequence = shortSequence(4);
  // One map swaps blocks, submaps (the default preset) whole submaps. Four frames of one view:
  // every block is near the camera and the one submap is the active one, none can go, and the
  // user hears so once.
  for (const auto& [params, swapped] : {std::pair<std::string, std::string>{" --param SubmapSize=0", "0 blocks"},
                                        {"", "0 of 1 submaps"}}) {
    const ToolRun bounded = offline("--sequence " + sequence + " --output " + test::scratchDirectory("bound") +
                                    " --param MapType=sparse --param MaxMemoryMB=0.5" + params);
    EXPECT_EQ(bounded.exit_code, 0) << bounded.output;
    EXPECT_NE(bounded.output.find("(MaxMemoryMB 0.50; " + swapped), std::string::npos) << bounded.output;
    const std::string overrun = "warning: the map holds ";
    const size_t warned_at = bounded.output.find(overrun);
    ASSERT_NE(warned_at, std::string::npos) << bounded.output;
    EXPECT_NE(bounded.output.find("above MaxMemoryMB=0.5", warned_at), std::string::npos) << bounded.output;
    EXPECT_EQ(bounded.output.find(overrun, warned_at + 1), std::string::npos) << "warned more than once";
  }

  expectRefused(sequence, "--param MapType=dense --param MaxMemoryMB=64", {"MaxMemoryMB=64 applies to MapType=sparse only"});
  expectRefused(sequence, "--param MapType=sparse --param MaxMemoryMB=64 --param SwapDirectory=/nonexistent/swap",
                {"SwapDirectory", "/nonexistent/swap"});
}

TEST(Offline, AVolumeRegionWritesOnlyTheVoxelsInsideIt) {
  const std::string sequence = shortSequence(3);
  const std::string out = test::scratchDirectory("region");
  const ToolRun run = offline("--sequence " + sequence + " --output " + out +
                              " --param MapType=sparse --param CellSize=0.04 --save-volume --volume-region -0.5,-0.5,0.5,0.5,0.3,2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const TsdfVolume region = io::readVti(out + "/sdf_volume.vti");
  // The lattice starts at the first camera's position, so voxel i lies at 0.04 i m.
  EXPECT_EQ(region.dims(), Eigen::Vector3i(25, 20, 38));
  EXPECT_TRUE(region.position(0, 0, 0).isApprox(Eigen::Vector3f(-0.48f, -0.48f, 0.52f), 1e-5f)) << region.position(0, 0, 0);

  expectRefused(sequence, "--volume-region 0,0,0,1,1,1", {"--volume-region applies to --save-volume"});
  expectRefused(sequence, "--save-volume --volume-region 0,0,0,1,-1,1", {"--volume-region: expected X0,Y0,Z0,X1,Y1,Z1"});
}

TEST(Offline, TheJsonSummaryIsValidJsonEvenForAPathWithATab) {
  const std::string sequence = shortSequence(3);
  const std::string tabbed = sequence + "\tfolder";
  fs::rename(sequence, tabbed);
  const std::string out = test::scratchDirectory("json");
  const ToolRun run = offline("--sequence '" + tabbed + "' --output " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(std::system(("/usr/bin/python3 -m json.tool " + out + "/summary.json > /dev/null").c_str()), 0);
}

TEST(Offline, TheLensDistortionIsTakenFromTheOptionAndSaid) {
  const std::string sequence = shortSequence(3);
  const ToolRun none = offline("--sequence " + sequence + " --output " + test::scratchDirectory("lens0"));
  ASSERT_EQ(none.exit_code, 0) << none.output;
  EXPECT_NE(none.output.find("lens distortion: none (intrinsics.txt)"), std::string::npos) << none.output;
  const ToolRun given = offline("--sequence " + sequence + " --output " + test::scratchDirectory("lens1") +
                                " --distortion 0.1,-0.2,0,0,0.05");
  ASSERT_EQ(given.exit_code, 0) << given.output;
  EXPECT_NE(given.output.find("lens distortion removed from every image: k1 0.1 k2 -0.2"), std::string::npos)
      << given.output;
  const ToolRun short_list = offline("--sequence " + sequence + " --output " + test::scratchDirectory("lens2") +
                                     " --distortion 0.1,0.2");
  EXPECT_EQ(short_list.exit_code, 1);
  EXPECT_NE(short_list.output.find("--distortion: expected K1,K2,P1,P2,K3, got \"0.1,0.2\""), std::string::npos)
      << short_list.output;
}

TEST(Offline, TumsIntrinsicsWithoutAStatedDistortionAreTrackedAsTheyAreAndTheMatchSaid) {
  // A sequence rendered for freiburg1's intrinsics through an ideal lens, its intrinsics.txt
  // without distortion columns, stamped in Unix time as TUM's recordings are.
  const std::string dir = test::scratchDirectory("tum_intrinsics");
  synthetic::SequenceSpec spec;
  spec.frames = 3;
  synthetic::writeSequence(dir, spec);
  std::ofstream(dir + "/intrinsics.txt") << "517.3 516.5 318.6 255.3 640 480 5000\n";
  std::ifstream list(dir + "/depth.txt");
  std::ostringstream unix_time;
  unix_time << std::fixed << std::setprecision(6);
  std::string line;
  for (int frame = 0; std::getline(list, line);) {
    if (!line.empty() && line[0] != '#') unix_time << 1305031102.0 + frame++ / 30.0 << line.substr(line.find(' ')) << "\n";
  }
  std::ofstream(dir + "/depth.txt") << unix_time.str();
  const ToolRun run = offline("--sequence " + dir + " --output " + test::scratchDirectory("tum_intrinsics_out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("lens distortion: none (none stated)"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("note: these are TUM freiburg1's intrinsics, but no lens distortion is stated, so none is "
                            "removed"),
            std::string::npos)
      << run.output;
}

TEST(Evaluate, ThePerPoseErrorsAreTheOnesTheRmseSummarises) {
  const std::string sequence = shortSequence(12);
  const std::string out = test::scratchDirectory("errors");
  ASSERT_EQ(offline("--sequence " + sequence + " --output " + out).exit_code, 0);
  const ToolRun run = test::runCommand(std::string(SDF_TRACKER_EVALUATE) + " --groundtruth " + sequence +
                                 "/groundtruth.txt --estimate " + out + "/trajectory.txt --errors " + out + "/e.csv");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream csv(out + "/e.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "timestamp,error_m");
  double sum = 0.0;
  int rows = 0;
  while (std::getline(csv, line)) {
    sum += std::pow(std::stod(line.substr(line.find(',') + 1)), 2);
    ++rows;
  }
  EXPECT_EQ(rows, 12);
  const auto ate = evaluation::computeAte(io::readTrajectory(out + "/trajectory.txt"),
                                          io::readTrajectory(sequence + "/groundtruth.txt"));
  EXPECT_NEAR(std::sqrt(sum / rows), ate.translation_m.rmse, 1e-5);
}

}  // namespace
}  // namespace sdf_tracker::tools
