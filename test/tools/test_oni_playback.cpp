// The .oni recordings tum_to_oni writes, played by OpenNI 2's own OniFile driver as
// openni2_depth_publisher plays them: the streams a recording holds, their frames in the order
// written, each with its timestamp and its pixels.
#include <gtest/gtest.h>

#include <OpenNI.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "sdf_tracker/devices/oni_file.h"
#include "test_helpers.h"

namespace sdf_tracker::devices {
namespace {

namespace fs = std::filesystem;

constexpr int kTimeout_ms = 2000;

PinholeCamera smallCamera() {
  PinholeCamera camera;
  camera.width = 64;
  camera.height = 48;
  camera.fx = camera.fy = 52.5;
  camera.cx = 31.5;
  camera.cy = 23.5;
  return camera;
}

/// OpenNI initialised for the test's lifetime.
class OniPlayback : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(openni::OpenNI::initialize(), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
    root_ = test::scratchDirectory("oni_playback");
  }
  void TearDown() override {
    openni::OpenNI::shutdown();
    fs::remove_all(root_);
  }
  std::string root_;
};

TEST_F(OniPlayback, ADepthAndColourRecordingPlaysBothStreamsInTheOrderWritten) {
  const PinholeCamera camera = smallCamera();
  const std::string path = root_ + "/colour.oni";
  {
    OniRecordingWriter writer(path, camera, true);
    for (int i = 0; i < 3; ++i) {
      std::vector<uint16_t> depth(64 * 48, static_cast<uint16_t>(1000 + i));
      ColourImage colour(64, 48, static_cast<uint8_t>(10 * i));
      colour.at(5, 7)[0] = 250;
      writer.addDepth(1000000 + 33000 * i, depth);
      writer.addColour(1000000 + 33000 * i + 10000, colour);
    }
    EXPECT_THROW(writer.addColour(1099000, ColourImage(32, 24)), std::invalid_argument);
    EXPECT_THROW(writer.addDepth(1000000, std::vector<uint16_t>(64 * 48)), std::invalid_argument)
        << "a stream's timestamps must increase";
    EXPECT_FALSE(fs::exists(path)) << "the recording appears only when complete";
    writer.finish();
  }
  openni::Device device;
  ASSERT_EQ(device.open(path.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  ASSERT_TRUE(device.hasSensor(openni::SENSOR_DEPTH));
  ASSERT_TRUE(device.hasSensor(openni::SENSOR_COLOR));
  openni::VideoStream depth, colour;
  ASSERT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
  ASSERT_EQ(colour.create(device, openni::SENSOR_COLOR), openni::STATUS_OK);
  EXPECT_EQ(colour.getVideoMode().getPixelFormat(), openni::PIXEL_FORMAT_RGB888);
  EXPECT_EQ(colour.getVideoMode().getResolutionX(), 64);
  EXPECT_NEAR(colour.getHorizontalFieldOfView(), depth.getHorizontalFieldOfView(), 1e-6);
  openni::PlaybackControl* playback = device.getPlaybackControl();
  playback->setRepeatEnabled(false);
  playback->setSpeed(-1.0f);  // a frame at a time, as the driver plays it
  EXPECT_EQ(playback->getNumberOfFrames(depth), 3);
  EXPECT_EQ(playback->getNumberOfFrames(colour), 3);
  ASSERT_EQ(depth.start(), openni::STATUS_OK);
  ASSERT_EQ(colour.start(), openni::STATUS_OK);

  openni::VideoStream* streams[] = {&depth, &colour};
  openni::VideoFrameRef frame;
  for (int i = 0; i < 6; ++i) {
    int ready = -1;
    ASSERT_EQ(openni::OpenNI::waitForAnyStream(streams, 2, &ready, kTimeout_ms), openni::STATUS_OK) << "frame " << i;
    const bool is_colour = ready == 1;
    EXPECT_EQ(is_colour, i % 2 == 1) << "frame " << i << ": the streams interleave as written";
    ASSERT_EQ(streams[ready]->readFrame(&frame), openni::STATUS_OK);
    const int n = i / 2;
    EXPECT_EQ(frame.getTimestamp(), static_cast<uint64_t>(1000000 + 33000 * n + (is_colour ? 10000 : 0)));
    if (is_colour) {
      const auto* rgb = static_cast<const uint8_t*>(frame.getData());
      EXPECT_EQ(rgb[0], 10 * n);
      EXPECT_EQ(rgb[(7 * 64 + 5) * 3], 250);
    } else {
      EXPECT_EQ(static_cast<const uint16_t*>(frame.getData())[100], 1000 + n);
    }
  }
  depth.stop();
  colour.stop();
  colour.destroy();
  depth.destroy();
  device.close();
}

TEST_F(OniPlayback, ADepthOnlyRecordingHasNoColourStream) {
  const std::string path = root_ + "/depth.oni";
  {
    OniRecordingWriter writer(path, smallCamera());
    writer.addDepth(1000000, std::vector<uint16_t>(64 * 48, 1500));
    EXPECT_THROW(writer.addColour(1010000, ColourImage(64, 48)), std::logic_error);
    writer.finish();
  }
  openni::Device device;
  ASSERT_EQ(device.open(path.c_str()), openni::STATUS_OK) << openni::OpenNI::getExtendedError();
  EXPECT_TRUE(device.hasSensor(openni::SENSOR_DEPTH));
  EXPECT_FALSE(device.hasSensor(openni::SENSOR_COLOR));
  openni::VideoStream depth;
  ASSERT_EQ(depth.create(device, openni::SENSOR_DEPTH), openni::STATUS_OK);
  device.getPlaybackControl()->setSpeed(-1.0f);
  ASSERT_EQ(depth.start(), openni::STATUS_OK);
  openni::VideoStream* streams[] = {&depth};
  int ready = -1;
  ASSERT_EQ(openni::OpenNI::waitForAnyStream(streams, 1, &ready, kTimeout_ms), openni::STATUS_OK);
  openni::VideoFrameRef frame;
  ASSERT_EQ(depth.readFrame(&frame), openni::STATUS_OK);
  EXPECT_EQ(static_cast<const uint16_t*>(frame.getData())[0], 1500);
  depth.stop();
  depth.destroy();
  device.close();
}

}  // namespace
}  // namespace sdf_tracker::devices
