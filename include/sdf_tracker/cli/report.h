#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "sdf_tracker/eval/evaluation.h"

namespace sdf_tracker::tools {

/// ATE and RPE of an estimate against ground truth, as printed and saved by the tools.
struct Accuracy {
  evaluation::AteResult ate;
  evaluation::RpeResult rpe;
};

/// Throws std::invalid_argument when too few poses associate.
Accuracy evaluateAccuracy(const std::vector<io::StampedPose>& estimate,
                          const std::vector<io::StampedPose>& ground_truth);

/// Human-readable lines: "ATE RMSE 0.0123 m (mean ..., median ..., max ...) over N poses" ...
std::string formatAccuracy(const Accuracy& accuracy);

/// Two panels: the trajectories seen from above their two widest axes (estimate aligned onto the
/// ground truth), and the absolute error over time. Written as PNG.
void writeAccuracyPlot(const std::string& path, const Accuracy& accuracy, const std::string& title);

/// JSON text of a string (quoted, escaped) and of a number (null when not finite).
std::string jsonString(const std::string& text);
std::string jsonNumber(double value);

/// A one-line progress bar with the processing rate, redrawn on stderr. finish() ends its line
/// (before a message of its own line; the next update() draws the bar again), and so does going out
/// of scope with the line open (a run that stopped on an error: its message starts a line).
class ProgressBar {
 public:
  explicit ProgressBar(size_t total, bool enabled = true);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void update(size_t done);
  void finish();

 private:
  size_t total_;
  bool enabled_;
  bool line_open_ = false;  ///< drawn and not yet ended
  std::chrono::steady_clock::time_point start_;
};

}  // namespace sdf_tracker::tools
