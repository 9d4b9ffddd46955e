// Depth cameras' own formats: the Kinect v1's disparity model, fakenect recordings as libfreenect
// replays them, and the calibration file the drivers read.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include "sdf_tracker/devices/fakenect_dump.h"
#include "sdf_tracker/devices/kinect_disparity.h"
#include "sdf_tracker/devices/recording.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "test_helpers.h"

namespace sdf_tracker::devices {
namespace {

namespace fs = std::filesystem;

TEST(KinectDisparity, MatchesLibfreenectsModelAtKnownPoints) {
  const KinectDisparityTable table;
  // libfreenect with the factory zero plane: disparity 4 * (const_shift + 0.375) = 801.5 lies on
  // the zero plane (1.2 m); the model's depth grows with disparity.
  EXPECT_NEAR(table.toMillimetres(802), 1200, 3);
  EXPECT_NEAR(table.toMillimetres(1000), 3864, 2);
  EXPECT_EQ(table.toMillimetres(kKinectNoDisparity), 0);
  EXPECT_LT(table.nearest_mm(), 500);
  EXPECT_GT(table.farthest_mm(), 8000);
  for (uint16_t d = 1; d < 1050; ++d) {
    if (table.toMillimetres(d) != 0 && table.toMillimetres(d - 1) != 0) {
      EXPECT_GE(table.toMillimetres(d), table.toMillimetres(d - 1)) << "at disparity " << d;
    }
  }
  EXPECT_NEAR(KinectZeroPlane().focalLength640_px(), 575.8, 0.1) << "freenect_camera's depth focal length";
}

TEST(KinectDisparity, RoundTripErrorIsHalfAStepOfTheSensor) {
  const KinectDisparityTable table;
  for (uint16_t mm = 600; mm <= 6000; mm += 7) {
    const uint16_t d = table.fromMillimetres(mm);
    ASSERT_NE(d, kKinectNoDisparity) << mm << " mm is within the Kinect's range";
    const int step = table.toMillimetres(d + 1) - table.toMillimetres(d - 1);
    EXPECT_LE(std::abs(table.toMillimetres(d) - mm), step / 2 + 1) << "at " << mm << " mm";
  }
  // Exact depths of the table come back exactly.
  const uint16_t exact_mm = table.toMillimetres(900);
  EXPECT_EQ(table.toMillimetres(table.fromMillimetres(exact_mm)), exact_mm);
  EXPECT_EQ(table.fromMillimetres(0), kKinectNoDisparity);
  EXPECT_EQ(table.fromMillimetres(60000), kKinectNoDisparity) << "beyond 10 m the Kinect reports nothing";
  EXPECT_EQ(table.fromMillimetres(50), kKinectNoDisparity) << "too near for the Kinect";
}

TEST(FakenectDump, IsWrittenAsFakenectRecordReadsItAndOnlyWhenComplete) {
  const std::string root = test::scratchDirectory("fakenect");
  const std::string dump = root + "/dump";
  std::vector<uint16_t> frame(fakenect::kWidth * fakenect::kHeight, kKinectNoDisparity);
  frame[0] = 802;
  frame[1] = 1000;
  {
    FakenectDumpWriter writer(dump);
    writer.addDepth(1305031102.175304, frame);
    writer.addDepth(1305031102.211214, frame);
    EXPECT_FALSE(fs::exists(dump)) << "the recording appears only when complete";
    EXPECT_THROW(writer.addDepth(1.0, std::vector<uint16_t>(10)), std::invalid_argument);
    writer.finish();
  }
  ASSERT_TRUE(fs::exists(dump + "/INDEX.txt"));
  EXPECT_FALSE(fs::exists(dump + ".partial"));
  const std::vector<FakenectFrame> frames = readFakenectFrames(dump).depth;
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_NEAR(frames[0].time_s, 1305031102.175304, 1e-6);
  EXPECT_NEAR(frames[1].time_s, 1305031102.211214, 1e-6);
  EXPECT_EQ(frames[0].problem, "");
  EXPECT_EQ(frames[1].problem, "");

  // fakenect's reader: "<type>-<seconds>-<timestamp>.pgm", a one-line header, raw values.
  std::ifstream index(dump + "/INDEX.txt");
  std::string first;
  std::getline(index, first);
  EXPECT_EQ(first.rfind("d-1305031102.175304-0.pgm", 0), 0u) << first;
  std::ifstream pgm(dump + "/" + first, std::ios::binary);
  std::string header;
  std::getline(pgm, header);
  EXPECT_EQ(header, "P5 640 480 65535");
  uint16_t values[2];
  pgm.read(reinterpret_cast<char*>(values), sizeof(values));
  EXPECT_EQ(values[0], 802);
  EXPECT_EQ(values[1], 1000);

  EXPECT_THROW(FakenectDumpWriter{dump}, std::runtime_error) << "an existing recording is not overwritten";
  {
    FakenectDumpWriter abandoned(root + "/abandoned");
    abandoned.addDepth(1.0, frame);
  }
  EXPECT_FALSE(fs::exists(root + "/abandoned")) << "a conversion that did not finish leaves nothing";
  EXPECT_FALSE(fs::exists(root + "/abandoned.partial"));
  fs::remove_all(root);
}

TEST(FakenectDump, AnIndexWithAStrayLineIsRefusedWithItsLineNumber) {
  const std::string root = test::scratchDirectory("fakenect_index");
  std::ofstream(root + "/INDEX.txt") << "d-1.000000-0.pgm\nnot a file name\n";
  try {
    readFakenectFrames(root);
    FAIL() << "a stray line was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readFakenectFrames(root + "/missing"), std::runtime_error);
  fs::remove_all(root);
}

TEST(FakenectDump, AFrameCutShortOrMissingIsNamedWithWhatItLacks) {
  const std::string root = test::scratchDirectory("fakenect_cut");
  const std::string dump = root + "/dump";
  {
    FakenectDumpWriter writer(dump);
    for (int i = 0; i < 3; ++i) writer.addDepth(10.0 + i / 30.0, std::vector<uint16_t>(640 * 480, 1000));
    writer.finish();
  }
  std::vector<FakenectFrame> frames = readFakenectFrames(dump).depth;
  ASSERT_EQ(frames.size(), 3u);
  fs::resize_file(frames[1].file, fs::file_size(frames[1].file) / 2);  // a copy that stopped half-way
  fs::remove(frames[2].file);
  frames = readFakenectFrames(dump).depth;
  EXPECT_EQ(frames[0].problem, "");
  EXPECT_NE(frames[1].problem.find("holds 307208 bytes of the 614417 a 640x480 image needs"), std::string::npos)
      << frames[1].problem;
  EXPECT_EQ(frames[2].problem, "cannot be opened");
  fs::remove_all(root);
}

TEST(FakenectDump, CarriesColourImagesBetweenTheDepthFramesInTheOrderTheyCame) {
  const std::string root = test::scratchDirectory("fakenect_colour");
  const std::string dump = root + "/dump";
  ColourImage colour(fakenect::kWidth, fakenect::kHeight, 0);
  colour.at(0, 0)[0] = 200;  // red
  colour.at(1, 0)[2] = 100;  // blue
  {
    FakenectDumpWriter writer(dump);
    writer.addDepth(10.0, std::vector<uint16_t>(640 * 480, 1000));
    writer.addColour(10.01, colour);
    writer.addDepth(10.033, std::vector<uint16_t>(640 * 480, 1000));
    EXPECT_THROW(writer.addColour(10.05, ColourImage(320, 240)), std::invalid_argument) << "fakenect plays 640x480";
    writer.finish();
  }
  std::ifstream index(dump + "/INDEX.txt");
  std::vector<std::string> lines;
  for (std::string line; std::getline(index, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u);
  EXPECT_EQ(lines[1].rfind("r-10.010000-10000.ppm", 0), 0u) << "fakenect's name for a colour image: " << lines[1];
  std::ifstream ppm(dump + "/" + lines[1], std::ios::binary);
  std::string header;
  std::getline(ppm, header);
  EXPECT_EQ(header, "P6 640 480 255");
  uint8_t pixels[6];
  ppm.read(reinterpret_cast<char*>(pixels), sizeof(pixels));
  EXPECT_EQ(pixels[0], 200);
  EXPECT_EQ(pixels[5], 100);

  FakenectFrames frames = readFakenectFrames(dump);
  ASSERT_EQ(frames.depth.size(), 2u);
  ASSERT_EQ(frames.colour.size(), 1u);
  EXPECT_NEAR(frames.colour[0].time_s, 10.01, 1e-6);
  EXPECT_EQ(frames.colour[0].problem, "");
  fs::resize_file(frames.colour[0].file, 1000);
  frames = readFakenectFrames(dump);
  EXPECT_NE(frames.colour[0].problem.find("holds 1000 bytes of the 921615 a 640x480 image needs"), std::string::npos)
      << frames.colour[0].problem;
  std::ofstream(frames.colour[0].file) << "P5 640 480 65535\n";
  EXPECT_NE(readFakenectFrames(dump).colour[0].problem.find("not \"P6 640 480 <maximum>\""), std::string::npos)
      << "a depth file where a colour image belongs is named";
  fs::remove_all(root);
}

TEST(RecordingOrder, InterleavesTheColourImagesPairedWithTheDepthFramesByTime) {
  const std::string root = test::scratchDirectory("recording_order");
  std::ofstream(root + "/depth.txt") << "1.000 depth/a.png\n1.033 depth/b.png\n1.066 depth/c.png\n";
  // b's colour image comes before it, a's after it; c has none within 20 ms.
  std::ofstream(root + "/rgb.txt") << "1.010 rgb/a.png\n1.025 rgb/b.png\n1.200 rgb/late.png\n";
  const TumSequence sequence = TumSequence::open(root);
  std::vector<RecordedImage> order = recordingOrder(sequence, true);
  ASSERT_EQ(order.size(), 5u);
  const std::vector<std::pair<size_t, bool>> expected = {{0, false}, {0, true}, {1, true}, {1, false}, {2, false}};
  for (size_t i = 0; i < order.size(); ++i) {
    EXPECT_EQ(order[i].frame, expected[i].first) << "image " << i;
    EXPECT_EQ(order[i].colour, expected[i].second) << "image " << i;
    if (i > 0) {
      EXPECT_LE(order[i - 1].timestamp_s, order[i].timestamp_s);
    }
  }
  EXPECT_EQ(recordingOrder(sequence, false).size(), 3u) << "without colour: the depth frames alone";
  fs::remove_all(root);
}

TEST(RecordingClock, IsShiftedWhenTheDepthOrTheGroundTruthStartsBelowOneSecond) {
  const std::string root = test::scratchDirectory("recording_clock");
  auto folder = [&root](const std::string& name, const std::string& depth, const std::string& truth) {
    const std::string dir = root + "/" + name;
    fs::create_directories(dir);
    std::ofstream(dir + "/depth.txt") << depth;
    if (!truth.empty()) std::ofstream(dir + "/groundtruth.txt") << truth;
    return TumSequence::open(dir);
  };
  const std::string pose = " 0 0 0 0 0 0 1\n";
  EXPECT_EQ(rosStampOffset(folder("from_zero", "0.0 depth/a.png\n0.033 depth/b.png\n", "")), 1.0);
  EXPECT_EQ(rosStampOffset(folder("unix_time", "1305031102.175 depth/a.png\n", "1305031102.1 " + pose)), 0.0);
  // A later part cut from a sequence that starts at 0 s: its depth starts at 20 s, its ground
  // truth (kept whole, for the evaluation) at 0 s, and a bag of it holds both.
  EXPECT_EQ(rosStampOffset(folder("later_part", "20.6 depth/a.png\n20.633 depth/b.png\n",
                                  "0.0" + pose + "20.6" + pose)), 1.0);
  fs::remove_all(root);
}

TEST(CalibrationFile, HoldsTheIntrinsicsInCameraInfoManagersLayout) {
  const std::string root = test::scratchDirectory("calibration");
  EXPECT_EQ(calibrationFileFor(root), root + "/depth_camera_info.yaml");
  EXPECT_EQ(calibrationFileFor(root + "/x.oni"), root + "/x.oni.yaml");
  EXPECT_EQ(calibrationFileFor(root, RecordedCamera::kColour), root + "/rgb_camera_info.yaml");
  EXPECT_EQ(calibrationFileFor(root + "/x.oni", RecordedCamera::kColour), root + "/x.oni.rgb.yaml");
  PinholeCamera camera = PinholeCamera::tumFreiburg1();
  camera.distortion = PinholeCamera::tumCamera("freiburg1")->distortion;
  writeCalibrationFile(root + "/c.yaml", camera, "depth");
  std::ifstream in(root + "/c.yaml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("image_width: 640"), std::string::npos);
  EXPECT_NE(text.find("data: [517.3, 0, 318.6, 0, 516.5, 255.3, 0, 0, 1]"), std::string::npos) << text;
  EXPECT_NE(text.find("distortion_model: plumb_bob"), std::string::npos);
  EXPECT_NE(text.find("data: [0.2624, -0.9531, -0.0054, 0.0026, 1.1633]"), std::string::npos) << text;
  fs::remove_all(root);
}

}  // namespace
}  // namespace sdf_tracker::devices
