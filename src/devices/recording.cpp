#include "sdf_tracker/devices/recording.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "sdf_tracker/io/tum_sequence.h"

namespace sdf_tracker::devices {

double rosStampOffset(const TumSequence& sequence) {
  if (sequence.size() == 0) return 0.0;
  double start_s = sequence.timestamp(0);
  if (!sequence.groundTruth().empty()) start_s = std::min(start_s, sequence.groundTruth().front().timestamp_s);
  return start_s < 1.0 ? 1.0 : 0.0;
}

std::string calibrationFileFor(const std::string& recording, RecordedCamera camera) {
  const bool depth = camera == RecordedCamera::kDepth;
  if (std::filesystem::is_directory(recording)) return recording + (depth ? "/depth" : "/rgb") + "_camera_info.yaml";
  return recording + (depth ? ".yaml" : ".rgb.yaml");
}

std::vector<RecordedImage> recordingOrder(const TumSequence& sequence, bool with_colour) {
  std::vector<RecordedImage> images;
  for (size_t i = 0; i < sequence.size(); ++i) {
    images.push_back({sequence.timestamp(i), i, false});
    if (with_colour && !sequence.colourPath(i).empty()) images.push_back({sequence.colourTimestamp(i), i, true});
  }
  std::stable_sort(images.begin(), images.end(),
                   [](const RecordedImage& a, const RecordedImage& b) { return a.timestamp_s < b.timestamp_s; });
  return images;
}

void writeCalibrationFile(const std::string& path, const PinholeCamera& camera, const std::string& camera_name) {
  std::ofstream out(path);
  out.precision(10);
  out << "image_width: " << camera.width << "\n"
      << "image_height: " << camera.height << "\n"
      << "camera_name: " << camera_name << "\n"
      << "camera_matrix:\n  rows: 3\n  cols: 3\n  data: [" << camera.fx << ", 0, " << camera.cx << ", 0, " << camera.fy
      << ", " << camera.cy << ", 0, 0, 1]\n"
      << "distortion_model: plumb_bob\n"
      << "distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [" << camera.distortion.k1 << ", "
      << camera.distortion.k2 << ", " << camera.distortion.p1 << ", " << camera.distortion.p2 << ", "
      << camera.distortion.k3 << "]\n"
      << "rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n"
      << "projection_matrix:\n  rows: 3\n  cols: 4\n  data: [" << camera.fx << ", 0, " << camera.cx << ", 0, 0, "
      << camera.fy << ", " << camera.cy << ", 0, 0, 0, 1, 0]\n";
  if (!out.flush()) throw std::runtime_error("cannot write " + path);
}

}  // namespace sdf_tracker::devices
