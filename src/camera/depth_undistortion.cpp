#include "sdf_tracker/camera/depth_undistortion.h"

#include <cmath>
#include <stdexcept>

#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

DepthUndistortion::DepthUndistortion(const PinholeCamera& camera) : camera_(camera) {
  throwIfInvalid("camera", camera.validate());
  source_index_.assign(static_cast<size_t>(camera.width) * camera.height, -1);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      // Where the lens puts the ray of undistorted pixel (u, v): the nearest distorted pixel holds its depth.
      const Eigen::Vector2d ideal((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy);
      const Eigen::Vector2d seen = camera.distortion.distort(ideal);
      const long us = std::lround(camera.fx * seen.x() + camera.cx), vs = std::lround(camera.fy * seen.y() + camera.cy);
      if (us >= 0 && us < camera.width && vs >= 0 && vs < camera.height) {
        source_index_[static_cast<size_t>(v) * camera.width + u] = static_cast<int32_t>(vs * camera.width + us);
      }
    }
  }
}

DepthImage DepthUndistortion::apply(const DepthImage& distorted) const {
  if (const std::string mismatch = camera_.sizeMismatch(distorted.width(), distorted.height()); !mismatch.empty()) {
    throw std::invalid_argument(mismatch);
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

void DepthUndistortion::apply(const ColourImage& distorted, ColourImage* ideal) const {
  if (const std::string mismatch = camera_.sizeMismatch(distorted.width(), distorted.height()); !mismatch.empty()) {
    throw std::invalid_argument(mismatch);
  }
  if (ideal->width() != camera_.width || ideal->height() != camera_.height) {
    *ideal = ColourImage(camera_.width, camera_.height);
  }
  const uint8_t* in = distorted.data();
  uint8_t* out = ideal->data();
  const long n = static_cast<long>(source_index_.size());
  // Part of every coloured frame's fusion: shared among the threads.
#pragma omp parallel for schedule(static)
  for (long i = 0; i < n; ++i) {
    uint8_t* to = out + 3 * i;
    const int32_t source = source_index_[static_cast<size_t>(i)];
    if (source < 0) {
      to[0] = to[1] = to[2] = 0;
      continue;
    }
    const uint8_t* from = in + 3 * static_cast<size_t>(source);
    to[0] = from[0], to[1] = from[1], to[2] = from[2];
  }
}

}  // namespace sdf_tracker
