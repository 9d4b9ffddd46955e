#include <ros/ros.h>

#include "sdf_tracker/ros/tracker_server.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "sdf_tracker_node");
  try {
    sdf_tracker_ros::TrackerServer server(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("sdf_tracker: %s", e.what());
    return 1;
  }
  return 0;
}
