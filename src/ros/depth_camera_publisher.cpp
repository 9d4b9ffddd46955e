#include "sdf_tracker/ros/depth_camera_publisher.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2/LinearMath/Quaternion.h>

#include "sdf_tracker/devices/recording.h"

namespace sdf_tracker_ros {

namespace {

/// rgbd_launch's layout of a Kinect-like camera: depth 2 cm, colour 4.5 cm to the right of the
/// link, optical frames z forward, x right, y down.
constexpr double kDepthOffset_m = -0.02;
constexpr double kRgbOffset_m = -0.045;

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child, double y_m,
                                          bool optical) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.y = y_m;
  tf2::Quaternion q;
  if (optical) {
    q.setRPY(-M_PI / 2, 0.0, -M_PI / 2);
  } else {
    q.setRPY(0.0, 0.0, 0.0);
  }
  t.transform.rotation.x = q.x();
  t.transform.rotation.y = q.y();
  t.transform.rotation.z = q.z();
  t.transform.rotation.w = q.w();
  return t;
}

}  // namespace

DepthCameraPublisher::DepthCameraPublisher(const ros::NodeHandle& camera_nh, const ros::NodeHandle& pnh)
    : camera_nh_(camera_nh), it_(camera_nh) {
  std::string camera = camera_nh.getNamespace();
  camera = camera.substr(camera.find_last_of('/') + 1);
  registered_ = pnh.param("depth_registration", false);
  frame_id_ = registered_ ? pnh.param<std::string>("rgb_frame_id", camera + "_rgb_optical_frame")
                          : pnh.param<std::string>("depth_frame_id", camera + "_depth_optical_frame");
  const std::string url = pnh.param<std::string>("depth_camera_info_url", "");
  url_given_ = !url.empty();
  const std::string prefix = registered_ ? "depth_registered" : "depth";
  calibration_ = std::make_unique<camera_info_manager::CameraInfoManager>(ros::NodeHandle(camera_nh, prefix),
                                                                          "depth", url);
  raw_pub_ = it_.advertise(prefix + "/image_raw", 1);
  metric_pub_ = it_.advertise(prefix + "/image", 1);
  info_pub_ = camera_nh_.advertise<sensor_msgs::CameraInfo>(prefix + "/camera_info", 1);
  if (pnh.param("publish_tf", true)) publishFrames(camera);
}

void DepthCameraPublisher::publishFrames(const std::string& camera) {
  const std::string link = camera + "_link";
  static_tf_.sendTransform(std::vector<geometry_msgs::TransformStamped>{
      transform(link, camera + "_depth_frame", kDepthOffset_m, false),
      transform(camera + "_depth_frame", camera + "_depth_optical_frame", 0.0, true),
      transform(link, camera + "_rgb_frame", kRgbOffset_m, false),
      transform(camera + "_rgb_frame", camera + "_rgb_optical_frame", 0.0, true)});
}

ros::NodeHandle DepthCameraPublisher::cameraNamespace() {
  return ros::this_node::getNamespace() == "/" ? ros::NodeHandle("camera") : ros::NodeHandle();
}

bool DepthCameraPublisher::hasSubscribers() const {
  return raw_pub_.getNumSubscribers() > 0 || metric_pub_.getNumSubscribers() > 0 || info_pub_.getNumSubscribers() > 0;
}

void DepthCameraPublisher::useRecordingCalibration(const std::string& recording) {
  if (url_given_) return;
  const std::string file = sdf_tracker::devices::calibrationFileFor(recording);
  if (std::filesystem::exists(file) && calibration_->loadCameraInfo("file://" + std::filesystem::absolute(file).string())) {
    ROS_INFO("depth intrinsics from the recording's calibration %s", file.c_str());
  } else {
    ROS_WARN("the recording has no calibration (%s not found): camera_info holds the device's nominal intrinsics; "
             "set ~depth_camera_info_url to use another", file.c_str());
  }
}

sensor_msgs::CameraInfo DepthCameraPublisher::cameraInfo(int width, int height,
                                                         const sdf_tracker::PinholeCamera& nominal) {
  if (calibration_->isCalibrated()) {
    sensor_msgs::CameraInfo info = calibration_->getCameraInfo();
    if (static_cast<int>(info.width) == width && static_cast<int>(info.height) == height) return info;
    if (!warned_size_) {
      ROS_WARN("the depth calibration is for %ux%u but the camera sends %dx%d: using the nominal intrinsics",
               info.width, info.height, width, height);
      warned_size_ = true;
    }
  }
  const sdf_tracker::PinholeCamera c = nominal.width == width ? nominal : nominal.scaledTo(width, height);
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

void DepthCameraPublisher::publish(const uint16_t* depth_mm, int width, int height, int stride, const ros::Time& stamp,
                                   const sdf_tracker::PinholeCamera& nominal) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = frame_id_;
  sensor_msgs::CameraInfo info = cameraInfo(width, height, nominal);
  info.header = header;

  const auto raw = boost::make_shared<sensor_msgs::Image>();
  raw->header = header;
  raw->width = width;
  raw->height = height;
  raw->encoding = sensor_msgs::image_encodings::TYPE_16UC1;
  raw->step = width * sizeof(uint16_t);
  raw->data.resize(static_cast<size_t>(raw->step) * height);
  const auto metric = boost::make_shared<sensor_msgs::Image>();
  metric->header = header;
  metric->width = width;
  metric->height = height;
  metric->encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  metric->step = width * sizeof(float);
  metric->data.resize(static_cast<size_t>(metric->step) * height);
  auto* raw_out = reinterpret_cast<uint16_t*>(raw->data.data());
  auto* metric_out = reinterpret_cast<float*>(metric->data.data());
  for (int v = 0; v < height; ++v) {
    const uint16_t* row = depth_mm + static_cast<size_t>(v) * stride;
    for (int u = 0; u < width; ++u) {
      const uint16_t mm = row[u];
      raw_out[static_cast<size_t>(v) * width + u] = mm;
      metric_out[static_cast<size_t>(v) * width + u] = mm == 0 ? std::numeric_limits<float>::quiet_NaN() : mm * 0.001f;
    }
  }
  raw_pub_.publish(raw);
  metric_pub_.publish(metric);
  info_pub_.publish(info);
}

}  // namespace sdf_tracker_ros
