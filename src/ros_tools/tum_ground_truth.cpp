// tum_ground_truth: shows the motion-capture ground truth of a TUM RGB-D bag beside the tracker's
// estimate, without a frame ever getting two parents.
//
// The benchmark's bags put on /tf the ground truth /world -> /kinect and the camera's rigid chain
// /kinect -> ... -> /openni_depth_optical_frame. tum_bag.launch plays the bag's /tf on ~input
// (tf_bag) instead, and this node re-publishes on /tf:
//   - the rigid chain (every transform whose parent is not ~ground_truth_parent) unchanged, so the
//     tracker can look up its camera's mounting on ~base_frame (kinect) and publish map -> kinect;
//   - the ground truth's tree (~ground_truth_parent and every frame below it) renamed with ~suffix
//     (world_gt -> kinect_gt -> ... -> openni_depth_optical_frame_gt), the ground truth to look at;
//     other transforms of the bag (a robot's odometry, odom -> base_link -> kinect) are passed on
//     only, so that no renamed frame gets a second parent;
// and once, on /tf_static, map -> world_gt placing the ground truth's camera on the tracker's
// camera at the first estimate (~estimate, the tracker's ~pose), so both start together.
// Leading slashes are dropped from every frame id. With ~show_ground_truth false only the chain is
// passed on.

#include <optional>
#include <set>

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/ros/parameters.h"

namespace {

using sdf_tracker_ros::stripSlash;

class GroundTruthRelay {
 public:
  GroundTruthRelay(ros::NodeHandle nh, ros::NodeHandle pnh) : tf_listener_(tf_buffer_, nh) {
    ground_truth_parent_ = stripSlash(pnh.param<std::string>("ground_truth_parent", "world"));
    suffix_ = pnh.param<std::string>("suffix", "_gt");
    camera_frame_ = stripSlash(pnh.param<std::string>("camera_frame", "openni_depth_optical_frame"));
    show_ground_truth_ = pnh.param<bool>("show_ground_truth", true);
    ground_truth_frames_.insert(ground_truth_parent_);
    if (suffix_.empty()) throw std::invalid_argument("~suffix must not be empty: the ground truth needs frames of its own");
    tf_pub_ = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
    input_sub_ = nh.subscribe("tf_bag", 100, &GroundTruthRelay::onTf, this);
    estimate_sub_ = nh.subscribe("estimate", 10, &GroundTruthRelay::onEstimate, this);
    ROS_INFO("tum_ground_truth: %s -> ... shown as %s%s -> ..., aligned to the estimate's %s", ground_truth_parent_.c_str(),
             ground_truth_parent_.c_str(), suffix_.c_str(), camera_frame_.c_str());
  }

 private:
  void onTf(const tf2_msgs::TFMessage& in) {
    tf2_msgs::TFMessage out;
    for (geometry_msgs::TransformStamped tf : in.transforms) {
      tf.header.frame_id = stripSlash(tf.header.frame_id);
      tf.child_frame_id = stripSlash(tf.child_frame_id);
      if (tf.header.frame_id != ground_truth_parent_) out.transforms.push_back(tf);  // the rigid chain
      if (!show_ground_truth_ || !ground_truth_frames_.count(tf.header.frame_id)) continue;
      ground_truth_frames_.insert(tf.child_frame_id);
      tf.header.frame_id += suffix_;
      tf.child_frame_id += suffix_;
      out.transforms.push_back(tf);
    }
    tf_pub_.publish(out);
  }

  void onEstimate(const geometry_msgs::PoseStamped& pose) {
    if (aligned_ || !show_ground_truth_) return;
    if (!first_) first_ = pose;
    // map <- world_gt, from the camera's pose in both at the first estimate's time.
    try {
      const Eigen::Isometry3d T_gt_camera = tf2::transformToEigen(tf_buffer_.lookupTransform(
          ground_truth_parent_ + suffix_, camera_frame_ + suffix_, first_->header.stamp));
      const Eigen::Isometry3d T_map_camera = sdf_tracker_ros::fromPoseMsg(first_->pose);
      geometry_msgs::TransformStamped alignment = tf2::eigenToTransform(T_map_camera * T_gt_camera.inverse());
      alignment.header.stamp = first_->header.stamp;
      alignment.header.frame_id = stripSlash(first_->header.frame_id);
      alignment.child_frame_id = ground_truth_parent_ + suffix_;
      static_broadcaster_.sendTransform(alignment);
      aligned_ = true;
      ROS_INFO("tum_ground_truth: %s placed in %s at the first estimate (stamp %.3f)",
               alignment.child_frame_id.c_str(), alignment.header.frame_id.c_str(), first_->header.stamp.toSec());
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5.0, "tum_ground_truth: waiting for the ground truth at the first estimate: %s", e.what());
    }
  }

  std::string ground_truth_parent_, suffix_, camera_frame_;
  /// ~ground_truth_parent and the frames seen below it: the tree shown renamed.
  std::set<std::string> ground_truth_frames_;
  bool show_ground_truth_ = true;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  ros::Publisher tf_pub_;
  ros::Subscriber input_sub_, estimate_sub_;
  std::optional<geometry_msgs::PoseStamped> first_;
  bool aligned_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "tum_ground_truth");
  try {
    GroundTruthRelay relay(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("tum_ground_truth: %s", e.what());
    return 1;
  }
  return 0;
}
