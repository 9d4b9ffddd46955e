#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace sdf_tracker {

/// A depth image in float metres, row-major. A pixel is a measurement when it is finite and > 0;
/// NaN, infinity, zero and negative values all mean "no measurement" (REP 118).
class DepthImage {
 public:
  DepthImage() = default;
  DepthImage(int width, int height, float fill_m = 0.0f)
      : width_(width), height_(height), data_m_(static_cast<size_t>(width) * height, fill_m) {}

  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return data_m_.empty(); }

  float& at(int u, int v) { return data_m_[static_cast<size_t>(v) * width_ + u]; }
  float at(int u, int v) const { return data_m_[static_cast<size_t>(v) * width_ + u]; }
  float* data() { return data_m_.data(); }
  const float* data() const { return data_m_.data(); }

  static bool isMeasurement(float depth_m) { return std::isfinite(depth_m) && depth_m > 0.0f; }

  /// Number of pixels that hold a measurement.
  int countMeasurements() const;
  /// The furthest measured depth [m]; 0 when there is none.
  float maxMeasurement() const;

  /// Converts raw 16-bit depth (value / depth_factor metres, 0 = none) to metres, once, at the edge.
  static DepthImage fromRaw16(const uint16_t* raw, int width, int height, double depth_factor);
  /// The inverse, row by row: round(metres * depth_factor); 0 where there is no measurement or the
  /// value does not fit in 16 bits.
  std::vector<uint16_t> toRaw16(double depth_factor) const;

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<float> data_m_;
};

}  // namespace sdf_tracker
