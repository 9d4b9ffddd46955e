#include "sdf_tracker/ros/node_diagnostics.h"

#include <algorithm>

namespace sdf_tracker_ros {

using diagnostic_msgs::DiagnosticStatus;

NodeDiagnostics::NodeDiagnostics(ros::NodeHandle nh, ros::NodeHandle pnh, const std::string& hardware_id,
                                 const std::string& odometry_transform, const std::string& colour_topic,
                                 bool loop_closure)
    : updater_(nh, pnh, pnh.getNamespace()),  // the nodelet's own name, not its manager's
      odometry_transform_(odometry_transform),
      colour_topic_(colour_topic) {
  updater_.setHardwareID(hardware_id);
  updater_.add("frames", this, &NodeDiagnostics::frames);
  updater_.add("tracking", this, &NodeDiagnostics::tracking);
  if (!odometry_transform_.empty()) updater_.add("odometry", this, &NodeDiagnostics::odometry);
  if (!colour_topic_.empty()) updater_.add("colour", this, &NodeDiagnostics::colour);
  if (loop_closure) updater_.add("loop closure", this, &NodeDiagnostics::loopClosure);
  // The updater publishes at its own period (~diagnostic_period, 1 s); it has to be asked often.
  timer_ = nh.createTimer(ros::Duration(0.25), [this](const ros::TimerEvent&) { updater_.update(); });
}

void NodeDiagnostics::frameProcessed(const sdf_tracker::TrackingStatus& status, double latency_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  window_.push_back({now, status.frames_received, status.frames_dropped, latency_s});
  trim(now);
  last_ = status;
  any_ = true;
  if (status.loop_solved) {
    last_solution_ = status;
    last_solution_wall_ = now;
  }
}

void NodeDiagnostics::loopClosure(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!any_) {
    stat.summary(DiagnosticStatus::OK, "no frame yet");
    return;
  }
  stat.add("active submap", last_.submap);
  stat.add("map memory [MiB]", last_.map_memory_mb);
  stat.add("submaps in the swap file", last_.submaps_swapped);
  stat.add("loops kept", last_.loops_closed);
  stat.add("loops found wrong", last_.loops_rejected);
  if (last_solution_) {
    stat.add("last correction [m]", last_solution_->loop_correction_m);
    stat.add("last correction [deg]", last_solution_->loop_correction_deg);
    stat.add("seconds since the last correction", (ros::WallTime::now() - last_solution_wall_).toSec());
  }
  if (last_.loops_rejected > 0) {
    stat.summaryf(DiagnosticStatus::WARN, "%u loop(s) kept; %u found wrong by the pose graph and left out",
                  last_.loops_closed, last_.loops_rejected);
  } else if (!last_solution_) {
    stat.summaryf(DiagnosticStatus::OK, "no loop closed yet (submap %u)", last_.submap);
  } else {
    stat.summaryf(DiagnosticStatus::OK, "%u loop(s) kept; the last moved the camera %.3f m, %.2f deg",
                  last_.loops_closed, last_solution_->loop_correction_m, last_solution_->loop_correction_deg);
  }
}

void NodeDiagnostics::odometryLookedUp(const std::string& problem) {
  std::lock_guard<std::mutex> lock(mutex_);
  odometry_looked_up_ = true;
  odometry_problem_ = problem;
  if (problem.empty()) {
    ++frames_with_odometry_;
    without_odometry_in_a_row_ = 0;
  } else {
    ++frames_without_odometry_;
    ++without_odometry_in_a_row_;
  }
}

void NodeDiagnostics::colourReceived(const std::string& problem) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++colour_images_;
  if (!problem.empty()) colour_problem_ = problem;
}

void NodeDiagnostics::frameColoured(bool coloured, const std::string& problem) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++(coloured ? frames_coloured_ : frames_uncoloured_);
  if (coloured) colour_problem_.clear();
  if (!problem.empty()) colour_problem_ = problem;
}

void NodeDiagnostics::colour(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  stat.add("topic", colour_topic_);
  stat.add("colour images received", colour_images_);
  stat.add("frames fused in colour", frames_coloured_);
  stat.add("frames fused without colour", frames_uncoloured_);
  if (!colour_problem_.empty()) {
    stat.summary(DiagnosticStatus::WARN, colour_problem_);
  } else if (colour_images_ == 0) {
    stat.summaryf(DiagnosticStatus::OK, "no colour images on %s: the map is made without colour", colour_topic_.c_str());
  } else {
    stat.summaryf(DiagnosticStatus::OK, "%u of %u frames fused in colour", frames_coloured_,
                  frames_coloured_ + frames_uncoloured_);
  }
}

