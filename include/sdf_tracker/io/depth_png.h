#pragma once

#include <string>

#include "sdf_tracker/camera/depth_image.h"

/// Depth images as 16-bit PNG files, as the TUM RGB-D benchmark stores them.
namespace sdf_tracker::io {

/// What a PNG's header says, read without decoding the image.
struct PngHeader {
  int width = 0;
  int height = 0;
  int bit_depth = 0;
  int colour_type = 0;  ///< 0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA
  std::string describe() const;  ///< "16-bit RGB"
};
/// Reads the signature and IHDR chunk; throws std::runtime_error for anything else.
PngHeader readPngHeader(const std::string& path);

/// A 16-bit single-channel (greyscale) PNG; metres = value / depth_factor, 0 = no measurement.
/// The header is checked before anything is decoded: other formats (RGB, grey + alpha, 8-bit)
/// are refused, not converted, and so is a size other than expected_width x expected_height
/// (when given) or one beyond kMaxImagePixels.
DepthImage readDepthPng(const std::string& path, double depth_factor, int expected_width = 0,
                        int expected_height = 0);
/// No depth image larger than this is decoded (a 4096 x 4096 image, 32 MiB of 16-bit depth).
constexpr long long kMaxImagePixels = 4096LL * 4096LL;
void writeDepthPng(const std::string& path, const DepthImage& depth, double depth_factor);

}  // namespace sdf_tracker::io
