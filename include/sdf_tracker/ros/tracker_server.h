#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include "sdf_tracker/SdfTrackerConfig.h"
#include "sdf_tracker/TrackingStatus.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/ros/map_publisher.h"
#include "sdf_tracker/ros/map_services.h"
#include "sdf_tracker/ros/node_diagnostics.h"
#include "sdf_tracker/ros/parameters.h"
#include "sdf_tracker/ros/pose_broadcaster.h"
#include "sdf_tracker/ros/tracker_state.h"

namespace sdf_tracker_ros {

/// The ROS node over sdf_tracker::SdfPipeline, used by both the node and the nodelet. It only
/// composes its parts: frames in (a one-slot mailbox drained by a frame thread: the newest frame
/// is always the next one tracked, and every frame replaced unprocessed is counted as dropped;
/// with Colour on, the colour images in a short cache, each depth frame fused with the one
/// nearest in stamp when it is fused, after tracking, never waiting for one),
/// PoseBroadcaster (tf, ~pose, ~path; nothing while the camera is searched for in the map),
/// MapPublisher (~cloud, ~mesh on their own thread), MapServices, pose requests (~initialpose),
/// NodeDiagnostics (/diagnostics) and live reconfiguration through the parameter table.
class TrackerServer {
 public:
  /// Throws std::invalid_argument when a parameter is invalid (the node then refuses to start).
  TrackerServer(ros::NodeHandle nh, ros::NodeHandle pnh);
  /// finish(), unless it was called.
  ~TrackerServer();

  /// Stops taking frames, prints the run's summary and writes the files the parameters ask for
  /// (on stdout and stderr: rosconsole may be gone at shut-down). False when a file could not be
  /// written. Once only; later calls return the first one's answer.
  bool finish();

 private:
  struct Frame {
    sensor_msgs::ImageConstPtr image;
    sensor_msgs::CameraInfoConstPtr info;  ///< null when the intrinsics come from parameters
  };

  void onFrame(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void onColour(const sensor_msgs::ImageConstPtr& image);
  /// Subscribes to the colour images (Colour on) or lets them go (off).
  void updateColourSubscription(bool colour_on);
  /// The cached colour image nearest to `stamp`, within kMaxColourGap_s, as RGB; nothing when
  /// there is none (or it cannot be read: said in the log, throttled).
  std::optional<sdf_tracker::ColourImage> colourAt(const ros::Time& stamp);
  void frameLoop();
  void process(const Frame& frame);
  /// The camera of `frame` (camera_info or the parameters); throws std::invalid_argument with the
  /// reason it cannot be used.
  sdf_tracker::PinholeCamera cameraFor(const Frame& frame);
  /// Has the pipeline search for the camera from the pose on ~initialpose (images of
  /// `image_frame`); says in the log what it did, or why the request is ignored. Called by the
  /// frame thread with the state's lock held.
  void applyPoseRequest(const geometry_msgs::PoseWithCovarianceStamped& request, const std::string& image_frame);
  /// ~status, and the same to the diagnostics.
  void publishStatus(const sdf_tracker::TrackingStatus& status);
  void checkInputs(const ros::TimerEvent&);
  void reconfigure(sdf_tracker::SdfTrackerConfig& config, uint32_t level);

  ros::NodeHandle nh_, pnh_;
  NodeOptions options_;
  /// FocalLength*, CenterPoint*, ImageWidth/Height; the tracker's configuration itself lives
  /// only in the pipeline.
  sdf_tracker::CameraSettings camera_settings_;
  TrackerState state_;

  // Frames in.
  image_transport::ImageTransport it_;
  image_transport::CameraSubscriber depth_sub_;  ///< image + camera_info, synchronised
  image_transport::Subscriber depth_only_sub_;    ///< image alone, when intrinsics are parameters
  /// Until the first frame is tracked: notes image and camera_info arrivals, so the watchdog can say
  /// which one is missing (images are not deserialised).
  ros::Subscriber image_watch_sub_, info_watch_sub_;
  /// ~initialpose (rviz's "2D Pose Estimate" through the launch files' remapping): the latest
  /// request waits in pending_pose_request_ for the next frame.
  ros::Subscriber initial_pose_sub_;
  std::string depth_topic_, info_topic_;
  image_transport::Subscriber colour_sub_;
  std::string colour_topic_;
  std::mutex mailbox_mutex_;  ///< guards the members down to stopping_
  std::condition_variable mailbox_changed_;
  std::optional<Frame> pending_;
  /// The latest colour images, oldest first (kColourCache of them at most).
  std::deque<sensor_msgs::ImageConstPtr> colour_cache_;
  uint32_t colour_received_ = 0;
  std::optional<geometry_msgs::PoseWithCovarianceStamped> pending_pose_request_;
  /// The last request received, and when: the same pose again within kRepeatedRequest_s is a
  /// repeat (a burst from a script, a latched topic), not a new request to verify from scratch.
  std::optional<geometry_msgs::PoseWithCovarianceStamped> last_pose_request_;
  ros::WallTime last_pose_request_wall_;
  uint32_t frames_received_ = 0;
  uint32_t frames_dropped_ = 0;
  ros::WallTime last_image_wall_, last_info_wall_;
  sensor_msgs::CameraInfoConstPtr last_info_;  ///< latest camera_info, to compare with parameters
  bool stopping_ = false;
  std::optional<bool> finished_;  ///< finish()'s answer, once it ran
  ros::Timer watchdog_timer_;

  // Used by the frame thread only.
  std::unique_ptr<PoseBroadcaster> poses_;
  ros::Publisher status_pub_;
  image_transport::Publisher denoised_pub_;
  ros::Time last_stamp_;
  std::vector<double> frame_ms_;  ///< the node's whole cost of each processed frame
  /// The log has said once where the intrinsics come from when that deserves a word.
  bool questioned_intrinsics_ = false;
  /// The camera last said in the log (said again when it changes).
  std::optional<sdf_tracker::PinholeCamera> announced_camera_;
  /// Tracking failed kLostAfterFailedFrames in a row after the camera was tracked (~status lost).
  bool lost_ = false;
  /// The camera's pose is not known (a loaded map, ~relocalise): it is searched for, not lost.
  bool searching_ = false;
  uint32_t frames_coloured_ = 0;
  /// Why the frame being processed was not fused with its colour image (for the diagnostics).
  std::string colour_problem_;

  std::unique_ptr<NodeDiagnostics> diagnostics_;
  std::unique_ptr<MapServices> services_;
  std::unique_ptr<MapPublisher> map_publisher_;
  std::unique_ptr<dynamic_reconfigure::Server<sdf_tracker::SdfTrackerConfig>> reconfigure_server_;
  std::thread frame_thread_;  ///< last: starts once everything above exists
};

}  // namespace sdf_tracker_ros
