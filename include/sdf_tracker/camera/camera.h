#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sdf_tracker {

/// Lens distortion in the plumb-bob model (OpenCV's and sensor_msgs/CameraInfo's k1 k2 p1 p2 k3),
/// acting on normalised image coordinates, so the same coefficients hold at every resolution.
struct LensDistortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  bool isZero() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
  /// Where the lens images the ideal normalised point (x, y) = (X/Z, Y/Z).
  Eigen::Vector2d distort(const Eigen::Vector2d& ideal) const {
    const double x = ideal.x(), y = ideal.y(), r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
  }
  /// The inverse of distort: the ideal normalised point the lens imaged at `distorted` (fixed-point
  /// iteration, exact to ~1e-9 for the moderate distortion of depth cameras).
  Eigen::Vector2d undistort(const Eigen::Vector2d& distorted) const;
  bool operator==(const LensDistortion& o) const {
    return k1 == o.k1 && k2 == o.k2 && p1 == o.p1 && p2 == o.p2 && k3 == o.k3;
  }
  /// For the user: "lens distortion: none (<source>)" or "lens distortion removed from every
  /// image: k1 .. k3 .. (<source>)".
  std::string summary(const std::string& source) const;
};

/// Intrinsics of a depth camera, in pixels. The optical frame is x right, y down, z forward
/// (REP 103 optical convention). backProject and project are the ideal pinhole; a camera with
/// lens distortion has its depth images undistorted first (DepthUndistortion), as the pipeline
/// does with every frame.
struct PinholeCamera {
  double fx = 520.0;
  double fy = 520.0;
  double cx = 319.5;
  double cy = 239.5;
  int width = 640;
  int height = 480;
  LensDistortion distortion;

  /// Every violated constraint, in words; empty when the camera is usable.
  std::vector<std::string> validate() const;
  /// Why an image of this size cannot come from this camera, in words; empty when the sizes match.
  std::string sizeMismatch(int image_width, int image_height) const;
  /// The same intrinsics without lens distortion: the camera of its undistorted images.
  PinholeCamera withoutDistortion() const {
    PinholeCamera ideal = *this;
    ideal.distortion = LensDistortion();
    return ideal;
  }

  /// The same lens at another resolution of the same sensor (VGA 640x480 -> QVGA 320x240 -> QQVGA
  /// 160x120, as the reference release scales its parameters). Throws std::invalid_argument when
  /// the new size is not a positive integer fraction of the current one.
  PinholeCamera scaledTo(int new_width, int new_height) const;

  /// Back-projection, eq. (3): pixel (u, v) with depth z [m] -> point in the camera frame.
  Eigen::Vector3f backProject(float u, float v, float depth_m) const {
    return {static_cast<float>((u - cx) / fx) * depth_m, static_cast<float>((v - cy) / fy) * depth_m,
            depth_m};
  }

  /// The world box around what the camera at T_W_C sees up to depth z_far_m: its centre and the
  /// image's outer corners at z_far_m.
  Eigen::AlignedBox3f viewBox(const Eigen::Isometry3f& T_W_C, float z_far_m) const;

  /// Projection of a point in the camera frame to continuous pixel coordinates; z must be > 0.
  Eigen::Vector2f project(const Eigen::Vector3f& p_C) const {
    return {static_cast<float>(fx * p_C.x() / p_C.z() + cx),
            static_cast<float>(fy * p_C.y() / p_C.z() + cy)};
  }

  bool operator==(const PinholeCamera& o) const {
    return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && width == o.width && height == o.height &&
           distortion == o.distortion;
  }
  bool operator!=(const PinholeCamera& o) const { return !(*this == o); }

  /// The TUM RGB-D benchmark's freiburg1 intrinsics (of the colour camera, to which the depth images
  /// are registered), without lens distortion: tumCamera("freiburg1") has that too.
  static PinholeCamera tumFreiburg1();

  /// The calibration TUM publishes for one of the benchmark's cameras ("freiburg1", "freiburg2",
  /// "freiburg3"; 640x480), intrinsics and lens distortion; nothing for any other name. The
  /// benchmark's bags do not carry it: their camera_info holds the OpenNI driver's default.
  static std::optional<PinholeCamera> tumCamera(const std::string& name);
  /// The names tumCamera knows, for messages: "freiburg1, freiburg2, freiburg3".
  static std::string tumCameraNames();
  /// The name of the TUM camera that `name` mentions, as the benchmark names its downloads
  /// (rgbd_dataset_freiburg2_desk -> "freiburg2"); empty when it mentions none.
  static std::string tumCameraMentionedIn(const std::string& name);

  /// What the OpenNI driver reported when it knew no calibration (the TUM bags of 2011 carry it):
  /// fx = fy = 525 px at 640x480, the centre of the image, no distortion; scaled to the size.
  static PinholeCamera openNiDefault(int width, int height);

  /// The TUM camera whose published intrinsics these are, with a lens distortion TUM publishes
  /// beside them (freiburg1 or freiburg2 at 640x480, matched to 0.05 px), or "". For a hint to the
  /// user only: intrinsics that match a known camera are a coincidence to report, not a
  /// calibration to apply (a simulator or another camera may use the same numbers).
  static std::string tumCameraWithIntrinsicsOf(const PinholeCamera& camera);
};

}  // namespace sdf_tracker
