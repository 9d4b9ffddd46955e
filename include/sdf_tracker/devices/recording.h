#pragma once

#include <string>

#include "sdf_tracker/camera/camera.h"

namespace sdf_tracker {
class TumSequence;
}

namespace sdf_tracker::devices {

/// Seconds added to a sequence's stamps when it becomes a ROS recording (bag, fakenect dump,
/// .oni): 1 s if its clock starts below 1 s, since ROS time 0 means "no time"; otherwise none.
/// The clock starts at the first depth frame or ground-truth pose, whichever is earlier: a part
/// cut from a sequence that starts at 0 s keeps the whole ground truth, and so the whole shift.
double rosStampOffset(const TumSequence& sequence);

/// Where a recording's depth calibration lives, in camera_info_manager's YAML: inside a folder
/// recording (fakenect dump), beside a file recording ("x.oni" -> "x.oni.yaml"). The converters
/// write it there; the drivers read it from there when ~depth_camera_info_url is not set.
std::string calibrationFileFor(const std::string& recording);

/// Writes a camera_info_manager (camera_calibration_parsers) YAML file for the camera, its
/// distortion as plumb_bob. Throws std::runtime_error naming the file if it cannot be written.
void writeCalibrationFile(const std::string& path, const PinholeCamera& camera, const std::string& camera_name);

}  // namespace sdf_tracker::devices
