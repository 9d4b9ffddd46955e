#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/depth_image.h"
#include "sdf_tracker/io/trajectory_file.h"

namespace sdf_tracker {

/// Overrides for what a sequence folder says about itself.
struct SequenceOptions {
  /// Intrinsics and lens distortion.
  std::optional<PinholeCamera> camera;
  /// Replaces the lens distortion only (of the options' camera, intrinsics.txt or the defaults).
  std::optional<LensDistortion> distortion;
  std::optional<double> depth_factor;
};

/// A depth sequence in the TUM RGB-D layout: depth.txt ("timestamp depth/<file>.png"), 16-bit
/// PNGs, optional groundtruth.txt and intrinsics.txt (kIntrinsicsColumns).
/// Intrinsics and depth factor come from the options, else intrinsics.txt, else the TUM camera
/// the folder's name mentions as TUM names its downloads (rgbd_dataset_freiburg2_desk: freiburg2's
/// published calibration), else the TUM freiburg1 defaults (517.3, 516.5, 318.6, 255.3); factor
/// 5000. The lens distortion is what the data states: the options' --distortion, else
/// intrinsics.txt's last five columns (without them: none), else the distortion TUM publishes for
/// the camera the folder's name gives; else none. It is never inferred from intrinsics that happen
/// to be a TUM camera's: distortionHint() then says how to state it.
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
  /// Where the intrinsics came from, for the user: "options", "intrinsics.txt", "TUM freiburg2, from
  /// the folder's name" or "TUM freiburg1 defaults".
  const std::string& intrinsicsSource() const { return intrinsics_source_; }
  /// Where the lens distortion came from, for the user: "none stated", "options",
  /// "intrinsics.txt" or the TUM camera the folder's name gives.
  const std::string& distortionSource() const { return distortion_source_; }
  /// When no distortion is stated and the intrinsics are a TUM camera's: a sentence for the user
  /// saying so and how to state TUM's published one; else "".
  const std::string& distortionHint() const { return distortion_hint_; }
  const std::vector<io::StampedPose>& groundTruth() const { return ground_truth_; }

  /// Drops every frame after the first n.
  void truncate(size_t n) {
    if (n < frames_.size()) frames_.resize(n);
  }

  static constexpr double kTumDepthFactor = 5000.0;
  static constexpr const char* kIntrinsicsColumns = "fx fy cx cy width height depth_factor [k1 k2 p1 p2 k3]";

 private:
  struct Frame {
    double timestamp_s;
    std::string path;
  };
  std::vector<Frame> frames_;
  PinholeCamera camera_;
  double depth_factor_ = kTumDepthFactor;
  std::string intrinsics_source_;
  std::string distortion_source_;
  std::string distortion_hint_;
  std::vector<io::StampedPose> ground_truth_;
};

}  // namespace sdf_tracker
