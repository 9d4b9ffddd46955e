#pragma once

#include <array>
#include <cstdint>

namespace sdf_tracker::devices {

/// What a Kinect v1 sends per depth pixel: an 11-bit disparity ("shift"), 2047 where the pattern
/// was not seen.
constexpr uint16_t kKinectNoDisparity = 2047;
/// libfreenect's depth modes end at 10 m.
constexpr uint16_t kKinectMaxDepth_mm = 10000;

/// The zero-plane calibration a Kinect v1 stores in its firmware, in libfreenect's units
/// (freenect_zero_plane_info and const_shift). Each unit stores its own; the defaults are values
/// commonly reported for Kinect v1 units (not read from a device here), used where the library
/// cannot read them (fakenect) and by tum_to_fakenect. The driver reads a real device's own.
struct KinectZeroPlane {
  double reference_distance_cm = 120.0;   ///< zero plane distance
  double reference_pixel_size_cm = 0.1042;  ///< zero plane pixel size
  double emitter_to_dcmos_cm = 7.5;       ///< baseline between the projector and the IR camera
  double const_shift = 200.0;

  /// The depth camera's focal length in pixels of a 640-wide image, as freenect_camera derives it.
  double focalLength640_px() const { return reference_distance_cm / (2.0 * reference_pixel_size_cm); }
};

/// libfreenect's disparity-to-depth model (the one behind FREENECT_DEPTH_MM), as a table both
/// ways: the Kinect driver converts what the device sends, tum_to_fakenect makes what a device
/// would have sent for a depth in millimetres.
class KinectDisparityTable {
 public:
  explicit KinectDisparityTable(const KinectZeroPlane& zero_plane = {});

  /// Depth in mm of a raw disparity; 0 (no depth) for 2047 and values outside the model's range.
  uint16_t toMillimetres(uint16_t disparity) const {
    return disparity < depth_mm_.size() ? depth_mm_[disparity] : 0;
  }
  /// The disparity whose depth is nearest to depth_mm; 2047 for 0 and depths the sensor cannot
  /// report (nearer than the first or farther than the last disparity's depth, by half a step).
  uint16_t fromMillimetres(uint16_t depth_mm) const;

  uint16_t nearest_mm() const { return depth_mm_[first_valid_]; }
  uint16_t farthest_mm() const { return depth_mm_[last_valid_]; }

 private:
  std::array<uint16_t, kKinectNoDisparity + 1> depth_mm_{};
  uint16_t first_valid_ = 0, last_valid_ = 0;
};

}  // namespace sdf_tracker::devices
