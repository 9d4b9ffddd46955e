// tum_to_bag: converts a TUM-layout depth folder into a rosbag shaped like the TUM RGB-D
// benchmark's own bags, so the ROS workflow can be tried and tested without downloads.
//   rosrun sdf_tracker tum_to_bag SEQUENCE_DIR OUT.bag [--frames N]
// Writes /camera/depth/image (32FC1 metres), /camera/depth/camera_info, and, when the folder has
// ground truth, /tf (world -> kinect, as in the TUM bags) plus a latched /tf_static map -> world
// that puts the ground truth's first pose on the tracker's start pose, so rviz shows both together.

#include <iostream>

#include <geometry_msgs/TransformStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <tf2_msgs/TFMessage.h>

#include "../tools/command_line.h"
#include "sdf_tracker/core/tum_sequence.h"
#include "sdf_tracker/ros/conversions.h"

namespace {

constexpr const char* kDepthFrame = "openni_depth_optical_frame";

geometry_msgs::TransformStamped toTransform(const Eigen::Isometry3d& T, const ros::Time& stamp, const std::string& parent,
                                            const std::string& child) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  const geometry_msgs::Pose pose = sdf_tracker_ros::toPoseMsg(T);
  tf.transform.translation.x = pose.position.x;
  tf.transform.translation.y = pose.position.y;
  tf.transform.translation.z = pose.position.z;
  tf.transform.rotation = pose.orientation;
  return tf;
}

sensor_msgs::CameraInfo toCameraInfo(const sdf_tracker::PinholeCamera& c, const std_msgs::Header& header) {
  sensor_msgs::CameraInfo info;
  info.header = header;
  info.width = c.width;
  info.height = c.height;
  info.distortion_model = "plumb_bob";
  info.D.assign(5, 0.0);
  info.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = {c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return info;
}

int run(int argc, char** argv) {
  if (argc != 3 && argc != 5) {
    std::cerr << "usage: tum_to_bag SEQUENCE_DIR OUT.bag [--frames N]\n";
    return 2;
  }
  sdf_tracker::TumSequence sequence = sdf_tracker::TumSequence::open(argv[1]);
  if (argc == 5) sequence.truncate(static_cast<size_t>(std::stoul(argv[4])));
  // ros::Time(0) means "no time" to tf: sequences that start at 0 s are shifted by this much.
  const double offset_s = sequence.timestamp(0) < 1.0 ? 1.0 : 0.0;
  rosbag::Bag bag(argv[2], rosbag::bagmode::Write);
  const auto& gt = sequence.groundTruth();
  size_t gt_index = 0;
  for (size_t i = 0; i < sequence.size(); ++i) {
    std_msgs::Header header;
    header.seq = static_cast<uint32_t>(i);
    header.stamp = ros::Time(sequence.timestamp(i) + offset_s);
    header.frame_id = kDepthFrame;
    if (i == 0 && !gt.empty()) {
      tf2_msgs::TFMessage tf_static;
      tf_static.transforms.push_back(toTransform(gt.front().T_W_C.inverse(), header.stamp, "map", "world"));
      bag.write("/tf_static", header.stamp, tf_static);
    }
    bag.write("/camera/depth/image", header.stamp, sdf_tracker_ros::toImageMsg(sequence.depth(i), header));
    bag.write("/camera/depth/camera_info", header.stamp, toCameraInfo(sequence.camera(), header));
    // Ground truth up to this frame's time, on /tf as world -> kinect.
    while (gt_index < gt.size() && gt[gt_index].timestamp_s <= sequence.timestamp(i) + 1e-6) {
      tf2_msgs::TFMessage tf;
      const ros::Time stamp(gt[gt_index].timestamp_s + offset_s);
      tf.transforms.push_back(toTransform(gt[gt_index].T_W_C, stamp, "world", "kinect"));
      bag.write("/tf", stamp, tf);
      ++gt_index;
    }
  }
  bag.close();
  std::cout << "wrote " << sequence.size() << " frames to " << argv[2];
  if (offset_s != 0.0) std::cout << " (stamps shifted by " << offset_s << " s)";
  std::cout << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return sdf_tracker::tools::runTool("tum_to_bag", run, argc, argv); }
