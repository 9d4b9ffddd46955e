#pragma once

#include <cstddef>
#include <vector>

#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/io/tum_sequence.h"
#include "sdf_tracker/surface/surface.h"

/// How well a coloured mesh agrees with the colour images it was made from.
namespace sdf_tracker::evaluation {

struct ColourAgreement {
  size_t frames = 0;       ///< colour images compared with
  size_t comparisons = 0;  ///< vertex views: a vertex seen in a frame
  /// Over the comparisons: the mean absolute difference of a channel [levels of 0-255], and the
  /// mean and median distance between the two RGB colours [levels].
  double mean_channel_difference = 0.0;
  double mean_distance = 0.0;
  double median_distance = 0.0;
};

/// Every `frame_step`-th frame of `sequence` that has a colour image and a pose in `trajectory`
/// (its camera to the mesh's world, at the frame's timestamp within 0.02 s): each vertex that
/// projects into its image, in front of the camera and within `depth_tolerance_m` of the depth
/// measured there (so seen, not hidden), compared with the colour of that pixel. Both images are
/// undistorted as the tracker does. Throws std::invalid_argument for a mesh without colours or a
/// frame_step below 1, and std::runtime_error for an unreadable image.
ColourAgreement compareMeshColours(const TriangleMesh& mesh, const TumSequence& sequence,
                                   const std::vector<io::StampedPose>& trajectory, int frame_step,
                                   double depth_tolerance_m = 0.02);

}  // namespace sdf_tracker::evaluation
