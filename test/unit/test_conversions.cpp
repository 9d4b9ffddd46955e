#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <sensor_msgs/image_encodings.h>

#include "sdf_tracker/SdfTrackerConfig.h"
#include "sdf_tracker/core/parameters.h"
#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {
namespace {

sensor_msgs::Image millimetreImage(uint32_t width, uint32_t height, uint16_t value) {
  sensor_msgs::Image msg;
  msg.width = width;
  msg.height = height;
  msg.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
  msg.step = width * 2;
  msg.data.resize(msg.step * height);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) std::memcpy(&msg.data[2 * i], &value, 2);
  return msg;
}

TEST(Conversions, MillimetresAndMetresGiveTheSameDepth) {
  const sdf_tracker::DepthImage mm = toDepthImage(millimetreImage(4, 3, 1234));
  EXPECT_FLOAT_EQ(mm.at(3, 2), 1.234f);
  std_msgs::Header header;
  header.frame_id = "cam";
  const sensor_msgs::Image metres = toImageMsg(mm, header);
  EXPECT_EQ(metres.encoding, sensor_msgs::image_encodings::TYPE_32FC1);
  EXPECT_EQ(metres.header.frame_id, "cam");
  EXPECT_FLOAT_EQ(toDepthImage(metres).at(1, 1), 1.234f);
}

TEST(Conversions, ZeroAndNaNAreNoMeasurement) {
  const sdf_tracker::DepthImage zero = toDepthImage(millimetreImage(2, 2, 0));
  EXPECT_EQ(zero.countMeasurements(), 0);
  sdf_tracker::DepthImage nan(2, 2, std::nanf(""));
  EXPECT_EQ(toDepthImage(toImageMsg(nan, std_msgs::Header())).countMeasurements(), 0);
}

TEST(Conversions, UnreadableImagesNameTheProblem) {
  sensor_msgs::Image colour = millimetreImage(4, 3, 1);
  colour.encoding = "rgb8";
  try {
    toDepthImage(colour);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rgb8"), std::string::npos);
  }
  sensor_msgs::Image short_data = millimetreImage(4, 3, 1);
  short_data.data.resize(5);
  EXPECT_THROW(toDepthImage(short_data), std::invalid_argument);
  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;  // K all zero: an uncalibrated camera
  EXPECT_THROW(toCamera(info), std::invalid_argument);
  info.K = {525, 0, 319.5, 0, 525, 239.5, 0, 0, 1};
  EXPECT_DOUBLE_EQ(toCamera(info).cx, 319.5);
}

TEST(Reconfigure, EveryLiveParameterIsInTheCoreTableAndMarkedLive) {
  for (const auto& description : sdf_tracker::SdfTrackerConfig::__getParamDescriptions__()) {
    const sdf_tracker::ParameterSpec* spec = sdf_tracker::findParameter(description->name);
    ASSERT_NE(spec, nullptr) << description->name << " is in cfg/SdfTracker.cfg but not in the parameter table";
    EXPECT_TRUE(spec->live) << description->name << " is reconfigurable but its table entry says it is not live";
  }
}

}  // namespace
}  // namespace sdf_tracker_ros
