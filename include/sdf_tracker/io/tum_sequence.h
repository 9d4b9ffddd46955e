#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"
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

/// A line of a TUM list (depth.txt, rgb.txt, accelerometer.txt): its timestamp and the rest of
/// the line (a file name, or values).
struct TimedLine {
  double timestamp_s;
  std::string rest;
  int line_number;  ///< in its file, from 1
  /// The first word after the timestamp: the file a list of images names ("" when none).
  std::string firstWord() const;
};
/// The lines of a TUM list after '#' comments, in file order; throws std::runtime_error naming
/// the file and line for one that does not start with a finite timestamp, or when the file
/// cannot be opened.
std::vector<TimedLine> readTimedList(const std::string& path);

/// Pairs two lists of timestamps as TUM's associate.py does: the closest pairs first, each
/// entry in at most one pair, none further apart than max_difference_s. Returns, for each of `a`,
/// the index into `b` of its partner, or -1.
std::vector<long> associateByTime(const std::vector<double>& a, const std::vector<double>& b, double max_difference_s);

/// A depth sequence in the TUM RGB-D layout: depth.txt ("timestamp depth/<file>.png"), 16-bit
/// PNGs, optional groundtruth.txt and intrinsics.txt (kIntrinsicsColumns).
/// Intrinsics and depth factor come from the options, else intrinsics.txt, else the TUM camera
/// the folder's name mentions as TUM names its downloads (rgbd_dataset_freiburg2_desk: freiburg2's
/// published calibration), else the TUM freiburg1 defaults (517.3, 516.5, 318.6, 255.3); factor
/// 5000. The lens distortion is what the data states: the options' --distortion, else
/// intrinsics.txt's last five columns (without them: none), else the distortion TUM publishes for
/// the camera the folder's name gives; else none. It is never inferred from intrinsics that happen
/// to be a TUM camera's: distortionHint() then says how to state it.
/// With rgb.txt ("timestamp rgb/<file>.png|.jpg", TUM's own clock for colour), each depth frame
/// is paired with the colour image nearest in time within kMaxColourGap_s (associateByTime); a
/// frame without one has no colour. TUM's depth is registered to its colour images, pixel for
/// pixel.
class TumSequence {
 public:
  /// Throws std::runtime_error naming the file and the problem.
  static TumSequence open(const std::string& directory, const SequenceOptions& options = {});

  size_t size() const { return frames_.size(); }
  double timestamp(size_t i) const { return frames_.at(i).timestamp_s; }
  const std::string& depthPath(size_t i) const { return frames_.at(i).path; }
  /// Reads frame i in metres; throws std::runtime_error for a missing or corrupt file.
  DepthImage depth(size_t i) const;
  /// The folder has rgb.txt.
  bool hasColourList() const { return has_colour_list_; }
  /// Frames paired with a colour image.
  size_t colouredFrames() const;
  /// The colour image paired with frame i ("" when none) and its timestamp (NaN when none).
  const std::string& colourPath(size_t i) const { return frames_.at(i).colour_path; }
  double colourTimestamp(size_t i) const { return frames_.at(i).colour_timestamp_s; }
  /// Reads frame i's colour image (PNG or JPEG, 8-bit grey or colour) as RGB; nothing when the
  /// frame has none. Throws std::runtime_error naming the file when it is missing, corrupt, or not
  /// of the depth images' size.
  std::optional<ColourImage> colour(size_t i) const;

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
  /// The furthest apart in time a depth and a colour image are paired (TUM's associate.py's).
  static constexpr double kMaxColourGap_s = 0.02;
  static constexpr const char* kIntrinsicsColumns = "fx fy cx cy width height depth_factor [k1 k2 p1 p2 k3]";

 private:
  struct Frame {
    double timestamp_s;
    std::string path;
    std::string colour_path;  ///< "" when no colour image is paired with it
    double colour_timestamp_s = std::numeric_limits<double>::quiet_NaN();
  };
  bool has_colour_list_ = false;
  std::vector<Frame> frames_;
  PinholeCamera camera_;
  double depth_factor_ = kTumDepthFactor;
  std::string intrinsics_source_;
  std::string distortion_source_;
  std::string distortion_hint_;
  std::vector<io::StampedPose> ground_truth_;
};

}  // namespace sdf_tracker
