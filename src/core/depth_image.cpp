#include "sdf_tracker/core/depth_image.h"

#include <algorithm>

namespace sdf_tracker {

int DepthImage::countMeasurements() const {
  return static_cast<int>(std::count_if(data_m_.begin(), data_m_.end(), isMeasurement));
}

DepthImage DepthImage::fromRaw16(const uint16_t* raw, int width, int height, double depth_factor) {
  DepthImage image(width, height);
  const float scale = static_cast<float>(1.0 / depth_factor);
  const size_t n = static_cast<size_t>(width) * height;
  for (size_t i = 0; i < n; ++i) {
    image.data_m_[i] = raw[i] == 0 ? 0.0f : static_cast<float>(raw[i]) * scale;
  }
  return image;
}

}  // namespace sdf_tracker
