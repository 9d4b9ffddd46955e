#pragma once
// What the rostests that play a launch file watch: every parent a tf frame gets, the tracker's
// poses, its latest diagnostics, and the offline pipeline on the same sequence to compare them with.

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include "sdf_tracker/TrackingStatus.h"

#include "sdf_tracker/cli/odometry_track.h"
#include "sdf_tracker/devices/recording.h"
#include "sdf_tracker/eval/evaluation.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/pipeline/parameters.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/ros/parameters.h"

namespace sdf_tracker::test {

/// Subscribes to /tf, /tf_static, sdf_tracker/pose, sdf_tracker/status and /diagnostics for its
/// lifetime. Lock `mutex` to read.
class LaunchWatch {
 public:
  explicit LaunchWatch(ros::NodeHandle& nh)
      : tf_sub_(nh.subscribe("/tf", 1000, &LaunchWatch::onTf, this)),
        static_sub_(nh.subscribe("/tf_static", 100, &LaunchWatch::onTf, this)),
        pose_sub_(nh.subscribe("sdf_tracker/pose", 1000, &LaunchWatch::onPose, this)),
        status_sub_(nh.subscribe("sdf_tracker/status", 1000, &LaunchWatch::onStatus, this)),
        diagnostics_sub_(nh.subscribe("/diagnostics", 100, &LaunchWatch::onDiagnostics, this)) {}

  /// Every frame seen on /tf or /tf_static has exactly one parent (call with `mutex` held).
  void expectOneParentPerFrame() const {
    for (const auto& [child, frame_parents] : parents) {
      std::string list;
      for (const auto& p : frame_parents) list += p + " ";
      EXPECT_EQ(frame_parents.size(), 1u) << "frame " << child << " has the parents " << list;
    }
  }

  std::mutex mutex;
  std::map<std::string, std::set<std::string>> parents;  ///< child frame -> its parents, slashes stripped
  std::vector<io::StampedPose> poses;                     ///< the tracker's estimates, as stamped
  ros::WallTime last_pose_wall;
  /// Status messages: one per frame the node processed; those predicted by the robot's odometry.
  size_t statuses = 0;
  size_t predicted_by_odometry = 0;
  /// The node's counts, as its latest status message gives them.
  uint32_t frames_received = 0;
  uint32_t frames_dropped = 0;
  /// The same counts in the first status message seen: the node may have taken a frame or two
  /// before this subscriber's connection stood, and their statuses never reached it.
  uint32_t first_frames_received = 0;
  uint32_t first_frames_dropped = 0;
  /// The latest status of each name on /diagnostics ("sdf_tracker: colour", ...).
  std::map<std::string, diagnostic_msgs::DiagnosticStatus> diagnostics;

  /// Frames the node received, and dropped, from the first status seen on (call with `mutex` held).
  uint32_t framesReceivedWhileWatched() const { return statuses > 0 ? frames_received - first_frames_received + 1 : 0; }
  uint32_t framesDroppedWhileWatched() const { return frames_dropped - first_frames_dropped; }

 private:
  void onTf(const tf2_msgs::TFMessage& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& tf : msg.transforms) {
      parents[sdf_tracker_ros::stripSlash(tf.child_frame_id)].insert(sdf_tracker_ros::stripSlash(tf.header.frame_id));
    }
  }
  void onPose(const geometry_msgs::PoseStamped& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    poses.push_back({msg.header.stamp.toSec(), sdf_tracker_ros::fromPoseMsg(msg.pose)});
    last_pose_wall = ros::WallTime::now();
  }

  void onStatus(const sdf_tracker::TrackingStatus& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    if (statuses++ == 0) {
      first_frames_received = msg.frames_received;
      first_frames_dropped = msg.frames_dropped;
    }
    predicted_by_odometry += msg.predicted_by_odometry;
    frames_received = std::max(frames_received, msg.frames_received);
    frames_dropped = std::max(frames_dropped, msg.frames_dropped);
  }

  void onDiagnostics(const diagnostic_msgs::DiagnosticArray& msg) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& status : msg.status) diagnostics[status.name] = status;
  }

  ros::Subscriber tf_sub_, static_sub_, pose_sub_, status_sub_, diagnostics_sub_;
};

/// The node coloured its map from the colour images it was given: "sdf_tracker: colour" is OK and
/// says frames were fused in colour (call with the watch's `mutex` held).
inline void expectFusedInColour(LaunchWatch& watch) {
  const diagnostic_msgs::DiagnosticStatus& colour = watch.diagnostics["sdf_tracker: colour"];
  EXPECT_EQ(colour.level, diagnostic_msgs::DiagnosticStatus::OK) << colour.message;
  EXPECT_NE(colour.message.find("frames fused in colour"), std::string::npos) << "\"" << colour.message << "\"";
}

/// The node's poses against the offline pipeline's (default preset) on the same sequence, with the
/// same `odometry` as the prediction when it has one: prints both ATEs after `label` and checks the
/// node tracked at least `min_fraction` of the frames and is within `max_ate_difference_m` of the
/// offline ATE. The node's stamps are the sequence's, shifted as the converters shift them
/// (devices::rosStampOffset).
inline void expectOfflineAccuracy(const TumSequence& sequence, const std::vector<io::StampedPose>& node_poses,
                                  const std::string& label, double min_fraction, double max_ate_difference_m,
                                  const tools::OdometryTrack* odometry = nullptr) {
  const double offset_s = devices::rosStampOffset(sequence);
  std::vector<io::StampedPose> node_trajectory = node_poses, offline_trajectory;
  for (auto& pose : node_trajectory) pose.timestamp_s -= offset_s;
  SdfPipeline offline(preset("default").pipeline);
  for (size_t i = 0; i < sequence.size(); ++i) {
    offline.processFrame(sequence.depth(i), sequence.camera(), sequence.timestamp(i),
                         odometry ? odometry->at(sequence.timestamp(i)) : std::nullopt);
    offline_trajectory.push_back({sequence.timestamp(i), offline.pose()});
  }
  const double node_ate = evaluation::computeAte(node_trajectory, sequence.groundTruth()).translation_m.rmse;
  const double offline_ate = evaluation::computeAte(offline_trajectory, sequence.groundTruth()).translation_m.rmse;
  std::cout << "[ figures  ] " << label << ": " << node_poses.size() << " of " << sequence.size()
            << " frames tracked, node ATE " << node_ate * 1000 << " mm, offline ATE " << offline_ate * 1000 << " mm\n";
  EXPECT_GE(static_cast<double>(node_poses.size()) / sequence.size(), min_fraction);
  EXPECT_LT(std::abs(node_ate - offline_ate), max_ate_difference_m);
}

}  // namespace sdf_tracker::test
