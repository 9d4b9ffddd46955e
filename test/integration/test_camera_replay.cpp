// Watches kinect.launch or openni2.launch replay a recording of a synthetic sequence through the
// camera library's own playback (libfreenect's fakenect, OpenNI 2's OniFile): the frames carry
// the sequence's stamps, every frame reaches the node, which processes it or counts it as dropped,
// the estimate is as accurate as the offline pipeline's on the same frames, and no frame of /tf
// has two parents. The recording carries colour and is played with depth_registration:=true: the
// driver publishes the colour images at their own stamps and the node colours its map with them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>
#include <iostream>

#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>

#include "launch_watch.h"

namespace st = sdf_tracker;

namespace {

/// The camera path (the driver, the library's playback, the transport) delivers every frame to
/// the node: all but a frame or two of the recording reach it.
constexpr double kMinReceivedFraction = 0.97;
/// Replayed at the recorded 30 Hz, a frame that arrives while the tracker is busy with the last is
/// dropped (and counted). The synthetic VGA scene has depth at nearly every pixel, where a real
/// recording has holes: here it costs the tracker 33-35 ms a frame in the node, at the edge of
/// 30 Hz, and 6-9 % of its frames are dropped on an idle machine, up to a third when something
/// else wakes up beside it (real 300-frame VGA recordings of fr1_xyz and redkitchen: none,
/// through either driver). Below this share the tracker has stopped keeping up at all.
constexpr double kMinProcessedFraction = 0.5;
/// The issue allows 5 mm between the node and the offline runner on a synthetic sequence.
constexpr double kMaxAteDifference_m = 0.005;
/// The replay has ended when no pose has come for this long.
constexpr double kQuietAfterReplay_s = 3.0;

TEST(CameraReplay, TracksTheRecordingAsTheOfflineRunnerDoes) {
  ros::NodeHandle pnh("~");
  const std::string sequence_dir = pnh.param<std::string>("sequence", "");
  const std::string camera = pnh.param<std::string>("camera", "");
  ASSERT_FALSE(sequence_dir.empty()) << "~sequence: the folder the recording was made from";
  const st::TumSequence sequence = st::TumSequence::open(sequence_dir);

  ASSERT_TRUE(sequence.hasColourList()) << sequence_dir << " was made without colour (sdf_tracker_synth --colour)";

  ros::NodeHandle nh;
  st::test::LaunchWatch watch(nh);
  std::vector<double> colour_stamps_s;  // guarded by watch.mutex
  const ros::Subscriber colour_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "camera/rgb/camera_info", 1000, [&](const sensor_msgs::CameraInfoConstPtr& info) {
        std::lock_guard<std::mutex> lock(watch.mutex);
        colour_stamps_s.push_back(info->header.stamp.toSec());
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();

  const ros::WallTime start = ros::WallTime::now();
  bool started = false, ended = false;
  while ((ros::WallTime::now() - start).toSec() < 150.0) {
    ros::WallDuration(0.2).sleep();
    std::lock_guard<std::mutex> lock(watch.mutex);
    started = !watch.poses.empty();
    if (started && (ros::WallTime::now() - watch.last_pose_wall).toSec() > kQuietAfterReplay_s) {
      ended = true;
      break;
    }
  }
  ASSERT_TRUE(started) << "no estimate on sdf_tracker/pose from " << camera;
  EXPECT_TRUE(ended) << "the replay did not end in time";

  std::lock_guard<std::mutex> lock(watch.mutex);
  watch.expectOneParentPerFrame();
  EXPECT_EQ(watch.parents["camera_link"], std::set<std::string>{"map"}) << "the tracker moves the camera's link";
  EXPECT_EQ(watch.parents["camera_depth_optical_frame"], std::set<std::string>{"camera_depth_frame"});
  EXPECT_EQ(watch.parents["camera_rgb_optical_frame"], std::set<std::string>{"camera_rgb_frame"});

  // The driver stamps each frame with the recording's own time: the sequence's, shifted as the
  // converters say.
  const double offset_s = st::devices::rosStampOffset(sequence);
  size_t next = 0, stamps_matched = 0;
  for (const auto& pose : watch.poses) {
    const double t = pose.timestamp_s - offset_s;
    while (next < sequence.size() && sequence.timestamp(next) < t - 1e-4) ++next;
    if (next < sequence.size() && std::abs(sequence.timestamp(next) - t) < 1e-4) ++stamps_matched;
  }
  EXPECT_EQ(stamps_matched, watch.poses.size()) << "every pose carries the stamp of one of the sequence's frames";

  // The colour images too, each at its own recorded stamp; and the map is coloured with them.
  std::set<long long> recorded_colour_us;
  for (size_t i = 0; i < sequence.size(); ++i) {
    if (!sequence.colourPath(i).empty()) {
      recorded_colour_us.insert(std::llround((sequence.colourTimestamp(i) + offset_s) * 1e6));
    }
  }
  const size_t colour_matched = std::count_if(colour_stamps_s.begin(), colour_stamps_s.end(), [&](double t) {
    return recorded_colour_us.count(std::llround(t * 1e6)) > 0;
  });
  std::cout << "[ figures  ] " << camera << " replay: " << colour_stamps_s.size() << " colour images of "
            << recorded_colour_us.size() << " recorded, " << colour_matched << " at a recorded stamp\n";
  EXPECT_EQ(colour_matched, colour_stamps_s.size()) << "every colour image carries the stamp it was recorded with";
  EXPECT_GE(colour_stamps_s.size(), kMinReceivedFraction * recorded_colour_us.size());
  st::test::expectFusedInColour(watch);

  // Every frame that reached the node was processed (one status each) or counted as dropped, from
  // the first status this test saw on (one may still be in flight).
  EXPECT_GE(watch.frames_received, kMinReceivedFraction * sequence.size())
      << "of " << sequence.size() << " recorded frames, " << watch.frames_received << " reached the node";
  EXPECT_GE(watch.statuses + watch.framesDroppedWhileWatched() + 1, watch.framesReceivedWhileWatched())
      << "of " << watch.framesReceivedWhileWatched() << " frames received since the first status seen, "
      << watch.statuses << " processed and " << watch.framesDroppedWhileWatched() << " dropped";
  std::cout << "[ figures  ] " << camera << " replay: " << watch.frames_received << " frames reached the node, "
            << watch.frames_dropped << " dropped while it was busy\n";
  st::test::expectOfflineAccuracy(sequence, watch.poses, camera + " replay at the recording's rate",
                                  kMinProcessedFraction, kMaxAteDifference_m);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "camera_replay_test");
  return RUN_ALL_TESTS();
}
