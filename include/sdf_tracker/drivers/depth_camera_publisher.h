#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <camera_info_manager/camera_info_manager.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "sdf_tracker/camera/camera.h"

namespace sdf_tracker_ros {

/// The output side every depth driver of this package shares, named as openni2_launch and
/// freenect_launch name theirs (REP 118), in the camera's namespace (e.g. "camera"):
///   depth/image_raw (16UC1, mm, 0 = no data), depth/image (32FC1, m, NaN = no data),
///   depth/camera_info; with ~depth_registration, the same under depth_registered/ in the colour
///   camera's optical frame;
///   for a camera or recording with colour: rgb/image_raw and rgb/image_color (both rgb8, one
///   message), rgb/camera_info, in the colour camera's optical frame;
///   on /tf_static (~publish_tf): <camera>_link -> <camera>_depth_frame ->
///   <camera>_depth_optical_frame and the <camera>_rgb_* twin, as rgbd_launch lays them out.
/// camera_info comes from ~depth_camera_info_url (~rgb_camera_info_url) (camera_info_manager) when
/// it holds a calibration for the image size, else from the driver's nominal intrinsics.
class DepthCameraPublisher {
 public:
  /// camera_nh: the camera's namespace; pnh: the driver's private parameters.
  DepthCameraPublisher(const ros::NodeHandle& camera_nh, const ros::NodeHandle& pnh);
  /// The camera's namespace for a driver node: the node's own (the launch files start drivers in
  /// <group ns="camera">), or "camera" for a driver started in the root namespace.
  static ros::NodeHandle cameraNamespace();

  /// A live camera that stops sending is re-opened this often until it is back.
  static constexpr double kReopenInterval_s = 1.0;

  bool registered() const { return registered_; }
  /// Someone listens to one of the depth topics: drivers stream only then, as openni2_camera does.
  bool hasSubscribers() const;
  /// Someone listens to one of the colour topics.
  bool hasColourSubscribers() const;
  /// A replayed recording brings its own calibrations (devices::calibrationFileFor); used unless
  /// ~depth_camera_info_url (~rgb_camera_info_url) is set. Says which intrinsics are in use; false
  /// (after saying why) when the recording has a calibration file that cannot be read.
  bool useRecordingCalibration(const std::string& recording);

  /// A replayed recording has ended: says so and gives subscribers time to take the last frames
  /// before the driver exits (and, with required="true", ends the launch).
  void finishRecording(const char* driver, size_t frames);

  /// One frame: `height` rows of `width` depths in mm, `stride` values apart.
  void publish(const uint16_t* depth_mm, int width, int height, int stride, const ros::Time& stamp,
               const sdf_tracker::PinholeCamera& nominal);
  /// One colour image: `height` rows of `width` RGB pixels, `stride_bytes` apart. `nominal`: the
  /// colour camera's intrinsics when no calibration states them.
  void publishColour(const uint8_t* rgb, int width, int height, int stride_bytes, const ros::Time& stamp,
                     const sdf_tracker::PinholeCamera& nominal);

 private:
  /// A camera's calibration from its ~<name>_camera_info_url, and whether the user gave one.
  struct Calibration {
    std::unique_ptr<camera_info_manager::CameraInfoManager> manager;
    bool url_given = false;
    bool warned_size = false;
  };
  static Calibration calibration(const ros::NodeHandle& nh, const std::string& camera, const std::string& url);
  /// Loads the recording's calibration file of `camera` unless a URL was given; false when it
  /// exists and cannot be read.
  static bool loadRecordingCalibration(Calibration* calibration, const std::string& file, const char* camera,
                                       bool warn_if_missing);
  static sensor_msgs::CameraInfo cameraInfo(Calibration* calibration, const char* camera, int width, int height,
                                            const sdf_tracker::PinholeCamera& nominal);
  void publishFrames(const std::string& camera);

  static constexpr double kLingerAfterRecording_s = 1.0;

  bool registered_ = false;
  std::string frame_id_, colour_frame_id_;
  image_transport::ImageTransport it_;
  image_transport::Publisher raw_pub_, metric_pub_, colour_raw_pub_, colour_pub_;
  ros::Publisher info_pub_, colour_info_pub_;
  Calibration depth_calibration_, colour_calibration_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
};

}  // namespace sdf_tracker_ros
