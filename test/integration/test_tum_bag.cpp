// Watches tum_bag.launch play a TUM-shaped bag at rate 1.0: every frame of /tf and /tf_static has
// one parent, at least 95 % of the frames get a pose, the estimate is as accurate as the offline
// pipeline's on the same frames, and the ground truth is shown beside it.

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>
#include <mutex>
#include <set>

#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "sdf_tracker/core/evaluation.h"
#include "sdf_tracker/core/parameters.h"
#include "sdf_tracker/core/pipeline.h"
#include "sdf_tracker/core/tum_sequence.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/ros/parameters.h"

namespace st = sdf_tracker;

namespace {

constexpr double kMinProcessedFraction = 0.95;
/// The node may drop a few frames and differ by float order; the issue allows 5 mm.
constexpr double kMaxAteDifference_m = 0.005;
/// Playback has ended when simulated time has not moved for this long.
constexpr double kQuietAfterPlayback_s = 4.0;
/// The map frame is levelled with the accelerometer: what is left is the first frame's pose error.
constexpr double kMaxTilt_deg = 1.0;

class TumBagTest : public ::testing::Test {
 public:
  void onTf(const tf2_msgs::TFMessage& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& tf : msg.transforms) {
      parents_[sdf_tracker_ros::stripSlash(tf.child_frame_id)].insert(sdf_tracker_ros::stripSlash(tf.header.frame_id));
    }
  }
  void onPose(const geometry_msgs::PoseStamped& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    poses_.push_back({msg.header.stamp.toSec(), sdf_tracker_ros::fromPoseMsg(msg.pose)});
  }
  void onClock(const rosgraph_msgs::Clock& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg.clock != last_clock_) last_clock_wall_ = ros::WallTime::now();
    last_clock_ = msg.clock;
  }

  std::mutex mutex_;
  std::map<std::string, std::set<std::string>> parents_;
  std::vector<st::io::StampedPose> poses_;
  ros::Time last_clock_;
  ros::WallTime last_clock_wall_ = ros::WallTime::now();
};

TEST_F(TumBagTest, PlaysAtRateOneWithOneParentPerFrameAndOfflineAccuracy) {
  const std::string sequence_dir = ros::NodeHandle("~").param<std::string>("sequence", "");
  ASSERT_FALSE(sequence_dir.empty()) << "~sequence: the folder the bag was made from";
  const st::TumSequence sequence = st::TumSequence::open(sequence_dir);

  ros::NodeHandle nh;
  ros::Subscriber tf_sub = nh.subscribe("/tf", 1000, &TumBagTest::onTf, static_cast<TumBagTest*>(this));
  ros::Subscriber static_sub = nh.subscribe("/tf_static", 100, &TumBagTest::onTf, static_cast<TumBagTest*>(this));
  ros::Subscriber pose_sub = nh.subscribe("sdf_tracker/pose", 1000, &TumBagTest::onPose, static_cast<TumBagTest*>(this));
  ros::Subscriber clock_sub = nh.subscribe("/clock", 10, &TumBagTest::onClock, static_cast<TumBagTest*>(this));
  ros::AsyncSpinner spinner(1);
  spinner.start();
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener(tf_buffer);

  // Wait for playback to start, then to end.
  const ros::WallTime start = ros::WallTime::now();
  bool started = false, ended = false;
  while ((ros::WallTime::now() - start).toSec() < 200.0) {
    ros::WallDuration(0.2).sleep();
    std::lock_guard<std::mutex> lock(mutex_);
    started = started || !poses_.empty();
    if (started && (ros::WallTime::now() - last_clock_wall_).toSec() > kQuietAfterPlayback_s) {
      ended = true;
      break;
    }
  }
  ASSERT_TRUE(started) << "no estimate on sdf_tracker/pose";
  EXPECT_TRUE(ended) << "playback did not end in time";

  std::lock_guard<std::mutex> lock(mutex_);
  // One parent per frame: the tracker must not give the bag's frames a second one.
  for (const auto& [child, parents] : parents_) {
    std::string list;
    for (const auto& p : parents) list += p + " ";
    EXPECT_EQ(parents.size(), 1u) << "frame " << child << " has the parents " << list;
  }
  EXPECT_EQ(parents_["kinect"], std::set<std::string>{"map"}) << "the tracker moves the camera's mount";
  EXPECT_EQ(parents_["openni_depth_optical_frame"], std::set<std::string>{"openni_depth_frame"});
  EXPECT_EQ(parents_["kinect_gt"], std::set<std::string>{"world_gt"}) << "the ground truth, renamed";
  EXPECT_EQ(parents_["world_gt"], std::set<std::string>{"map"}) << "the ground truth, aligned to the map";
  EXPECT_TRUE(tf_buffer.canTransform("map", "openni_depth_optical_frame_gt", ros::Time(0)));
  // The bag's /imu levels the map frame: the synthetic world's up (-y) is the map's +z.
  const Eigen::Isometry3d T_map_world =
      tf2::transformToEigen(tf_buffer.lookupTransform("map", "world_gt", ros::Time(0)));
  const Eigen::Vector3d up_map = T_map_world.linear() * -Eigen::Vector3d::UnitY();
  const double tilt_deg = std::acos(std::min(1.0, up_map.z())) * 180.0 / M_PI;
  std::cout << "[ figures  ] map frame tilted " << tilt_deg << " degrees from level\n";
  EXPECT_LT(tilt_deg, kMaxTilt_deg) << "the map frame is not levelled by /imu";

  const double processed = static_cast<double>(poses_.size()) / sequence.size();
  // Offline, the same frames (the node's stamps are the sequence's, shifted as tum_to_bag says).
  const double offset_s = sequence.timestamp(0) < 1.0 ? 1.0 : 0.0;
  st::SdfPipeline offline(st::preset("default").pipeline);
  std::vector<st::io::StampedPose> offline_trajectory, node_trajectory = poses_;
  for (auto& pose : node_trajectory) pose.timestamp_s -= offset_s;
  for (size_t i = 0; i < sequence.size(); ++i) {
    offline.processFrame(sequence.depth(i), sequence.camera(), sequence.timestamp(i));
    offline_trajectory.push_back({sequence.timestamp(i), offline.pose()});
  }
  const double node_ate = st::evaluation::computeAte(node_trajectory, sequence.groundTruth()).translation_m.rmse;
  const double offline_ate = st::evaluation::computeAte(offline_trajectory, sequence.groundTruth()).translation_m.rmse;
  std::cout << "[ figures  ] tum_bag.launch at rate 1.0: " << poses_.size() << " of " << sequence.size()
            << " frames processed, node ATE " << node_ate * 1000 << " mm, offline ATE " << offline_ate * 1000
            << " mm\n";
  EXPECT_GE(processed, kMinProcessedFraction);
  EXPECT_LT(std::abs(node_ate - offline_ate), kMaxAteDifference_m);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "tum_bag_test");
  return RUN_ALL_TESTS();
}
