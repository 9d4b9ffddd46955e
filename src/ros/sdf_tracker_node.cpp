#include <cstdio>

#include <ros/ros.h>

#include "sdf_tracker/ros/tracker_server.h"
#include "sdf_tracker/util/frame_memory.h"

int main(int argc, char** argv) {
  // Line-buffered even into a pipe (roslaunch), so the shut-down summary is not lost.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  sdf_tracker::keepFrameMemoryResident();
  ros::init(argc, argv, "sdf_tracker_node");
  try {
    sdf_tracker_ros::TrackerServer server(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
    // A file the user asked for that could not be written is a failed run.
    return server.finish() ? 0 : 1;
  } catch (const std::exception& e) {
    // Also straight to stderr: rosconsole has been seen to drop the message when the node
    // exits right after it.
    ROS_FATAL("sdf_tracker: %s", e.what());
    std::fprintf(stderr, "sdf_tracker_node: %s\n", e.what());
    return 1;
  }
}
