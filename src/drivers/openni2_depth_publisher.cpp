// openni2_depth_publisher: a depth driver on OpenNI 2 (openni2_camera is not packaged in Debian)
// for PrimeSense / Asus Xtion cameras and .oni recordings, publishing what openni2_launch
// publishes (see DepthCameraPublisher).
//
// Parameters: ~device_id (a device URI or a .oni file; empty: the first device),
// ~depth_mode ("VGA" or "QVGA", 30 Hz; a recording plays its own), ~depth_registration,
// ~depth_mirroring (default false), and those of DepthCameraPublisher. Streams only while someone
// subscribes.
//
// Stamps: a live camera's frames are stamped on arrival. A recording's frames carry its own
// clock: the stamps it holds (tum_to_oni writes the sequence's), or, for recordings made by
// OpenNI's Recorder (whose clock starts at 0), the playback start plus the recorded offset. A
// recording is published at its recorded pace, frame by frame; the node ends after its last frame.
// A live camera that stops is re-opened until it is back; with no camera at all the node exits
// with an error.

#include <cmath>
#include <cstdint>
#include <string>

#include <OpenNI.h>
#include <ros/ros.h>

#include "sdf_tracker/drivers/depth_camera_publisher.h"

namespace {

constexpr int kFrameTimeout_ms = 2000;
/// OpenNI's playback speed that makes a recording hand on a frame only when one is read.
constexpr float kManualPlayback = -1.0f;
constexpr double kReopenInterval_s = sdf_tracker_ros::DepthCameraPublisher::kReopenInterval_s;

class OpenNI2Driver {
 public:
  OpenNI2Driver() : camera_nh_(sdf_tracker_ros::DepthCameraPublisher::cameraNamespace()), pnh_("~"), publisher_(camera_nh_, pnh_) {
    device_id_ = pnh_.param<std::string>("device_id", "");
    depth_mode_ = pnh_.param<std::string>("depth_mode", "VGA");
    mirroring_ = pnh_.param("depth_mirroring", false);
  }

  int run() {
    if (depth_mode_ != "VGA" && depth_mode_ != "QVGA") {
      ROS_FATAL("openni2_depth_publisher: ~depth_mode must be VGA or QVGA (got \"%s\")", depth_mode_.c_str());
      return 1;
    }
    if (openni::OpenNI::initialize() != openni::STATUS_OK) {
      ROS_FATAL("openni2_depth_publisher: OpenNI 2 failed to initialise: %s", openni::OpenNI::getExtendedError());
      return 1;
    }
    int result = 1;
    if (open()) {
      result = loop();
      close();
    }
    openni::OpenNI::shutdown();
    return result;
  }

 private:
  bool open() {
    if (device_id_.empty()) {
      openni::Array<openni::DeviceInfo> devices;
      openni::OpenNI::enumerateDevices(&devices);
      if (devices.getSize() == 0) {
        ROS_FATAL("openni2_depth_publisher: no OpenNI 2 camera found (is it plugged in, and may this user open it? "
                  "a recording is played with ~device_id:=file.oni)");
        return false;
      }
    }
    if (device_.open(device_id_.empty() ? openni::ANY_DEVICE : device_id_.c_str()) != openni::STATUS_OK) {
      ROS_FATAL("openni2_depth_publisher: cannot open ~device_id \"%s\": %s", device_id_.c_str(),
                openni::OpenNI::getExtendedError());
      return false;
    }
    if (depth_.create(device_, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
      ROS_FATAL("openni2_depth_publisher: the device has no depth stream: %s", openni::OpenNI::getExtendedError());
      device_.close();
      return false;
    }
    if (device_.isFile()) {
      playback_ = device_.getPlaybackControl();
      playback_->setRepeatEnabled(false);
      // OniFile's own clock hands frames on in bursts, and a subscriber that keeps only the newest
      // frame then loses those in between: frames are read one at a time instead ("manual" speed)
      // and published at the recording's own pace (paceLikeTheRecording).
      playback_->setSpeed(kManualPlayback);
      frames_in_recording_ = playback_->getNumberOfFrames(depth_);
      if (!publisher_.useRecordingCalibration(device_id_)) {
        depth_.destroy();
        device_.close();
        return false;
      }
      ROS_INFO("openni2_depth_publisher: playing %s (%d depth frames, %dx%d)", device_id_.c_str(), frames_in_recording_,
               depth_.getVideoMode().getResolutionX(), depth_.getVideoMode().getResolutionY());
    } else if (!configureLiveCamera()) {
      depth_.destroy();
      device_.close();
      return false;
    }
    const openni::VideoMode mode = depth_.getVideoMode();
    nominal_.width = mode.getResolutionX();
    nominal_.height = mode.getResolutionY();
    nominal_.fx = nominal_.width / (2.0 * std::tan(depth_.getHorizontalFieldOfView() / 2.0));
    nominal_.fy = nominal_.height / (2.0 * std::tan(depth_.getVerticalFieldOfView() / 2.0));
    nominal_.cx = (nominal_.width - 1) / 2.0;
    nominal_.cy = (nominal_.height - 1) / 2.0;
    return true;
  }

  bool configureLiveCamera() {
    openni::VideoMode mode;
    mode.setResolution(depth_mode_ == "VGA" ? 640 : 320, depth_mode_ == "VGA" ? 480 : 240);
    mode.setFps(30);
    mode.setPixelFormat(openni::PIXEL_FORMAT_DEPTH_1_MM);
    if (depth_.setVideoMode(mode) != openni::STATUS_OK) {
      ROS_FATAL("openni2_depth_publisher: the camera refuses ~depth_mode %s (30 Hz, mm): %s", depth_mode_.c_str(),
                openni::OpenNI::getExtendedError());
      return false;
    }
    if (publisher_.registered()) {
      if (!device_.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) ||
          device_.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) != openni::STATUS_OK) {
        ROS_FATAL("openni2_depth_publisher: ~depth_registration: this camera cannot register depth to colour");
        return false;
      }
    }
    if (depth_.setMirroringEnabled(mirroring_) != openni::STATUS_OK && mirroring_) {
      ROS_FATAL("openni2_depth_publisher: ~depth_mirroring: this camera cannot mirror its depth");
      return false;
    }
    const openni::DeviceInfo& info = device_.getDeviceInfo();
    ROS_INFO("openni2_depth_publisher: %s %s (%s), depth %s at 30 Hz%s", info.getVendor(), info.getName(), info.getUri(),
             depth_mode_.c_str(), publisher_.registered() ? ", registered to colour" : "");
    return true;
  }

