#include "sdf_tracker/eval/colour_agreement.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "sdf_tracker/camera/depth_undistortion.h"
#include "sdf_tracker/eval/evaluation.h"

namespace sdf_tracker::evaluation {

ColourAgreement compareMeshColours(const TriangleMesh& mesh, const TumSequence& sequence,
                                   const std::vector<io::StampedPose>& trajectory, int frame_step,
                                   double depth_tolerance_m) {
  if (mesh.colours.size() != mesh.vertices_W.size() || mesh.vertices_W.empty()) {
    throw std::invalid_argument("the mesh has no vertex colours to compare");
  }
  if (frame_step < 1) throw std::invalid_argument("frame step " + std::to_string(frame_step) + " is below 1");
  const PinholeCamera& camera = sequence.camera();
  const PinholeCamera ideal = camera.withoutDistortion();
  std::optional<DepthUndistortion> undistortion;
  if (!camera.distortion.isZero()) undistortion.emplace(camera);

  // The frames compared, and their times to find their poses by.
  std::vector<size_t> indices;
  std::vector<double> frame_times, pose_times;
  for (size_t i = 0; i < sequence.size(); i += static_cast<size_t>(frame_step)) {
    if (sequence.colourPath(i).empty()) continue;
    indices.push_back(i);
    frame_times.push_back(sequence.timestamp(i));
  }
  for (const io::StampedPose& pose : trajectory) pose_times.push_back(pose.timestamp_s);
  constexpr double kMaxPoseGap_s = 0.02;  // as the benchmark associates poses
  const std::vector<long> pose_of = associateByTime(frame_times, pose_times, kMaxPoseGap_s);

  ColourAgreement agreement;
  std::vector<double> distances;
  double channel_sum = 0.0;
  ColourImage colour;
  for (size_t f = 0; f < indices.size(); ++f) {
    if (pose_of[f] < 0) continue;
    const size_t index = indices[f];
    DepthImage depth = sequence.depth(index);
    const ColourImage raw = *sequence.colour(index);
    if (undistortion) {
      depth = undistortion->apply(depth);
      undistortion->apply(raw, &colour);
    } else {
      colour = raw;
    }
    const Eigen::Isometry3f T_C_W = trajectory[static_cast<size_t>(pose_of[f])].T_W_C.inverse().cast<float>();
    ++agreement.frames;
    for (size_t v = 0; v < mesh.vertices_W.size(); ++v) {
      const Eigen::Vector3f p_C = T_C_W * mesh.vertices_W[v];
      if (p_C.z() <= 0.0f) continue;
      const long u = std::lround(ideal.fx * p_C.x() / p_C.z() + ideal.cx);
      const long w = std::lround(ideal.fy * p_C.y() / p_C.z() + ideal.cy);
      if (u < 0 || w < 0 || u >= ideal.width || w >= ideal.height) continue;
      const float z = depth.at(static_cast<int>(u), static_cast<int>(w));
      if (!DepthImage::isMeasurement(z) || std::fabs(z - p_C.z()) > depth_tolerance_m) continue;
      const uint8_t* pixel = colour.at(static_cast<int>(u), static_cast<int>(w));
      double squared = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double difference = static_cast<double>(mesh.colours[v][c]) - pixel[c];
        channel_sum += std::fabs(difference);
        squared += difference * difference;
      }
      distances.push_back(std::sqrt(squared));
    }
  }
  agreement.comparisons = distances.size();
  if (distances.empty()) return agreement;
  agreement.mean_channel_difference = channel_sum / (3.0 * distances.size());
  const ErrorStats stats = summarize(distances);
  agreement.mean_distance = stats.mean;
  agreement.median_distance = stats.median;
  return agreement;
}

}  // namespace sdf_tracker::evaluation
