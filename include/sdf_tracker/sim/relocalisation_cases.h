#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/io/trajectory_file.h"
#include "sdf_tracker/sim/synthetic.h"

/// Second sessions in a saved map, made to try the relocaliser where it is hard: a view much of
/// which the map never saw, and places that look alike. The same cases drive the pipeline's tests
/// (in memory) and the relocalisation bench (written in TUM layout by sdf_tracker_synth).
namespace sdf_tracker::synthetic {

struct RelocalisationCase {
  std::string name;
  std::string description;
  Scene scene;
  /// The first session: fused at these true poses (its map and place memory are what the second
  /// session loads).
  std::vector<io::StampedPose> mapping;
  /// The first session saw only the left half of each of its views.
  bool mapping_saw_left_half_only = false;
  /// The second session, with no idea where it is.
  std::vector<io::StampedPose> session;
  /// Every view of the second session fits two places alike: accepting any is a false acceptance.
  bool ambiguous = false;

  DepthImage mappingView(size_t frame, const PinholeCamera& camera, const NoiseModel& noise, uint32_t seed) const;
  DepthImage sessionView(size_t frame, const PinholeCamera& camera, const NoiseModel& noise, uint32_t seed) const;
};

/// The cases' names: half-new, two-rooms, symmetric-room, two-desks.
std::vector<std::string> relocalisationCaseNames();
/// Throws std::invalid_argument naming the cases when `name` is none of them.
RelocalisationCase relocalisationCase(const std::string& name);

/// Writes the case as two TUM-layout folders, directory/mapping and directory/session (each with
/// depth/, depth.txt, groundtruth.txt, intrinsics.txt), and directory/case.txt saying what it is.
void writeRelocalisationCase(const std::string& directory, const RelocalisationCase& c, const PinholeCamera& camera,
                             const NoiseModel& noise, uint32_t seed);

}  // namespace sdf_tracker::synthetic
