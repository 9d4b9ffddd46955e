#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sdf_tracker/core/camera.h"
#include "sdf_tracker/core/depth_image.h"
#include "sdf_tracker/core/io.h"

namespace sdf_tracker {

/// Overrides for what a sequence folder says about itself.
struct SequenceOptions {
  std::optional<PinholeCamera> camera;
  std::optional<double> depth_factor;
};

/// A depth sequence in the TUM RGB-D layout: depth.txt ("timestamp depth/<file>.png"), 16-bit
/// PNGs, optional groundtruth.txt and intrinsics.txt ("fx fy cx cy width height depth_factor").
/// Intrinsics and depth factor come from the options, else intrinsics.txt, else the TUM
/// freiburg1 defaults (517.3, 516.5, 318.6, 255.3; factor 5000).
class TumSequence {
 public:
  /// Throws std::runtime_error naming the file and the problem.
  static TumSequence open(const std::string& directory, const SequenceOptions& options = {});

  size_t size() const { return frames_.size(); }
  double timestamp(size_t i) const { return frames_.at(i).timestamp_s; }
  const std::string& depthPath(size_t i) const { return frames_.at(i).path; }
  /// Reads frame i in metres; throws std::runtime_error for a missing or corrupt file.
  DepthImage depth(size_t i) const;

  const PinholeCamera& camera() const { return camera_; }
  double depthFactor() const { return depth_factor_; }
  /// Where the intrinsics came from, for the user: "options", "intrinsics.txt" or "TUM freiburg1 defaults".
  const std::string& intrinsicsSource() const { return intrinsics_source_; }
  const std::vector<io::StampedPose>& groundTruth() const { return ground_truth_; }

  /// Drops every frame after the first n.
  void truncate(size_t n) {
    if (n < frames_.size()) frames_.resize(n);
  }

  static constexpr double kTumDepthFactor = 5000.0;

 private:
  struct Frame {
    double timestamp_s;
    std::string path;
  };
  std::vector<Frame> frames_;
  PinholeCamera camera_;
  double depth_factor_ = kTumDepthFactor;
  std::string intrinsics_source_;
  std::vector<io::StampedPose> ground_truth_;
};

}  // namespace sdf_tracker
