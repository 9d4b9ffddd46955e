#include "sdf_tracker/devices/kinect_disparity.h"

#include <cmath>
#include <stdexcept>

namespace sdf_tracker::devices {

namespace {
// libfreenect's registration constants (registration.c).
constexpr double kParameterCoefficient = 4.0;
constexpr double kShiftScale = 10.0;
constexpr double kS2dConstOffset = 0.375;

/// Depth in mm (not rounded) of a raw disparity; not finite or <= 0 outside the model.
double depthOf(double disparity, const KinectZeroPlane& z) {
  const double fixed_ref_x = (disparity - kParameterCoefficient * z.const_shift) / kParameterCoefficient - kS2dConstOffset;
  const double metric = fixed_ref_x * z.reference_pixel_size_cm;
  return kShiftScale * (metric * z.reference_distance_cm / (z.emitter_to_dcmos_cm - metric) + z.reference_distance_cm);
}
}  // namespace

KinectDisparityTable::KinectDisparityTable(const KinectZeroPlane& zero_plane) {
  bool any = false;
  double previous = 0.0;
  for (uint16_t d = 0; d < kKinectNoDisparity; ++d) {
    const double mm = depthOf(d, zero_plane);
    // Depth grows with disparity up to the pole of the model; beyond it the values are meaningless.
    const bool valid = std::isfinite(mm) && mm >= 1.0 && mm < kKinectMaxDepth_mm && (!any || mm > previous);
    if (!valid) {
      if (any && mm <= previous) break;
      continue;
    }
    depth_mm_[d] = static_cast<uint16_t>(std::lround(mm));
    if (!any) first_valid_ = d;
    last_valid_ = d;
    any = true;
    previous = mm;
  }
  if (!any || last_valid_ - first_valid_ < 100) {
    throw std::invalid_argument("Kinect zero-plane calibration gives no usable depth range");
  }
}

uint16_t KinectDisparityTable::fromMillimetres(uint16_t depth_mm) const {
  if (depth_mm == 0) return kKinectNoDisparity;
  // Valid depths grow with disparity: binary search for the first disparity at or beyond depth_mm.
  uint16_t lo = first_valid_, hi = last_valid_;
  if (depth_mm < depth_mm_[lo]) {
    return 2 * depth_mm >= depth_mm_[lo] + (depth_mm_[lo] - depth_mm_[lo + 1]) ? lo : kKinectNoDisparity;
  }
  if (depth_mm > depth_mm_[hi]) {
    return 2 * depth_mm <= 2 * depth_mm_[hi] + (depth_mm_[hi] - depth_mm_[hi - 1]) ? hi : kKinectNoDisparity;
  }
  while (lo < hi) {
    const uint16_t mid = static_cast<uint16_t>((lo + hi) / 2);
    if (depth_mm_[mid] < depth_mm) {
      lo = static_cast<uint16_t>(mid + 1);
    } else {
      hi = mid;
    }
  }
  // depth_mm_[lo] >= depth_mm > depth_mm_[lo - 1] (or lo is the first): take the nearer.
  if (lo > first_valid_ && depth_mm - depth_mm_[lo - 1] < depth_mm_[lo] - depth_mm) return static_cast<uint16_t>(lo - 1);
  return lo;
}

}  // namespace sdf_tracker::devices
