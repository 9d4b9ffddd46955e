// openni2_depth_publisher: a small depth driver on libopenni2 (openni2_camera is not packaged in
// Debian). Publishes, as openni2_launch does, in REP 118 form:
//   <camera>/depth/image_raw (16UC1 mm), <camera>/depth/image (32FC1 m), <camera>/depth/camera_info
// with frame_id <camera>_depth_optical_frame. Parameters: ~width, ~height, ~fps, ~device_uri.

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <OpenNI.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/image_encodings.h>

namespace {

sensor_msgs::CameraInfo cameraInfoFromFieldOfView(int width, int height, float hfov_rad, float vfov_rad,
                                                  const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = width;
  info.height = height;
  const double fx = width / (2.0 * std::tan(hfov_rad / 2.0));
  const double fy = height / (2.0 * std::tan(vfov_rad / 2.0));
  const double cx = (width - 1) / 2.0, cy = (height - 1) / 2.0;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {fx, 0, cx, 0, fy, cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0};
  return info;
}

int run() {
  ros::NodeHandle nh("camera"), pnh("~");
  const int width = pnh.param("width", 640), height = pnh.param("height", 480), fps = pnh.param("fps", 30);
  const std::string uri = pnh.param<std::string>("device_uri", "");
  const std::string frame_id = pnh.param<std::string>("frame_id", nh.getNamespace().substr(1) + "_depth_optical_frame");

  if (openni::OpenNI::initialize() != openni::STATUS_OK) {
    ROS_FATAL("openni2_depth_publisher: OpenNI2 failed to initialise: %s", openni::OpenNI::getExtendedError());
    return 1;
  }
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  if (devices.getSize() == 0) {
    ROS_FATAL("openni2_depth_publisher: no OpenNI2 depth camera found (is it plugged in, and readable by this user?)");
    openni::OpenNI::shutdown();
    return 1;
  }
  openni::Device device;
  if (device.open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK) {
    ROS_FATAL("openni2_depth_publisher: cannot open device \"%s\": %s", uri.empty() ? "any" : uri.c_str(),
              openni::OpenNI::getExtendedError());
    openni::OpenNI::shutdown();
    return 1;
  }
  openni::VideoStream depth;
  openni::VideoMode mode;
  mode.setResolution(width, height);
  mode.setFps(fps);
  mode.setPixelFormat(openni::PIXEL_FORMAT_DEPTH_1_MM);
  if (depth.create(device, openni::SENSOR_DEPTH) != openni::STATUS_OK || depth.setVideoMode(mode) != openni::STATUS_OK ||
      depth.start() != openni::STATUS_OK) {
    ROS_FATAL("openni2_depth_publisher: cannot start a %dx%d@%d mm depth stream: %s", width, height, fps,
              openni::OpenNI::getExtendedError());
    openni::OpenNI::shutdown();
    return 1;
  }
  image_transport::ImageTransport it(nh);
  image_transport::Publisher raw_pub = it.advertise("depth/image_raw", 1);
  image_transport::Publisher metric_pub = it.advertise("depth/image", 1);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("depth/camera_info", 1);
  ROS_INFO("openni2_depth_publisher: streaming %dx%d@%d from %s", width, height, fps, devices[0].getName());

  openni::VideoFrameRef frame;
  while (ros::ok()) {
    int ready = -1;
    openni::VideoStream* streams[] = {&depth};
    if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, 2000) != openni::STATUS_OK) {
      ROS_WARN_THROTTLE(5.0, "openni2_depth_publisher: no depth frame for 2 s");
      continue;
    }
    if (depth.readFrame(&frame) != openni::STATUS_OK || !frame.isValid()) continue;
    std_msgs::Header header;
    header.stamp = ros::Time::now();  // the driver's clock is not ROS time; stamp at arrival
    header.frame_id = frame_id;
    sensor_msgs::Image raw;
    raw.header = header;
    raw.width = frame.getWidth();
    raw.height = frame.getHeight();
    raw.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
    raw.step = raw.width * 2;
    raw.data.resize(static_cast<size_t>(raw.step) * raw.height);
    for (uint32_t v = 0; v < raw.height; ++v) {
      std::memcpy(raw.data.data() + v * raw.step, static_cast<const uint8_t*>(frame.getData()) + v * frame.getStrideInBytes(),
                  raw.step);
    }
    sensor_msgs::Image metric = raw;
    metric.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
    metric.step = raw.width * 4;
    metric.data.resize(static_cast<size_t>(metric.step) * raw.height);
    const size_t n = static_cast<size_t>(raw.width) * raw.height;
    for (size_t i = 0; i < n; ++i) {
      uint16_t mm;
      std::memcpy(&mm, raw.data.data() + 2 * i, 2);
      const float m = mm == 0 ? std::numeric_limits<float>::quiet_NaN() : mm * 0.001f;
      std::memcpy(metric.data.data() + 4 * i, &m, 4);
    }
    raw_pub.publish(raw);
    metric_pub.publish(metric);
    info_pub.publish(cameraInfoFromFieldOfView(raw.width, raw.height, depth.getHorizontalFieldOfView(),
                                               depth.getVerticalFieldOfView(), header));
    ros::spinOnce();
  }
  depth.stop();
  depth.destroy();
  device.close();
  openni::OpenNI::shutdown();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "openni2_depth_publisher");
  return run();
}
