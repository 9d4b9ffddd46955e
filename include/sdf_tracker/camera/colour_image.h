#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sdf_tracker {

/// A colour image, 8-bit RGB, row-major, three bytes a pixel. The map is coloured from images
/// registered to the depth: pixel (u, v) of the colour image sees what pixel (u, v) of the depth
/// image measured (a TUM RGB-D recording, a camera's depth_registered stream).
class ColourImage {
 public:
  ColourImage() = default;
  ColourImage(int width, int height, uint8_t fill = 0)
      : width_(width), height_(height), rgb_(static_cast<size_t>(width) * height * 3, fill) {}

  int width() const { return width_; }
  int height() const { return height_; }
  bool empty() const { return rgb_.empty(); }

  /// The pixel's red, green and blue.
  uint8_t* at(int u, int v) { return rgb_.data() + (static_cast<size_t>(v) * width_ + u) * 3; }
  const uint8_t* at(int u, int v) const { return rgb_.data() + (static_cast<size_t>(v) * width_ + u) * 3; }
  uint8_t* data() { return rgb_.data(); }
  const uint8_t* data() const { return rgb_.data(); }

  /// Why this image cannot colour a depth image of width x height ("the colour image is 320x240,
  /// the depth image 640x480"), or "" when it can.
  std::string sizeMismatch(int depth_width, int depth_height) const;

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<uint8_t> rgb_;
};

}  // namespace sdf_tracker
