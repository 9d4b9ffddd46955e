#include "sdf_tracker/camera/camera.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

Eigen::Vector2d LensDistortion::undistort(const Eigen::Vector2d& distorted) const {
  Eigen::Vector2d ideal = distorted;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d step = distorted - distort(ideal);
    ideal += step;
    if (step.squaredNorm() < 1e-20) break;
  }
  return ideal;
}

std::string LensDistortion::summary(const std::string& source) const {
  std::ostringstream text;
  if (isZero()) {
    text << "lens distortion: none (" << source << ")";
  } else {
    text << "lens distortion removed from every image: k1 " << k1 << " k2 " << k2 << " p1 " << p1 << " p2 " << p2
         << " k3 " << k3 << " (" << source << ")";
  }
  return text.str();
}

std::vector<std::string> PinholeCamera::validate() const {
  Violations v;
  v.requirePositive("fx", fx);
  v.requirePositive("fy", fy);
  v.requireFinite("cx", cx);
  v.requireFinite("cy", cy);
  v.requirePositive("width", width);
  v.requirePositive("height", height);
  v.requireFinite("k1", distortion.k1);
  v.requireFinite("k2", distortion.k2);
  v.requireFinite("p1", distortion.p1);
  v.requireFinite("p2", distortion.p2);
  v.requireFinite("k3", distortion.k3);
  return v.list();
}

std::string PinholeCamera::sizeMismatch(int image_width, int image_height) const {
  if (image_width == width && image_height == height) return "";
  std::ostringstream msg;
  msg << "depth image is " << image_width << "x" << image_height << " but the camera is " << width << "x" << height;
  return msg.str();
}

PinholeCamera PinholeCamera::scaledTo(int new_width, int new_height) const {
  if (new_width <= 0 || new_height <= 0 || width % new_width != 0 || height % new_height != 0 ||
      width / new_width != height / new_height) {
    std::ostringstream msg;
    msg << "image size " << new_width << "x" << new_height << " is not an integer fraction of the "
        << width << "x" << height << " the intrinsics were given for";
    throw std::invalid_argument(msg.str());
  }
  const double factor = static_cast<double>(width / new_width);
  PinholeCamera scaled = *this;
  scaled.fx = fx / factor;
  scaled.fy = fy / factor;
  // Pixel centres: continuous coordinate c maps to (c + 0.5) / factor - 0.5.
  scaled.cx = (cx + 0.5) / factor - 0.5;
  scaled.cy = (cy + 0.5) / factor - 0.5;
  scaled.width = new_width;
  scaled.height = new_height;
  return scaled;
}

namespace {

/// TUM RGB-D's published colour-camera calibrations (vision.in.tum.de, "file formats"), 640x480.
/// freiburg3's images were undistorted by TUM: its distortion is zero.
struct TumCalibration {
  const char* name;
  double fx, fy, cx, cy;
  LensDistortion distortion;

  PinholeCamera camera() const {
    PinholeCamera c;
    c.fx = fx, c.fy = fy, c.cx = cx, c.cy = cy;
    c.width = 640, c.height = 480;
    c.distortion = distortion;
    return c;
  }
};
constexpr TumCalibration kTumCameras[] = {
    {"freiburg1", 517.3, 516.5, 318.6, 255.3, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}},
    {"freiburg2", 520.9, 521.0, 325.1, 249.7, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172}},
    {"freiburg3", 535.4, 539.2, 320.1, 247.6, {}},
};
constexpr double kOpenNiDefaultFocal_px = 525.0;  ///< at 640x480

}  // namespace

PinholeCamera PinholeCamera::tumFreiburg1() { return tumCamera("freiburg1")->withoutDistortion(); }

std::optional<PinholeCamera> PinholeCamera::tumCamera(const std::string& name) {
  for (const TumCalibration& c : kTumCameras) {
    if (name == c.name) return c.camera();
  }
  return std::nullopt;
}

std::string PinholeCamera::tumCameraNames() {
  std::string names;
  for (const TumCalibration& c : kTumCameras) names += (names.empty() ? "" : ", ") + std::string(c.name);
  return names;
}

std::string PinholeCamera::tumCameraMentionedIn(const std::string& name) {
  for (const TumCalibration& c : kTumCameras) {
    if (name.find(c.name) != std::string::npos) return c.name;
  }
  return "";
}

PinholeCamera PinholeCamera::openNiDefault(int width, int height) {
  PinholeCamera camera;
  camera.fx = camera.fy = kOpenNiDefaultFocal_px * width / 640.0;
  camera.cx = (width - 1) / 2.0;
  camera.cy = (height - 1) / 2.0;
  camera.width = width;
  camera.height = height;
  return camera;
}

std::string PinholeCamera::tumCameraWithIntrinsicsOf(const PinholeCamera& camera) {
  constexpr double kTolerance_px = 0.05;
  if (camera.width != 640 || camera.height != 480) return "";
  for (const TumCalibration& c : kTumCameras) {
    if (c.distortion.isZero()) continue;  // nothing the user would miss
    if (std::abs(camera.fx - c.fx) <= kTolerance_px && std::abs(camera.fy - c.fy) <= kTolerance_px &&
        std::abs(camera.cx - c.cx) <= kTolerance_px && std::abs(camera.cy - c.cy) <= kTolerance_px) {
      return c.name;
    }
  }
  return "";
}

Eigen::AlignedBox3f PinholeCamera::viewBox(const Eigen::Isometry3f& T_W_C, float z_far_m) const {
  Eigen::AlignedBox3f box(T_W_C.translation());
  for (const float u : {-0.5f, width - 0.5f}) {
    for (const float v : {-0.5f, height - 0.5f}) box.extend(T_W_C * backProject(u, v, z_far_m));
  }
  return box;
}

}  // namespace sdf_tracker
