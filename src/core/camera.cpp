#include "sdf_tracker/core/camera.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

std::vector<std::string> PinholeCamera::validate() const {
  Violations v;
  v.requirePositive("fx", fx);
  v.requirePositive("fy", fy);
  v.requireFinite("cx", cx);
  v.requireFinite("cy", cy);
  v.requirePositive("width", width);
  v.requirePositive("height", height);
  return v.list();
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

PinholeCamera PinholeCamera::tumFreiburg1() {
  PinholeCamera camera;
  camera.fx = 517.3;
  camera.fy = 516.5;
  camera.cx = 318.6;
  camera.cy = 255.3;
  camera.width = 640;
  camera.height = 480;
  return camera;
}

}  // namespace sdf_tracker
