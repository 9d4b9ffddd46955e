#pragma once

#include <string>

#include "sdf_tracker/camera/colour_image.h"

/// Colour images as files: PNG or JPEG, as the TUM RGB-D benchmark and its converters store them.
namespace sdf_tracker::io {

/// An 8-bit colour or greyscale PNG or JPEG, as RGB (grey in all three channels). Throws
/// std::runtime_error naming the file when it is missing or cannot be decoded, when it holds
/// 16-bit values (a depth image, not colour), or when it is not expected_width x expected_height
/// (when given).
ColourImage readColourImage(const std::string& path, int expected_width = 0, int expected_height = 0);
/// A PNG, or a JPEG (quality 90) for a path ending in .jpg or .jpeg; any other extension is refused.
void writeColourImage(const std::string& path, const ColourImage& image);

}  // namespace sdf_tracker::io
