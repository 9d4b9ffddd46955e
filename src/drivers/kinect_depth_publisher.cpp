// kinect_depth_publisher: a Kinect v1 depth driver on libfreenect (freenect_camera is not packaged
// in Debian), publishing what freenect_launch publishes (see DepthCameraPublisher).
//
// Parameters: ~device_id ("#1", "#2", ... or a serial; empty: the first Kinect),
// ~depth_registration (depth in the colour camera's frame), and those of DepthCameraPublisher.
// Streams depth only while someone subscribes to it, colour (RGB, 640x480) only while someone
// subscribes to colour.
//
// Depth: the device sends 11-bit disparities; they become millimetres through libfreenect's
// depth model with the device's own zero-plane calibration when the library provides it, else
// (fakenect) with values typical of Kinect v1 units. With ~depth_registration, libfreenect's
// registered millimetre mode is used instead.
//
// Replay: under libfreenect's fakenect (FAKENECT_PATH set, and its library first on
// LD_LIBRARY_PATH, as the `fakenect` wrapper does), frames and colour images carry the
// recording's own stamps and the node ends when the recording does; a file that is incomplete is
// skipped, said by name. fakenect plays the depth as it was recorded: ~depth_registration then
// states that it was recorded registered to the colour (tum_to_fakenect's recordings are). A live
// device that stops is re-opened until it is back.

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <libfreenect.h>
#include <libfreenect_registration.h>
#include <ros/ros.h>

#include "sdf_tracker/devices/fakenect_dump.h"
#include "sdf_tracker/devices/kinect_disparity.h"
#include "sdf_tracker/drivers/depth_camera_publisher.h"

namespace {

namespace dev = sdf_tracker::devices;
constexpr double kReopenInterval_s = sdf_tracker_ros::DepthCameraPublisher::kReopenInterval_s;
/// The Kinect v1 colour camera's focal length at 640x480 in freenect_camera's nominal calibration,
/// for when no calibration states it (libfreenect does not know it).
constexpr double kNominalColourFocal_px = 525.0;

/// libfreenect's device calibration, when the library in use has it: fakenect's stand-in
/// library does not, so the function is looked up at run time rather than linked.
std::optional<dev::KinectZeroPlane> deviceZeroPlane(freenect_device* device) {
  using CopyRegistration = freenect_registration (*)(freenect_device*);
  using DestroyRegistration = int (*)(freenect_registration*);
  auto copy = reinterpret_cast<CopyRegistration>(dlsym(RTLD_DEFAULT, "freenect_copy_registration"));
  auto destroy = reinterpret_cast<DestroyRegistration>(dlsym(RTLD_DEFAULT, "freenect_destroy_registration"));
  if (copy == nullptr || destroy == nullptr) return std::nullopt;
  freenect_registration registration = copy(device);
  dev::KinectZeroPlane zero_plane;
  zero_plane.reference_distance_cm = registration.zero_plane_info.reference_distance;
  zero_plane.reference_pixel_size_cm = registration.zero_plane_info.reference_pixel_size;
  zero_plane.emitter_to_dcmos_cm = registration.zero_plane_info.dcmos_emitter_dist;
  zero_plane.const_shift = registration.const_shift;
  destroy(&registration);
  if (zero_plane.reference_pixel_size_cm <= 0.0 || zero_plane.reference_distance_cm <= 0.0) return std::nullopt;
  return zero_plane;
}

/// The mode with this format at 640x480, if the library offers it (never freenect_find_depth_mode:
/// fakenect's asserts on formats it does not know).
std::optional<freenect_frame_mode> depthMode(freenect_depth_format format) {
  for (int i = 0; i < freenect_get_depth_mode_count(); ++i) {
    const freenect_frame_mode mode = freenect_get_depth_mode(i);
    if (mode.is_valid && mode.depth_format == format && mode.resolution == FREENECT_RESOLUTION_MEDIUM) return mode;
  }
  return std::nullopt;
}

/// 640x480 RGB, if the library offers it (never freenect_find_video_mode, for the same reason).
std::optional<freenect_frame_mode> colourMode() {
  for (int i = 0; i < freenect_get_video_mode_count(); ++i) {
    const freenect_frame_mode mode = freenect_get_video_mode(i);
    if (mode.is_valid && mode.video_format == FREENECT_VIDEO_RGB && mode.resolution == FREENECT_RESOLUTION_MEDIUM) {
      return mode;
    }
  }
  return std::nullopt;
}

class KinectDriver {
 public:
  KinectDriver() : camera_nh_(sdf_tracker_ros::DepthCameraPublisher::cameraNamespace()), pnh_("~"), publisher_(camera_nh_, pnh_) {
    device_id_ = pnh_.param<std::string>("device_id", "");
    if (const char* path = std::getenv("FAKENECT_PATH")) replay_path_ = path;
  }