  void close() {
    if (streaming_) depth_.stop();
    streaming_ = false;
    depth_.destroy();
    device_.close();
  }

  int loop() {
    ros::AsyncSpinner spinner(1);
    spinner.start();
    openni::VideoFrameRef frame;
    while (ros::ok()) {
      const bool wanted = publisher_.hasSubscribers();
      if (wanted != streaming_) {
        if (wanted) {
          depth_.start();
        } else {
          depth_.stop();
        }
        streaming_ = wanted;
        ROS_INFO("openni2_depth_publisher: %s streaming", wanted ? "subscribed: start" : "no subscriber: stop");
      }
      if (!streaming_) {
        ros::WallDuration(0.01).sleep();
        continue;
      }
      int ready = -1;
      openni::VideoStream* streams[] = {&depth_};
      // In manual playback a frame is there whenever it is read.
      const bool available = playback_ != nullptr ||
                             openni::OpenNI::waitForAnyStream(streams, 1, &ready, kFrameTimeout_ms) == openni::STATUS_OK;
      if (available && depth_.readFrame(&frame) == openni::STATUS_OK && frame.isValid()) {
        if (playback_ != nullptr) paceLikeTheRecording(frame);
        publish(frame);
        if (playback_ != nullptr && frames_ >= static_cast<size_t>(frames_in_recording_)) {
          publisher_.finishRecording("openni2_depth_publisher", frames_);
          return 0;
        }
        continue;
      }
      if (playback_ != nullptr) {
        ROS_ERROR("openni2_depth_publisher: the recording stopped after %zu of %d frames", frames_,
                  frames_in_recording_);
        return 1;
      }
      ROS_ERROR("openni2_depth_publisher: no depth frame for %d ms (%s); re-opening the camera every %.0f s",
                kFrameTimeout_ms, openni::OpenNI::getExtendedError(), kReopenInterval_s);
      close();
      while (ros::ok()) {
        ros::WallDuration(kReopenInterval_s).sleep();
        if (device_.open(device_id_.empty() ? openni::ANY_DEVICE : device_id_.c_str()) == openni::STATUS_OK &&
            depth_.create(device_, openni::SENSOR_DEPTH) == openni::STATUS_OK && configureLiveCamera()) {
          ROS_INFO("openni2_depth_publisher: the camera is back");
          break;
        }
        depth_.destroy();
        device_.close();
      }
    }
    return 0;
  }

  /// Waits until this frame is as far from the recording's first frame in wall time as it was when
  /// it was recorded, so frames go out evenly at the recorded rate.
  void paceLikeTheRecording(const openni::VideoFrameRef& frame) {
    const uint64_t recorded_us = frame.getTimestamp();
    if (frames_ == 0) {
      first_frame_wall_ = ros::WallTime::now();
      first_frame_us_ = recorded_us;
      return;
    }
    const double offset_s = recorded_us >= first_frame_us_ ? (recorded_us - first_frame_us_) * 1e-6 : 0.0;
    const ros::WallDuration wait = (first_frame_wall_ + ros::WallDuration(offset_s)) - ros::WallTime::now();
    if (wait > ros::WallDuration(0.0)) wait.sleep();
  }

  ros::Time stampOf(const openni::VideoFrameRef& frame) {
    if (playback_ == nullptr) return ros::Time::now();
    const uint64_t recorded_us = frame.getTimestamp();
    if (frames_ == 0) relative_clock_start_ = recorded_us == 0 ? ros::Time::now() : ros::Time();
    ros::Time stamp;
    stamp.fromNSec(recorded_us * 1000);
    return relative_clock_start_.isZero() ? stamp : relative_clock_start_ + (stamp - ros::Time());
  }

  void publish(const openni::VideoFrameRef& frame) {
    const ros::Time stamp = stampOf(frame);
    ++frames_;
    const int stride = frame.getStrideInBytes() / static_cast<int>(sizeof(uint16_t));
    publisher_.publish(static_cast<const uint16_t*>(frame.getData()), frame.getWidth(), frame.getHeight(), stride, stamp,
                       nominal_);
  }

  ros::NodeHandle camera_nh_, pnh_;
  sdf_tracker_ros::DepthCameraPublisher publisher_;
  std::string device_id_, depth_mode_;
  bool mirroring_ = false;
  openni::Device device_;
  openni::VideoStream depth_;
  openni::PlaybackControl* playback_ = nullptr;
  int frames_in_recording_ = 0;
  ros::Time relative_clock_start_;
  ros::WallTime first_frame_wall_;  ///< when the recording's first frame went out
  uint64_t first_frame_us_ = 0;     ///< its recorded time
  sdf_tracker::PinholeCamera nominal_;
  size_t frames_ = 0;
  bool streaming_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "openni2_depth_publisher");
  return OpenNI2Driver().run();
}
