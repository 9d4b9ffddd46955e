#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/transform_broadcaster.h>

#include "sdf_tracker/SavePath.h"
#include "sdf_tracker/SdfTrackerConfig.h"
#include "sdf_tracker/core/io.h"
#include "sdf_tracker/core/parameters.h"
#include "sdf_tracker/core/pipeline.h"

namespace sdf_tracker_ros {

/// The node's own options (ROS plumbing), read with the tracker's settings.
struct NodeOptions {
  std::string camera_name = "camera";  ///< c_name
  bool depth_registered = false;
  std::string world_frame = "map";
  std::string odom_frame;    ///< when set, tf goes world -> odom (identity) -> camera
  std::string camera_frame;  ///< empty: the image's frame_id
  double cloud_rate_hz = 1.0;
  double mesh_rate_hz = 0.2;
  std::string trajectory_file;
  std::string mesh_file;   ///< when set, mesh.ply-style PLY written at shut-down
  std::string cloud_file;  ///< when set, surface cloud PLY written at shut-down
  std::string load_volume = "none";  ///< LoadVolume
  bool output_triangles = false;     ///< OutputTriangles: triangles.obj at shut-down
  bool output_volume = false;        ///< OutputVolume: sdf_volume.vti at shut-down
  std::string output_directory = ".";
  /// Intrinsics given explicitly (FocalLengthX/Y, CenterPointX/Y): used instead of camera_info.
  bool intrinsics_from_parameters = false;
};

/// Reads every private parameter in one place: the tracker's through the core's name table, the
/// node's own here. Throws std::invalid_argument listing every invalid or unreadable value;
/// `unknown` receives the names of private parameters nobody reads.
void readParameters(const ros::NodeHandle& pnh, sdf_tracker::Settings* settings, NodeOptions* options,
                    std::vector<std::string>* unknown);

/// The ROS layer over sdf_tracker::SdfPipeline: depth + camera_info in; tf, pose, path, status,
/// cloud, mesh and the ray-cast depth out; services to reset, save and load. Used by both the
/// node and the nodelet. Callbacks may come from several threads: the pipeline is guarded.
class TrackerServer {
 public:
  /// Throws std::invalid_argument when a parameter is invalid (the node then refuses to start).
  TrackerServer(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~TrackerServer();

 private:
  /// `synchronised_info` is null when the intrinsics come from parameters.
  void depthCallback(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& synchronised_info);
  void checkInputs(const ros::TimerEvent&);
  void publishPose(const std_msgs::Header& header, const Eigen::Isometry3d& T_W_C, const std::string& camera_frame);
  /// Extracts a map product under the lock and publishes it, only when someone listens.
  template <typename Extract, typename Convert>
  void publishMap(const ros::Publisher& publisher, Extract extract, Convert convert);
  void publishCloud(const ros::TimerEvent&);
  void publishMesh(const ros::TimerEvent&);
  void reconfigure(sdf_tracker::SdfTrackerConfig& config, uint32_t level);
  bool reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&);
  /// Runs a service's action under the lock; its text (or the exception's) becomes the message.
  bool answer(sdf_tracker::SavePath::Response& res, const std::function<std::string()>& action);
  bool saveMesh(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  bool saveVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  bool loadVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res);
  void writeTrajectory();
  std::string outputPath(const std::string& requested, const std::string& default_name) const;

  ros::NodeHandle nh_, pnh_;
  sdf_tracker::Settings settings_;
  NodeOptions options_;

  std::mutex mutex_;  ///< guards everything below
  std::unique_ptr<sdf_tracker::SdfPipeline> pipeline_;
  std::vector<sdf_tracker::io::StampedPose> trajectory_;
  nav_msgs::Path path_;
  std::string last_camera_frame_;
  ros::Time last_stamp_;
  std::optional<uint32_t> last_seq_;
  uint32_t frames_dropped_ = 0;
  uint32_t frames_processed_ = 0;
  double sum_frame_ms_ = 0.0;
  bool warned_intrinsics_ = false;

  image_transport::ImageTransport it_;
  image_transport::CameraSubscriber depth_sub_;  ///< image + camera_info, synchronised
  image_transport::Subscriber depth_only_sub_;    ///< image alone, when intrinsics are parameters
  ros::Subscriber info_watch_sub_;                ///< notes camera_info arrivals for the watchdog
  ros::Timer watchdog_timer_;
  std::string depth_topic_, info_topic_;
  ros::WallTime last_frame_wall_, last_info_wall_;
  sensor_msgs::CameraInfoConstPtr last_info_;  ///< latest camera_info, to compare with parameters
  image_transport::Publisher denoised_pub_;
  ros::Publisher pose_pub_, path_pub_, status_pub_, cloud_pub_, mesh_pub_;
  ros::ServiceServer reset_srv_, save_mesh_srv_, save_volume_srv_, load_volume_srv_;
  ros::Timer cloud_timer_, mesh_timer_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::unique_ptr<dynamic_reconfigure::Server<sdf_tracker::SdfTrackerConfig>> reconfigure_server_;
};

}  // namespace sdf_tracker_ros