  int run() {
    if (freenect_init(&context_, nullptr) < 0) {
      ROS_FATAL("kinect_depth_publisher: libfreenect failed to initialise (is libusb working?)");
      return 1;
    }
    freenect_select_subdevices(context_, FREENECT_DEVICE_CAMERA);
    if (!replay_path_.empty()) {
      try {
        recording_ = dev::readFakenectFrames(replay_path_);
      } catch (const std::exception& e) {
        ROS_FATAL("kinect_depth_publisher: FAKENECT_PATH=%s: %s", replay_path_.c_str(), e.what());
        return 1;
      }
      ROS_INFO("kinect_depth_publisher: replaying the fakenect recording %s (%zu depth frames, %zu colour images)%s",
               std::filesystem::absolute(replay_path_).c_str(), recording_.depth.size(), recording_.colour.size(),
               publisher_.registered() ? ", its depth registered to the colour (~depth_registration)" : "");
      auto incomplete = [](const std::vector<dev::FakenectFrame>& frames) {
        return static_cast<long>(std::count_if(frames.begin(), frames.end(),
                                               [](const dev::FakenectFrame& f) { return !f.problem.empty(); }));
      };
      if (incomplete(recording_.depth) + incomplete(recording_.colour) > 0) {
        ROS_WARN("kinect_depth_publisher: %ld of the recording's depth frames and %ld of its colour images are "
                 "incomplete and will be skipped when fakenect plays them",
                 incomplete(recording_.depth), incomplete(recording_.colour));
      }
      if (!publisher_.useRecordingCalibration(replay_path_)) {
        freenect_shutdown(context_);
        return 1;
      }
    }
    if (!open()) {
      freenect_shutdown(context_);
      return 1;
    }
    const int result = loop();
    close();
    freenect_shutdown(context_);
    return result;
  }

 private:
  bool open() {
    const int devices = freenect_num_devices(context_);
    if (devices < 1) {
      ROS_FATAL("kinect_depth_publisher: no Kinect found (libfreenect sees no device; is it plugged in and powered, "
                "and may this user open it? see /lib/udev/rules.d/60-libfreenect0.5.rules)");
      return false;
    }
    int status = -1;
    if (device_id_.empty() || device_id_[0] == '#') {
      const int index = device_id_.empty() ? 0 : std::atoi(device_id_.c_str() + 1) - 1;
      if (index < 0 || index >= devices) {
        ROS_FATAL("kinect_depth_publisher: ~device_id \"%s\": there are %d Kinects (#1 to #%d)", device_id_.c_str(),
                  devices, devices);
        return false;
      }
      status = freenect_open_device(context_, &device_, index);
    } else {
      status = freenect_open_device_by_camera_serial(context_, &device_, device_id_.c_str());
    }
    if (status < 0) {
      ROS_FATAL("kinect_depth_publisher: cannot open the Kinect \"%s\" (libfreenect error %d)",
                device_id_.empty() ? "#1" : device_id_.c_str(), status);
      return false;
    }
    // A recording's depth is played as recorded; a live device registers it when asked to.
    const bool register_depth = publisher_.registered() && replay_path_.empty();
    const freenect_depth_format format = register_depth ? FREENECT_DEPTH_REGISTERED : FREENECT_DEPTH_11BIT;
    const std::optional<freenect_frame_mode> mode = depthMode(format);
    if (!mode) {
      ROS_FATAL("kinect_depth_publisher: this libfreenect offers no %s depth mode",
                register_depth ? "registered" : "11-bit");
      return false;
    }
    freenect_set_depth_mode(device_, *mode);
    mode_ = *mode;
    const std::optional<dev::KinectZeroPlane> device_zero_plane = deviceZeroPlane(device_);
    const dev::KinectZeroPlane zero_plane = device_zero_plane.value_or(dev::KinectZeroPlane{});
    disparity_ = dev::KinectDisparityTable(zero_plane);
    nominal_.width = mode->width;
    nominal_.height = mode->height;
    nominal_.fx = nominal_.fy = zero_plane.focalLength640_px() * mode->width / 640.0;
    nominal_.cx = (mode->width - 1) / 2.0;
    nominal_.cy = (mode->height - 1) / 2.0;
    nominal_colour_ = nominal_;
    nominal_colour_.fx = nominal_colour_.fy = kNominalColourFocal_px * mode->width / 640.0;
    if (publisher_.registered()) nominal_ = nominal_colour_;  // the depth is seen from the colour camera
    colour_mode_ = colourMode();
    if (colour_mode_) {
      freenect_set_video_mode(device_, *colour_mode_);
    } else {
      ROS_WARN("kinect_depth_publisher: this libfreenect offers no 640x480 RGB mode: depth only");
    }
    freenect_set_user(device_, this);
    freenect_set_depth_callback(device_, &KinectDriver::onDepth);
    freenect_set_video_callback(device_, &KinectDriver::onColour);
    ROS_INFO("kinect_depth_publisher: Kinect open, %dx%d %s depth, %s calibration", mode->width, mode->height,
             publisher_.registered() ? "registered" : "11-bit",
             device_zero_plane ? "the device's" : "typical zero-plane");
    return true;
  }

  void close() {
    if (device_ == nullptr) return;
    if (streaming_) freenect_stop_depth(device_);
    if (streaming_colour_) freenect_stop_video(device_);
    streaming_ = streaming_colour_ = false;
    freenect_close_device(device_);
    device_ = nullptr;
  }

