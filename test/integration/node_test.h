// The fixture of the node's rostest (node.test): a live sdf_tracker_node fed synthetic frames
// in lock-step with its ~status. Shared by test_node.cpp and test_node_services.cpp.
#pragma once

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <tuple>

#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <std_srvs/Empty.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include "sdf_tracker/SavePath.h"
#include "sdf_tracker/SaveRegion.h"
#include "sdf_tracker/TrackingStatus.h"
#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/io/mesh_file.h"
#include "sdf_tracker/io/sdfmap_file.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/sim/synthetic.h"

namespace st = sdf_tracker;

namespace node_test {

// The node and the offline pipeline see the same frames; they may differ only by float order.
constexpr double kMaxAteDifference_m = 0.01;
constexpr double kStatusTimeout_s = 20.0;
constexpr double kResend_s = 2.0;
/// The camera of every synthetic frame the tests send.
const st::PinholeCamera kQvga = st::PinholeCamera::tumFreiburg1().scaledTo(320, 240);

class NodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    image_pub_ = nh_.advertise<sensor_msgs::Image>("camera/depth/image", 5);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("camera/depth/camera_info", 5);
    status_sub_ = nh_.subscribe("sdf_tracker/status", 50, &NodeTest::onStatus, this);
    pose_sub_ = nh_.subscribe("sdf_tracker/pose", 50, &NodeTest::onPose, this);
    path_sub_ = nh_.subscribe("sdf_tracker/path", 5, &NodeTest::onPath, this);
    cloud_sub_ = nh_.subscribe("sdf_tracker/cloud", 1, &NodeTest::onCloud, this);
    spinner_.start();
    ASSERT_TRUE(ros::service::waitForService("sdf_tracker/save_mesh", ros::Duration(60.0)));
    // Both directions: the node hears our frames, and we hear its status and pose.
    for (int i = 0; i < 100 && (image_pub_.getNumSubscribers() == 0 || info_pub_.getNumSubscribers() == 0 ||
                                status_sub_.getNumPublishers() == 0 || pose_sub_.getNumPublishers() == 0);
         ++i) {
      ros::Duration(0.1).sleep();
    }
  }

  void onStatus(const sdf_tracker::TrackingStatus& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    statuses_.push_back(msg);
    changed_.notify_all();
  }
  void onPose(const geometry_msgs::PoseStamped& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_.push_back({msg.header.stamp.toSec(), sdf_tracker_ros::fromPoseMsg(msg.pose)});
  }
  void onPath(const nav_msgs::Path& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    last_path_ = msg;
  }
  void onCloud(const sensor_msgs::PointCloud2& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    cloud_points_ = msg.width * msg.height;
  }

  /// Publishes one frame and waits for the node's status about it.
  sdf_tracker::TrackingStatus publishAndWait(const sensor_msgs::Image& image, const st::PinholeCamera& camera) {
    std::unique_lock<std::mutex> lock(mutex_);
    const size_t before = statuses_.size();
    const sensor_msgs::CameraInfo info = sdf_tracker_ros::toCameraInfo(camera, image.header);
    // Connections come up one by one (the node has several subscribers per topic): re-send the
    // pair until the node answers. A pair it already took is dropped by stamp, never tracked twice.
    bool arrived = false;
    for (double waited_s = 0.0; !arrived && waited_s < kStatusTimeout_s; waited_s += kResend_s) {
      lock.unlock();
      info_pub_.publish(info);
      image_pub_.publish(image);
      lock.lock();
      arrived = changed_.wait_for(lock, std::chrono::duration<double>(kResend_s),
                                  [&] { return statuses_.size() > before; });
    }
    EXPECT_TRUE(arrived) << "no status for the frame stamped " << image.header.stamp;
    return arrived ? statuses_.back() : sdf_tracker::TrackingStatus();
  }

  /// The room's exact depth from the desk path at t_s, as the QVGA camera's frame stamped stamp_s.
  static sensor_msgs::Image deskFrame(double stamp_s, double t_s,
                                      const std::string& frame_id = "camera_depth_optical_frame") {
    st::synthetic::NoiseModel exact;
    exact.enabled = false;
    std_msgs::Header header;
    header.stamp = ros::Time(stamp_s);
    header.frame_id = frame_id;
    const auto T = st::synthetic::cameraPose(st::synthetic::Motion::kDesk, t_s, 10.0);
    return sdf_tracker_ros::toImageMsg(st::synthetic::Scene::indoorRoom().render(kQvga, T, exact, 0), header);
  }
  /// Publishes deskFrame(stamp_s, t_s) and waits for the node's status about it.
  sdf_tracker::TrackingStatus publishDeskFrame(double stamp_s, double t_s) {
    return publishAndWait(deskFrame(stamp_s, t_s), kQvga);
  }

  ros::NodeHandle nh_;
  ros::AsyncSpinner spinner_{1};
  ros::Publisher image_pub_, info_pub_;
  ros::Subscriber status_sub_, pose_sub_, path_sub_, cloud_sub_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<sdf_tracker::TrackingStatus> statuses_;
  std::vector<st::io::StampedPose> poses_;
  nav_msgs::Path last_path_;  ///< the latest ~path
  size_t cloud_points_ = 0;
};

/// ros::service::call through a connection of its own, tried again when the connection itself
/// failed: ROS 1 opens one per call, and one of the CI runs of this test saw such a call fail
/// with the node up and answering every other. Whether the node did what was asked is in the
/// response, which the tests check.
template <typename Service>
inline bool callService(const std::string& name, Service& service) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (ros::service::call(name, service)) return true;
    ros::Duration(0.5).sleep();
  }
  return false;
}

/// A QVGA synthetic sequence converted by the package's own tum_to_bag, as a user would.
inline std::string makeSyntheticBag(const std::string& directory, int frames) {
  st::synthetic::SequenceSpec spec;
  spec.frames = frames;
  spec.camera = kQvga;
  spec.seed = 11;
  st::synthetic::writeSequence(directory, spec);
  const std::string bag = directory + "/sequence.bag";
  const std::string command = "rosrun sdf_tracker tum_to_bag " + directory + " " + bag + " > /dev/null";
  if (std::system(command.c_str()) != 0) throw std::runtime_error("failed: " + command);
  return bag;
}


}  // namespace node_test
