#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/places/place_descriptor.h"

namespace sdf_tracker {

/// A view the map was built from: where the camera was, and how the view looked.
struct Keyframe {
  Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
  PlaceCode code;
};

struct PlaceMemoryConfig {
  PlaceDescriptorConfig descriptor;
  /// A tracked view is looked at for a keyframe only once the camera has moved this far (or
  /// turned this much) since the last one looked at: most frames cost nothing.
  double check_translation_m = 0.05;
  double check_rotation_rad = 0.0872664626;  // 5 degrees
  /// A view becomes a keyframe unless some keyframe lies within keyframe_spacing_m and
  /// keyframe_spacing_rad of it and has a code that differs from its own by less than min_novelty
  /// (PlaceEncoder::dissimilarity): keyframes every ~10 cm or 10 degrees along the path, more
  /// where the view changes without the camera moving.
  double keyframe_spacing_m = 0.1;
  double keyframe_spacing_rad = 0.174532925;  // 10 degrees
  double min_novelty = 0.2;
  /// No keyframe is added beyond this many: the memory's bound.
  int max_keyframes = 20000;

  std::vector<std::string> validate() const;
};

/// The places a map was built from, to find the camera again when it does not know where it is:
/// keyframes added as the map grows (when the view is new enough), looked up by how alike their
/// codes are. Bounded by max_keyframes; see bytesPerKeyframe(). Not thread safe.
class PlaceMemory {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit PlaceMemory(const PlaceMemoryConfig& config = PlaceMemoryConfig());

  const PlaceMemoryConfig& config() const { return config_; }
  const PlaceEncoder& encoder() const { return encoder_; }
  const std::vector<Keyframe>& keyframes() const { return keyframes_; }
  bool empty() const { return keyframes_.empty(); }
  /// The bytes each keyframe holds: its code (one byte per fern), its pose, the vector's own.
  size_t bytesPerKeyframe() const;

  /// A tracked view (depth as the tracker takes it) at T_W_C: becomes a keyframe when the camera
  /// has moved enough since the last view looked at and the view is new enough. Returns whether
  /// it was added.
  bool offer(const DepthImage& depth, const Eigen::Isometry3d& T_W_C);
  /// Adds a keyframe as it is (a loaded one). Throws std::invalid_argument when its code does not
  /// come from this memory's descriptor (the wrong fern count) or the memory is full.
  void add(Keyframe keyframe);

  struct Match {
    size_t keyframe;       ///< index into keyframes()
    double dissimilarity;  ///< PlaceEncoder::dissimilarity
  };
  /// The (at most) `count` keyframes whose codes are most like `code`, most alike first.
  std::vector<Match> mostAlike(const PlaceCode& code, size_t count) const;

  void clear();

 private:
  PlaceMemoryConfig config_;
  PlaceEncoder encoder_;
  std::vector<Keyframe> keyframes_;
  bool checked_any_ = false;
  Eigen::Isometry3d T_W_C_last_checked_ = Eigen::Isometry3d::Identity();
};

}  // namespace sdf_tracker