void NodeDiagnostics::odometry(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  stat.add("transform", odometry_transform_);
  stat.add("frames with odometry", frames_with_odometry_);
  stat.add("frames without odometry", frames_without_odometry_);
  if (!odometry_looked_up_) {
    stat.summary(DiagnosticStatus::WARN, "no frame yet");
  } else if (!odometry_problem_.empty()) {
    stat.add("last problem", odometry_problem_);
    stat.summaryf(DiagnosticStatus::WARN, "%u frames in a row without odometry (predicted at constant velocity): %s",
                  without_odometry_in_a_row_, odometry_problem_.c_str());
  } else {
    stat.summaryf(DiagnosticStatus::OK, "%s in tf at the last frame (%u of %u frames)", odometry_transform_.c_str(),
                  frames_with_odometry_, frames_with_odometry_ + frames_without_odometry_);
  }
}

void NodeDiagnostics::trim(const ros::WallTime& now) {
  // The oldest frame kept is the reference the rates are counted from.
  while (window_.size() > 2 && (now - window_[1].wall).toSec() > kRateWindow_s) window_.pop_front();
}

void NodeDiagnostics::frames(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  trim(now);
  if (!any_) {
    stat.summary(DiagnosticStatus::WARN, "no frame yet");
    return;
  }
  const Processed& first = window_.front();
  const Processed& last = window_.back();
  const double since_last_s = (now - last.wall).toSec();
  const double span_s = (last.wall - first.wall).toSec();
  const double processed_hz = span_s > 0.0 ? (window_.size() - 1) / span_s : 0.0;
  const double received_hz = span_s > 0.0 ? (last.frames_received - first.frames_received) / span_s : 0.0;
  const uint32_t dropped = last.frames_dropped - first.frames_dropped;
  const uint32_t received = last.frames_received - first.frames_received;
  double latency_max_s = 0.0, latency_sum_s = 0.0;
  for (const Processed& p : window_) {
    latency_max_s = std::max(latency_max_s, p.latency_s);
    latency_sum_s += p.latency_s;
  }
  stat.add("frames processed per second", processed_hz);
  stat.add("frames received per second", received_hz);
  stat.add("frames received", last.frames_received);
  stat.add("frames dropped", last.frames_dropped);
  stat.add("latency mean [s]", latency_sum_s / window_.size());
  stat.add("latency max [s]", latency_max_s);
  stat.add("seconds since the last frame", since_last_s);
  if (since_last_s > kStaleAfter_s) {
    stat.summaryf(DiagnosticStatus::ERROR, "no frame for %.1f s", since_last_s);
  } else if (received > 0 && 2 * dropped > received) {
    stat.summaryf(DiagnosticStatus::WARN, "dropping %u of %u frames: the tracker is slower than the camera",
                  dropped, received);
  } else {
    stat.summaryf(DiagnosticStatus::OK, "%.1f frames/s of the camera's %.1f", processed_hz, received_hz);
  }
}

void NodeDiagnostics::tracking(diagnostic_updater::DiagnosticStatusWrapper& stat) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!any_) {
    stat.summary(DiagnosticStatus::WARN, "no frame yet");
    return;
  }
  stat.add("status", last_.status_text);
  stat.add("failures in a row", last_.consecutive_failures);
  stat.add("lost", last_.lost ? "true" : "false");
  stat.add("overlap", last_.overlap);
  stat.add("constrained directions", static_cast<int>(last_.constrained_rank));
  stat.add("residual RMS [m]", last_.rms_residual_m);
  stat.add("tracking [ms]", last_.tracking_ms);
  stat.add("prediction", last_.predicted_by_odometry ? "the robot's odometry" : "constant velocity");
  if (last_.lost) {
    stat.summary(DiagnosticStatus::ERROR, "lost: " + last_.status_text);
  } else if (last_.status == sdf_tracker::TrackingStatus::DEGENERATE && last_.consecutive_failures == 0 &&
             last_.predicted_by_odometry) {
    // A robot along a bare wall, tracked (no failure counted; fused or not, as MinPoseChangeToFuseData
    // says): what the view leaves open, its odometry gives.
    stat.summaryf(DiagnosticStatus::OK, "tracking: %d of 6 directions from the view, the others from the odometry",
                  last_.constrained_rank);
  } else if (last_.status == sdf_tracker::TrackingStatus::RELOCALISING ||
             last_.status == sdf_tracker::TrackingStatus::AMBIGUOUS) {
    stat.summary(DiagnosticStatus::WARN, "searching the map for the camera: " + last_.status_text);
  } else if (last_.status != sdf_tracker::TrackingStatus::OK) {
    stat.summary(DiagnosticStatus::WARN, last_.status_text);
  } else {
    stat.summary(DiagnosticStatus::OK, "tracking");
  }
}

}  // namespace sdf_tracker_ros
