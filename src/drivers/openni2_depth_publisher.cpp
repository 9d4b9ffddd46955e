// openni2_depth_publisher: a depth driver on OpenNI 2 (openni2_camera is not packaged in Debian)
// for PrimeSense / Asus Xtion cameras and .oni recordings, publishing what openni2_launch
// publishes (see DepthCameraPublisher).
//
// Parameters: ~device_id (a device URI or a .oni file; empty: the first device),
// ~depth_mode ("VGA" or "QVGA", 30 Hz; a recording plays its own), ~depth_registration,
// ~depth_mirroring (default false), and those of DepthCameraPublisher. Streams only while someone
// subscribes. A camera with a colour sensor, or a recording with a colour stream, also publishes
// colour (RGB at the depth's resolution, 30 Hz) while someone subscribes to it; a recording plays
// its colour with its depth, in the order recorded.
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
    const bool has_colour = device_.hasSensor(openni::SENSOR_COLOR);
    if (has_colour && colour_.create(device_, openni::SENSOR_COLOR) != openni::STATUS_OK) {
      ROS_WARN("openni2_depth_publisher: the device's colour stream cannot be opened (%s): depth only",
               openni::OpenNI::getExtendedError());
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
        close();
        return false;
      }
      ROS_INFO("openni2_depth_publisher: playing %s (%d depth frames, %dx%d%s)", device_id_.c_str(),
               frames_in_recording_, depth_.getVideoMode().getResolutionX(), depth_.getVideoMode().getResolutionY(),
               colour_.isValid() ? ", with colour" : "");
    } else if (!configureLiveCamera()) {
      close();
      return false;
    }
    nominal_ = nominalOf(depth_);
    if (colour_.isValid()) nominal_colour_ = nominalOf(colour_);
    return true;
  }

  /// The intrinsics a stream's video mode and field of view state (principal point centred).
  static sdf_tracker::PinholeCamera nominalOf(openni::VideoStream& stream) {
    const openni::VideoMode mode = stream.getVideoMode();
    sdf_tracker::PinholeCamera camera;
    camera.width = mode.getResolutionX();
    camera.height = mode.getResolutionY();
    camera.fx = camera.width / (2.0 * std::tan(stream.getHorizontalFieldOfView() / 2.0));
    camera.fy = camera.height / (2.0 * std::tan(stream.getVerticalFieldOfView() / 2.0));
    camera.cx = (camera.width - 1) / 2.0;
    camera.cy = (camera.height - 1) / 2.0;
    return camera;
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
    if (colour_.isValid()) {
      openni::VideoMode colour_mode = mode;
      colour_mode.setPixelFormat(openni::PIXEL_FORMAT_RGB888);
      if (colour_.setVideoMode(colour_mode) != openni::STATUS_OK) {
        ROS_WARN("openni2_depth_publisher: the camera refuses colour at %s (30 Hz, RGB): %s; depth only",
                 depth_mode_.c_str(), openni::OpenNI::getExtendedError());
        colour_.destroy();
      }
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
    ROS_INFO("openni2_depth_publisher: %s %s (%s), depth %s at 30 Hz%s%s", info.getVendor(), info.getName(),
             info.getUri(), depth_mode_.c_str(), publisher_.registered() ? ", registered to colour" : "",
             colour_.isValid() ? ", colour" : "");
    return true;
  }

  void close() {
    if (streaming_) depth_.stop();
    if (streaming_colour_) colour_.stop();
    streaming_ = streaming_colour_ = false;
    colour_.destroy();
    depth_.destroy();
    device_.close();
  }

  /// Starts and stops the streams as subscribers come and go. A recording plays its colour
  /// whenever it plays its depth, so that the two stay in the order they were recorded.
  void followSubscribers() {
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
    const bool colour_wanted =
        colour_.isValid() && (playback_ != nullptr ? streaming_ : publisher_.hasColourSubscribers());
    if (colour_wanted != streaming_colour_) {
      if (colour_wanted) {
        colour_.start();
      } else {
        colour_.stop();
      }
      streaming_colour_ = colour_wanted;
    }
  }

  int loop() {
    ros::AsyncSpinner spinner(1);
    spinner.start();
    openni::VideoFrameRef frame;
    while (ros::ok()) {
      followSubscribers();
      if (!streaming_ && !streaming_colour_) {
        ros::WallDuration(0.01).sleep();
        continue;
      }
      openni::VideoStream* streams[2];
      int count = 0;
      if (streaming_) streams[count++] = &depth_;
      if (streaming_colour_) streams[count++] = &colour_;
      // In manual playback, waiting hands on the recording's next frame, of whichever stream.
      int ready = -1;
      const bool available =
          openni::OpenNI::waitForAnyStream(streams, count, &ready, kFrameTimeout_ms) == openni::STATUS_OK;
      openni::VideoStream* stream = available ? streams[ready] : nullptr;
      if (stream != nullptr && stream->readFrame(&frame) == openni::STATUS_OK && frame.isValid()) {
        if (playback_ != nullptr) paceLikeTheRecording(frame);
        if (stream == &colour_) {
          if (publisher_.hasColourSubscribers()) publishColour(frame);
          continue;
        }
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
      ROS_ERROR("openni2_depth_publisher: no frame for %d ms (%s); re-opening the camera every %.0f s",
                kFrameTimeout_ms, openni::OpenNI::getExtendedError(), kReopenInterval_s);
      close();
      while (ros::ok()) {
        ros::WallDuration(kReopenInterval_s).sleep();
        if (device_.open(device_id_.empty() ? openni::ANY_DEVICE : device_id_.c_str()) == openni::STATUS_OK &&
            depth_.create(device_, openni::SENSOR_DEPTH) == openni::STATUS_OK &&
            (!device_.hasSensor(openni::SENSOR_COLOR) || colour_.create(device_, openni::SENSOR_COLOR) == openni::STATUS_OK) &&
            configureLiveCamera()) {
          ROS_INFO("openni2_depth_publisher: the camera is back");
          break;
        }
        close();
      }
    }
    return 0;
  }

  /// Waits until this frame is as far from the recording's first frame in wall time as it was when
  /// it was recorded, so frames go out evenly at the recorded rate.
  void paceLikeTheRecording(const openni::VideoFrameRef& frame) {
    const uint64_t recorded_us = frame.getTimestamp();
    if (first_frame_wall_.isZero()) {
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
    if (!clock_started_) {
      relative_clock_start_ = recorded_us == 0 ? ros::Time::now() : ros::Time();
      clock_started_ = true;
    }
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

  void publishColour(const openni::VideoFrameRef& frame) {
    publisher_.publishColour(static_cast<const uint8_t*>(frame.getData()), frame.getWidth(), frame.getHeight(),
                             frame.getStrideInBytes(), stampOf(frame), nominal_colour_);
  }

  ros::NodeHandle camera_nh_, pnh_;
  sdf_tracker_ros::DepthCameraPublisher publisher_;
  std::string device_id_, depth_mode_;
  bool mirroring_ = false;
  openni::Device device_;
  openni::VideoStream depth_, colour_;
  openni::PlaybackControl* playback_ = nullptr;
  int frames_in_recording_ = 0;
  bool clock_started_ = false;
  ros::Time relative_clock_start_;
  ros::WallTime first_frame_wall_;  ///< when the recording's first frame went out
  uint64_t first_frame_us_ = 0;     ///< its recorded time
  sdf_tracker::PinholeCamera nominal_, nominal_colour_;
  size_t frames_ = 0;
  bool streaming_ = false, streaming_colour_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "openni2_depth_publisher");
  return OpenNI2Driver().run();
}
