#pragma once

#include <string>
#include <vector>

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

/// The cameras of a depth camera whose calibration a recording carries.
enum class RecordedCamera { kDepth, kColour };

/// Where a recording's calibration of one camera lives, in camera_info_manager's YAML: inside a
/// folder recording (fakenect dump: depth_camera_info.yaml, rgb_camera_info.yaml), beside a file
/// recording ("x.oni" -> "x.oni.yaml", "x.oni.rgb.yaml"). The converters write them there; the
/// drivers read them from there when ~depth_camera_info_url (~rgb_camera_info_url) is not set.
std::string calibrationFileFor(const std::string& recording, RecordedCamera camera = RecordedCamera::kDepth);

/// One image of a recording made from a TUM sequence: depth frame `frame`, or the colour image
/// paired with it (TumSequence::colourPath).
struct RecordedImage {
  double timestamp_s;
  size_t frame;
  bool colour;
};

/// The sequence's depth frames and, with `with_colour`, the colour images paired with them, in the
/// order a camera sends them: by time (a colour image stamped with its depth frame after it).
std::vector<RecordedImage> recordingOrder(const TumSequence& sequence, bool with_colour);

/// Writes a camera_info_manager (camera_calibration_parsers) YAML file for the camera, its
/// distortion as plumb_bob. Throws std::runtime_error naming the file if it cannot be written.
void writeCalibrationFile(const std::string& path, const PinholeCamera& camera, const std::string& camera_name);

}  // namespace sdf_tracker::devices
