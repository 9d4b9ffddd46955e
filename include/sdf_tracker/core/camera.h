#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace sdf_tracker {

/// Pinhole intrinsics of a depth camera (no distortion), in pixels.
/// The optical frame is x right, y down, z forward (REP 103 optical convention).
struct PinholeCamera {
  double fx = 520.0;
  double fy = 520.0;
  double cx = 319.5;
  double cy = 239.5;
  int width = 640;
  int height = 480;

  /// Every violated constraint, in words; empty when the camera is usable.
  std::vector<std::string> validate() const;

  /// The same lens at another resolution of the same sensor (VGA 640x480 -> QVGA 320x240 -> QQVGA
  /// 160x120, as the reference release scales its parameters). Throws std::invalid_argument when
  /// the new size is not a positive integer fraction of the current one.
  PinholeCamera scaledTo(int new_width, int new_height) const;

  /// Back-projection, eq. (3): pixel (u, v) with depth z [m] -> point in the camera frame.
  Eigen::Vector3f backProject(float u, float v, float depth_m) const {
    return {static_cast<float>((u - cx) / fx) * depth_m, static_cast<float>((v - cy) / fy) * depth_m,
            depth_m};
  }

  /// Projection of a point in the camera frame to continuous pixel coordinates; z must be > 0.
  Eigen::Vector2f project(const Eigen::Vector3f& p_C) const {
    return {static_cast<float>(fx * p_C.x() / p_C.z() + cx),
            static_cast<float>(fy * p_C.y() / p_C.z() + cy)};
  }

  /// The TUM RGB-D benchmark's freiburg1 depth camera, the documented default for sequences
  /// that carry no intrinsics.txt.
  static PinholeCamera tumFreiburg1();
};

}  // namespace sdf_tracker
