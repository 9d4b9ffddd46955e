#pragma once

#include <cstdint>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
#include "sdf_tracker/camera/depth_image.h"

namespace sdf_tracker {

/// Removes a camera's lens distortion from its depth images, so that the ideal pinhole model
/// (PinholeCamera::backProject / project) holds for them. Each pixel of the undistorted image takes
/// the depth of the distorted image's pixel nearest to where the lens imaged that pixel's ray:
/// depth along the optical axis does not change with the lens, and no depth is blended across an
/// edge. The pixel map is computed once, here.
class DepthUndistortion {
 public:
  /// Throws std::invalid_argument for an invalid camera.
  explicit DepthUndistortion(const PinholeCamera& camera);

  /// The camera the map was made for (with its distortion).
  const PinholeCamera& camera() const { return camera_; }

  /// `distorted` must have the camera's size (throws std::invalid_argument otherwise). Pixels whose
  /// ray the lens puts outside the image hold no measurement.
  DepthImage apply(const DepthImage& distorted) const;
  /// The same pixel map for a colour image registered to the depth, into `ideal` (its memory
  /// reused from frame to frame): each undistorted pixel takes the colour of the pixel its depth
  /// came from; black where the ray leaves the image.
  void apply(const ColourImage& distorted, ColourImage* ideal) const;

 private:
  PinholeCamera camera_;
  std::vector<int32_t> source_index_;  ///< per undistorted pixel: the distorted pixel's index, or -1
};

}  // namespace sdf_tracker
