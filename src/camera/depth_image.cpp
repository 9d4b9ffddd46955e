#include "sdf_tracker/camera/depth_image.h"

#include <algorithm>
#include <cmath>

namespace sdf_tracker {

int DepthImage::countMeasurements() const {
  return static_cast<int>(std::count_if(data_m_.begin(), data_m_.end(), isMeasurement));
}

float DepthImage::maxMeasurement() const {
  float furthest = 0.0f;
  for (const float z : data_m_) {
    if (isMeasurement(z)) furthest = std::max(furthest, z);
  }
  return furthest;
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

std::vector<uint16_t> DepthImage::toRaw16(double depth_factor) const {
  std::vector<uint16_t> raw(data_m_.size());
  for (size_t i = 0; i < raw.size(); ++i) {
    const double value = isMeasurement(data_m_[i]) ? std::round(data_m_[i] * depth_factor) : 0.0;
    raw[i] = static_cast<uint16_t>(value > 65535.0 ? 0.0 : value);
  }
  return raw;
}

}  // namespace sdf_tracker
