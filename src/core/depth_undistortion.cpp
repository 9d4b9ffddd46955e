#include "sdf_tracker/core/depth_undistortion.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

DepthUndistortion::DepthUndistortion(const PinholeCamera& camera) : camera_(camera) {
  throwIfInvalid("camera", camera.validate());
  source_index_.assign(static_cast<size_t>(camera.width) * camera.height, -1);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector2d seen = camera.distortion.distort({(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy});
      const long us = std::lround(camera.fx * seen.x() + camera.cx), vs = std::lround(camera.fy * seen.y() + camera.cy);
      if (us >= 0 && us < camera.width && vs >= 0 && vs < camera.height) {
        source_index_[static_cast<size_t>(v) * camera.width + u] = static_cast<int32_t>(vs * camera.width + us);
      }
    }
  }
}

PinholeCamera DepthUndistortion::idealCamera() const {
  PinholeCamera ideal = camera_;
  ideal.distortion = LensDistortion();
  return ideal;
}

DepthImage DepthUndistortion::apply(const DepthImage& distorted) const {
  if (distorted.width() != camera_.width || distorted.height() != camera_.height) {
    std::ostringstream msg;
    msg << "depth image is " << distorted.width() << "x" << distorted.height() << " but the camera is "
        << camera_.width << "x" << camera_.height;
    throw std::invalid_argument(msg.str());
  }
  DepthImage ideal(camera_.width, camera_.height);
  const float* in = distorted.data();
  float* out = ideal.data();
  const size_t n = source_index_.size();
  for (size_t i = 0; i < n; ++i) {
    if (source_index_[i] >= 0) out[i] = in[source_index_[i]];
  }
  return ideal;
}

}  // namespace sdf_tracker