  int loop() {
    ros::AsyncSpinner spinner(1);
    spinner.start();
    while (ros::ok()) {
      const bool wanted = publisher_.hasSubscribers();
      if (wanted != streaming_) {
        (wanted ? freenect_start_depth : freenect_stop_depth)(device_);
        streaming_ = wanted;
        ROS_INFO("kinect_depth_publisher: %s streaming", wanted ? "subscribed: start" : "no subscriber: stop");
      }
      // fakenect passes over a colour image while colour is stopped: a recording plays colour with
      // its depth, so that every image it hands on is the one INDEX.txt lists next.
      const bool colour_wanted =
          colour_mode_.has_value() && (replay_path_.empty() ? publisher_.hasColourSubscribers() : streaming_);
      if (colour_wanted != streaming_colour_) {
        (colour_wanted ? freenect_start_video : freenect_stop_video)(device_);
        streaming_colour_ = colour_wanted;
      }
      // A recording advances with every call: only while streaming, so no frame is skipped.
      if (!replay_path_.empty() && !streaming_) {
        ros::WallDuration(0.01).sleep();
        continue;
      }
      timeval timeout{0, 100000};
      if (freenect_process_events_timeout(context_, &timeout) >= 0) continue;
      if (!replay_path_.empty()) {
        publisher_.finishRecording("kinect_depth_publisher", frames_);
        return 0;
      }
      ROS_ERROR("kinect_depth_publisher: lost the Kinect after %zu frames; trying to re-open it every %.0f s",
                frames_, kReopenInterval_s);
      close();
      while (ros::ok() && device_ == nullptr) {
        ros::WallDuration(kReopenInterval_s).sleep();
        if (freenect_num_devices(context_) > 0 && open()) ROS_INFO("kinect_depth_publisher: the Kinect is back");
      }
    }
    return 0;
  }

  static void onDepth(freenect_device* device, void* data, uint32_t /*device_timestamp*/) {
    static_cast<KinectDriver*>(freenect_get_user(device))->publish(static_cast<const uint16_t*>(data));
  }

  static void onColour(freenect_device* device, void* rgb, uint32_t /*device_timestamp*/) {
    static_cast<KinectDriver*>(freenect_get_user(device))->publishColour(static_cast<const uint8_t*>(rgb));
  }

  /// The recording's next file of `frames`, if it is whole (fakenect hands on whatever the file
  /// held: reading a whole image from a short one would overrun); its stamp goes to `stamp`.
  bool nextRecorded(const std::vector<dev::FakenectFrame>& frames, size_t* next, const char* what, ros::Time* stamp) {
    if (*next >= frames.size()) {
      ROS_ERROR_ONCE("kinect_depth_publisher: the recording plays more %s than its INDEX.txt lists", what);
      return false;
    }
    const dev::FakenectFrame& frame = frames[(*next)++];
    if (!frame.problem.empty()) {
      ROS_ERROR("kinect_depth_publisher: skipped the recording's %s %s: it %s", what, frame.file.c_str(),
                frame.problem.c_str());
      return false;
    }
    *stamp = ros::Time(frame.time_s);
    return true;
  }

  void publishColour(const uint8_t* rgb) {
    ros::Time stamp = ros::Time::now();
    if (!replay_path_.empty() && !nextRecorded(recording_.colour, &colour_frames_, "colour images", &stamp)) return;
    if (publisher_.hasColourSubscribers()) {
      publisher_.publishColour(rgb, colour_mode_->width, colour_mode_->height, colour_mode_->width * 3, stamp,
                               nominal_colour_);
    }
  }

  void publish(const uint16_t* data) {
    ros::Time stamp = ros::Time::now();
    if (!replay_path_.empty()) {
      if (!nextRecorded(recording_.depth, &frames_, "depth frames", &stamp)) return;
    } else {
      ++frames_;
    }
    const size_t n = static_cast<size_t>(mode_.width) * mode_.height;
    depth_mm_.resize(n);
    if (mode_.depth_format == FREENECT_DEPTH_11BIT) {
      for (size_t i = 0; i < n; ++i) depth_mm_[i] = disparity_.toMillimetres(data[i]);
      data = depth_mm_.data();
    }
    publisher_.publish(data, mode_.width, mode_.height, mode_.width, stamp, nominal_);
  }

  ros::NodeHandle camera_nh_, pnh_;
  sdf_tracker_ros::DepthCameraPublisher publisher_;
  std::string device_id_, replay_path_;
  dev::FakenectFrames recording_;
  freenect_context* context_ = nullptr;
  freenect_device* device_ = nullptr;
  freenect_frame_mode mode_{};
  std::optional<freenect_frame_mode> colour_mode_;
  dev::KinectDisparityTable disparity_;
  sdf_tracker::PinholeCamera nominal_, nominal_colour_;
  std::vector<uint16_t> depth_mm_;
  size_t frames_ = 0, colour_frames_ = 0;
  bool streaming_ = false, streaming_colour_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "kinect_depth_publisher");
  return KinectDriver().run();
}
