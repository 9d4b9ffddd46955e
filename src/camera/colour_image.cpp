#include "sdf_tracker/camera/colour_image.h"

#include <sstream>

namespace sdf_tracker {

std::string ColourImage::sizeMismatch(int depth_width, int depth_height) const {
  if (width_ == depth_width && height_ == depth_height) return "";
  std::ostringstream s;
  s << "the colour image is " << width_ << "x" << height_ << ", the depth image " << depth_width << "x" << depth_height
    << ": colour must be registered to the depth, pixel for pixel";
  return s.str();
}

}  // namespace sdf_tracker
