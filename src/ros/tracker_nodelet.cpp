#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "sdf_tracker/ros/tracker_server.h"

namespace sdf_tracker_ros {

/// sdf_tracker as a nodelet, e.g. in the same manager as the camera driver (zero-copy images).
class TrackerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      server_ = std::make_unique<TrackerServer>(getMTNodeHandle(), getMTPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("sdf_tracker: %s", e.what());
      throw;
    }
  }
  std::unique_ptr<TrackerServer> server_;
};

}  // namespace sdf_tracker_ros

PLUGINLIB_EXPORT_CLASS(sdf_tracker_ros::TrackerNodelet, nodelet::Nodelet)
