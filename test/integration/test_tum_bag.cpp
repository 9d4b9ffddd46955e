// Watches tum_bag.launch play a TUM-shaped bag at rate 1.0: every frame of /tf and /tf_static has
// one parent, at least 95 % of the frames get a pose, the estimate is as accurate as the offline
// pipeline's on the same frames, and the ground truth is shown beside it.

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <mutex>

#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "launch_watch.h"

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
  void onClock(const rosgraph_msgs::Clock& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg.clock != last_clock_) last_clock_wall_ = ros::WallTime::now();
    last_clock_ = msg.clock;
  }

  std::mutex mutex_;
  ros::Time last_clock_;
  ros::WallTime last_clock_wall_ = ros::WallTime::now();
};

TEST_F(TumBagTest, PlaysAtRateOneWithOneParentPerFrameAndOfflineAccuracy) {
  const std::string sequence_dir = ros::NodeHandle("~").param<std::string>("sequence", "");
  ASSERT_FALSE(sequence_dir.empty()) << "~sequence: the folder the bag was made from";
  const st::TumSequence sequence = st::TumSequence::open(sequence_dir);

  ros::NodeHandle nh;
  st::test::LaunchWatch watch(nh);
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
    {
      std::lock_guard<std::mutex> lock(watch.mutex);
      started = started || !watch.poses.empty();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (started && (ros::WallTime::now() - last_clock_wall_).toSec() > kQuietAfterPlayback_s) {
      ended = true;
      break;
    }
  }
  ASSERT_TRUE(started) << "no estimate on sdf_tracker/pose";
  EXPECT_TRUE(ended) << "playback did not end in time";

  std::lock_guard<std::mutex> lock(watch.mutex);
  // One parent per frame: the tracker must not give the bag's frames a second one.
  watch.expectOneParentPerFrame();
  EXPECT_EQ(watch.parents["kinect"], std::set<std::string>{"map"}) << "the tracker moves the camera's mount";
  EXPECT_EQ(watch.parents["openni_depth_optical_frame"], std::set<std::string>{"openni_depth_frame"});
  EXPECT_EQ(watch.parents["kinect_gt"], std::set<std::string>{"world_gt"}) << "the ground truth, renamed";
  EXPECT_EQ(watch.parents["world_gt"], std::set<std::string>{"map"}) << "the ground truth, aligned to the map";
  EXPECT_TRUE(tf_buffer.canTransform("map", "openni_depth_optical_frame_gt", ros::Time(0)));
  // The bag's /imu levels the map frame: the synthetic world's up (-y) is the map's +z.
  const Eigen::Isometry3d T_map_world =
      tf2::transformToEigen(tf_buffer.lookupTransform("map", "world_gt", ros::Time(0)));
  const Eigen::Vector3d up_map = T_map_world.linear() * -Eigen::Vector3d::UnitY();
  const double tilt_deg = std::acos(std::min(1.0, up_map.z())) * 180.0 / M_PI;
  std::cout << "[ figures  ] map frame tilted " << tilt_deg << " degrees from level\n";
  EXPECT_LT(tilt_deg, kMaxTilt_deg) << "the map frame is not levelled by /imu";

  st::test::expectOfflineAccuracy(sequence, watch.poses, "tum_bag.launch at rate 1.0", kMinProcessedFraction,
                                  kMaxAteDifference_m);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "tum_bag_test");
  return RUN_ALL_TESTS();
}
