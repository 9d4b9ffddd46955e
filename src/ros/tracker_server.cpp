#include "sdf_tracker/ros/tracker_server.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <numeric>
#include <sstream>

#include <image_transport/camera_common.h>
#include <topic_tools/shape_shifter.h>

#include "sdf_tracker/TrackingStatus.h"
#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/surface/raycaster.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

namespace {

constexpr double kThrottle_s = 2.0;
/// This many failed frames in a row and tracking counts as lost (a third of a second at 30 Hz):
/// single failures happen (motion blur, a passing occluder) and are only warned about.
constexpr int kLostAfterFailedFrames = 10;
/// Frames wait in ROS's queue only as long as it takes to move them into the mailbox.
constexpr uint32_t kSubscriberQueue = 5;
/// Colour images kept for the depth frames to come (half a second at 30 Hz), and how far apart in
/// stamp a depth frame and its colour image may be (TUM's associate.py's 20 ms).
constexpr size_t kColourCache = 15;
constexpr double kMaxColourGap_s = 0.02;
/// The same pose on ~initialpose again within this many seconds is a repeat, not a new request.
constexpr double kRepeatedRequest_s = 1.0;
/// A pose request stamped further ahead of the node's clock than this is refused: its clock is
/// not the node's.
constexpr double kMaxRequestAhead_s = 1.0;

bool samePoseRequest(const geometry_msgs::PoseWithCovarianceStamped& a, const geometry_msgs::PoseWithCovarianceStamped& b) {
  const auto& p = a.pose.pose;
  const auto& q = b.pose.pose;
  return a.header.frame_id == b.header.frame_id && p.position.x == q.position.x && p.position.y == q.position.y &&
         p.position.z == q.position.z && p.orientation.x == q.orientation.x && p.orientation.y == q.orientation.y &&
         p.orientation.z == q.orientation.z && p.orientation.w == q.orientation.w;
}

std::string statusText(const st::TrackResult& result) {
  std::string text = st::toString(result.status);
  if (!result.message.empty()) text += ": " + result.message;
  return text;
}

}  // namespace

TrackerServer::TrackerServer(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh), it_(nh) {
  std::vector<std::string> warnings, notes;
  st::Settings settings;
  readParameters(pnh_, &settings, &options_, &warnings, &notes);
  for (const auto& warning : warnings) ROS_WARN("sdf_tracker: %s", warning.c_str());
  for (const auto& note : notes) ROS_INFO("sdf_tracker: %s", note.c_str());
  camera_settings_ = settings.camera;
  // Before the reconfigure server, whose first call may subscribe to it.
  colour_topic_ = nh_.resolveName(options_.colour_topic.empty() ? options_.camera_name + "/rgb/image_color"
                                                                : options_.colour_topic);
  state_.pipeline = std::make_unique<st::SdfPipeline>(settings.pipeline);
  std::optional<Eigen::Isometry3d> loaded_map_frame;
  if (options_.load_volume != "none" && !options_.load_volume.empty()) {
    st::io::LoadedMap loaded =
        st::io::loadMap(options_.load_volume, settings.pipeline.volume.compact_voxels, settings.pipeline.places);
    loaded_map_frame = loaded.T_map_W;
    const std::string held = st::io::describeLoadedPlaces(loaded.places.get(), settings.pipeline.relocalise);
    const std::string submaps = st::io::describeLoadedSubmaps(loaded.submaps, settings.pipeline);
    if (const std::string grey = st::io::describeLoadedColour(*loaded.submaps.submaps.front().map,
                                                              settings.pipeline.fuse_colour && options_.colourUsable());
        !grey.empty()) {
      ROS_INFO("sdf_tracker: the map in %s %s", options_.load_volume.c_str(), grey.c_str());
    }
    state_.pipeline->setSubmaps(std::move(loaded.submaps), std::move(loaded.places));
    ROS_INFO("sdf_tracker: tracking against the map in %s (%s), which %s; %s%s", options_.load_volume.c_str(),
             state_.pipeline->config().volume.describe().c_str(), held.c_str(),
             describeLoadedMapFrame(loaded_map_frame.has_value()).c_str(), (submaps.empty() ? "" : "; it " + submaps).c_str());
  }

  poses_ = std::make_unique<PoseBroadcaster>(nh_, pnh_, options_, loaded_map_frame);
  status_pub_ = pnh_.advertise<sdf_tracker::TrackingStatus>("status", 10);
  denoised_pub_ = it_.advertise(options_.camera_name + "/depth/image_denoised", 1);
  const PoseBroadcaster* poses = poses_.get();
  services_ = std::make_unique<MapServices>(pnh_, state_, options_, *poses_);
  map_publisher_ = std::make_unique<MapPublisher>(
      pnh_, state_.mutex,
      [this] {
        // The submaps, oldest first, each where the pose graph places it; the active one last.
        const st::SdfPipeline& pipeline = *state_.pipeline;
        std::vector<LiveMapPart> parts;
        const st::SubmapStore& closed = pipeline.closedSubmaps();
        for (int node = 0; node < static_cast<int>(closed.size()); ++node) {
          parts.push_back({closed.inMemory(node), closed.place(node).T_map_W, closed.swapped(node)});
        }
        parts.push_back({&pipeline.map(), pipeline.submapPlace(static_cast<int>(pipeline.submapCount()) - 1).T_map_W});
        return parts;
      },
      [poses] { return poses->T_map_W(); },
      [this] {
        std::lock_guard<std::mutex> lock(state_.mutex);
        return state_.last_stamp;
      },
      options_.frames.map_frame, options_.cloud_rate_hz, options_.mesh_rate_hz);

  const std::string depth_topic =
      options_.camera_name + (options_.depth_registered ? "/depth_registered/image" : "/depth/image");
  const auto& f = options_.frames;
  const std::string base =
      !f.base_frame.empty() ? f.base_frame : f.camera_frame.empty() ? "<image frame>" : f.camera_frame;
  diagnostics_ = std::make_unique<NodeDiagnostics>(nh_, pnh_, nh_.resolveName(depth_topic),
                                                   f.odom_frame.empty() ? "" : f.odom_frame + " -> " + base,
                                                   settings.pipeline.fuse_colour ? colour_topic_ : "",
                                                   settings.pipeline.loops.enabled);

  // Start the reconfigure server from our values, not the cfg file's defaults. Its first call
  // comes now, and may subscribe to colour: everything a colour image reaches exists by then.
  toReconfigureConfig(settings).__toServer__(pnh_);
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<sdf_tracker::SdfTrackerConfig>>(pnh_);
  reconfigure_server_->setCallback(
      [this](sdf_tracker::SdfTrackerConfig& config, uint32_t level) { reconfigure(config, level); });
  frame_thread_ = std::thread(&TrackerServer::frameLoop, this);
  if (options_.intrinsics_from_parameters) {
    depth_only_sub_ = it_.subscribe(depth_topic, kSubscriberQueue,
                                    [this](const sensor_msgs::ImageConstPtr& image) { onFrame(image, nullptr); });
    depth_topic_ = depth_only_sub_.getTopic();
  } else {
    depth_sub_ = it_.subscribeCamera(depth_topic, kSubscriberQueue, &TrackerServer::onFrame, this);
    depth_topic_ = depth_sub_.getTopic();
  }
  info_topic_ = image_transport::getCameraInfoTopic(depth_topic_);
  if (!options_.intrinsics_from_parameters) {
    image_watch_sub_ = nh_.subscribe<topic_tools::ShapeShifter>(
        depth_topic_, 1, [this](const topic_tools::ShapeShifter::ConstPtr&) {
          std::lock_guard<std::mutex> lock(mailbox_mutex_);
          last_image_wall_ = ros::WallTime::now();
        });
  }
  info_watch_sub_ = nh_.subscribe<sensor_msgs::CameraInfo>(
      info_topic_, 1, [this](const sensor_msgs::CameraInfoConstPtr& info) {
        std::lock_guard<std::mutex> lock(mailbox_mutex_);
        last_info_wall_ = ros::WallTime::now();
        last_info_ = info;
      });
  initial_pose_sub_ = pnh_.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
      "initialpose", 1, [this](const geometry_msgs::PoseWithCovarianceStampedConstPtr& request) {
        std::lock_guard<std::mutex> lock(mailbox_mutex_);
        const ros::WallTime now = ros::WallTime::now();
        const bool repeat = last_pose_request_ && samePoseRequest(*last_pose_request_, *request) &&
                            (now - last_pose_request_wall_).toSec() < kRepeatedRequest_s;
        last_pose_request_ = *request;
        last_pose_request_wall_ = now;
        if (repeat) {
          ROS_DEBUG("sdf_tracker: the same pose again on %s: already taken", initial_pose_sub_.getTopic().c_str());
          return;
        }
        pending_pose_request_ = *request;
      });
  watchdog_timer_ = nh_.createTimer(ros::Duration(2.0), &TrackerServer::checkInputs, this);

  const auto& v = settings.pipeline.volume;
  const std::string tree = f.odom_frame.empty()
                               ? f.map_frame + " -> " + base
                               : f.map_frame + " -> " + f.odom_frame + " (" + f.odom_frame + " -> " + base +
                                     " from the robot's odometry, also the motion prior)";
  ROS_INFO("sdf_tracker: listening on %s (intrinsics from %s); %s; tf %s", depth_topic_.c_str(),
           options_.intrinsics_from_parameters ? "parameters" : info_topic_.c_str(), v.describe().c_str(),
           tree.c_str());
  if (settings.pipeline.fuse_colour) {
    ROS_INFO("sdf_tracker: colour from %s, %s", colour_topic_.c_str(),
             options_.colourUsable() ? "registered to the depth" : "NOT used: the depth is not known to be registered to it");
  }
}

void TrackerServer::updateColourSubscription(bool colour_on) {
  if (colour_on == static_cast<bool>(colour_sub_)) return;
  if (!colour_on) {
    colour_sub_.shutdown();
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    colour_cache_.clear();
    return;
  }
  colour_sub_ = it_.subscribe(colour_topic_, kSubscriberQueue, &TrackerServer::onColour, this);
}

void TrackerServer::onColour(const sensor_msgs::ImageConstPtr& image) {
  if (!options_.colourUsable()) {
    diagnostics_->colourReceived("colour images on " + colour_topic_ + " are not used: the depth is not registered to "
                                 "them (~depth_registered or ~colour_registered)");
    // Colour from another viewpoint than the depth's would paint every surface with what lies
    // beside it: not used, and said once.
    ROS_WARN_ONCE("sdf_tracker: colour images on %s are not used: the depth on %s is not registered to them. Use a "
                  "driver's registered depth (~depth_registered: true), or set ~colour_registered: true when the depth "
                  "is registered to the colour by other means (TUM RGB-D's bags are); or Colour: false to stop this "
                  "subscription",
                  colour_topic_.c_str(), depth_topic_.c_str());
    return;
  }
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  // From the first colour image on, ~cloud keeps its rgb field (a camera without colour: as before).
  if (colour_received_++ == 0) map_publisher_->setColour(true);
  diagnostics_->colourReceived("");
  colour_cache_.push_back(image);
  if (colour_cache_.size() > kColourCache) colour_cache_.pop_front();
}

std::optional<st::ColourImage> TrackerServer::colourAt(const ros::Time& stamp) {
  sensor_msgs::ImageConstPtr nearest;
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    double best_s = kMaxColourGap_s;
    for (const sensor_msgs::ImageConstPtr& image : colour_cache_) {
      const double gap_s = std::fabs((image->header.stamp - stamp).toSec());
      if (gap_s <= best_s) best_s = gap_s, nearest = image;
    }
  }
  if (!nearest) return std::nullopt;
  try {
    return toColourImage(*nearest);
  } catch (const std::invalid_argument& e) {
    ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: colour image from %s: %s: the frame is fused without colour",
                      colour_topic_.c_str(), e.what());
    colour_problem_ = std::string("colour image: ") + e.what();
    return std::nullopt;
  }
}

TrackerServer::~TrackerServer() { finish(); }

bool TrackerServer::finish() {
  if (finished_) return *finished_;
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    stopping_ = true;
  }
  mailbox_changed_.notify_all();
  if (frame_thread_.joinable()) frame_thread_.join();
  map_publisher_.reset();
  std::vector<double> ms = frame_ms_;
  std::sort(ms.begin(), ms.end());
  // Also on stdout: rosconsole may be gone by the time roslaunch stops the node.
  std::printf("sdf_tracker: %u frames received, %zu processed, %u dropped, %u fused in colour (%u colour images "
              "received); per frame in the node: median %.1f ms, mean %.1f ms\n",
              frames_received_, ms.size(), frames_dropped_, frames_coloured_, colour_received_,
              ms.empty() ? 0.0 : ms[ms.size() / 2],
              ms.empty() ? 0.0 : std::accumulate(ms.begin(), ms.end(), 0.0) / ms.size());
  finished_ = services_->writeAtShutdown();
  return *finished_;
}

void TrackerServer::onFrame(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info) {
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    ++frames_received_;
    if (pending_) ++frames_dropped_;  // the frame thread was still busy: only the newest is kept
    pending_ = Frame{image, info};
  }
  mailbox_changed_.notify_one();
}

void TrackerServer::frameLoop() {
  while (true) {
    Frame frame;
    {
      std::unique_lock<std::mutex> lock(mailbox_mutex_);
      mailbox_changed_.wait(lock, [this] { return stopping_ || pending_; });
      if (stopping_) return;
      frame = std::move(*pending_);
      pending_.reset();
    }
    try {
      process(frame);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(kThrottle_s, "sdf_tracker: frame stamped %.3f: %s", frame.image->header.stamp.toSec(), e.what());
    }
  }
}

st::PinholeCamera TrackerServer::cameraFor(const Frame& frame) {
  st::PinholeCamera camera;
  std::string distortion_source;
  if (options_.intrinsics_from_parameters) {
    camera = camera_settings_.camera();
    distortion_source = "FocalLength/CenterPoint parameters";
    sensor_msgs::CameraInfoConstPtr info;
    {
      std::lock_guard<std::mutex> lock(mailbox_mutex_);
      info = last_info_;
    }
    if (!questioned_intrinsics_ && info && info->K[0] > 0.0 &&
        (std::abs(info->K[0] - camera.fx) > 1e-3 || std::abs(info->K[2] - camera.cx) > 1e-3)) {
      ROS_WARN("sdf_tracker: FocalLength/CenterPoint parameters (fx %.2f, cx %.2f) disagree with %s (fx %.2f, cx "
               "%.2f); using the parameters",
               camera.fx, camera.cx, info_topic_.c_str(), info->K[0], info->K[2]);
      questioned_intrinsics_ = true;
    }
  } else {
    camera = trackingCamera(*frame.info, info_topic_, options_.tum_camera, &distortion_source);
    if (!questioned_intrinsics_) {
      questioned_intrinsics_ = true;
      const auto& K = frame.info->K;
      const bool driver_default = holdsOpenNiDefault(*frame.info);
      if (!options_.tum_camera.empty()) {
        ROS_INFO("sdf_tracker: ~tum_camera %s: its calibration replaces %s (fx %.2f fy %.2f cx %.2f cy %.2f%s)",
                 options_.tum_camera.c_str(), info_topic_.c_str(), K[0], K[4], K[2], K[5],
                 driver_default ? ", the OpenNI driver's default" : "");
      } else if (driver_default) {
        ROS_WARN(
            "sdf_tracker: %s holds the OpenNI driver's default intrinsics (fx = fy = %.1f, cx %.1f, cy %.1f, no "
            "distortion), a guess rather than a calibration of this camera. A TUM RGB-D bag: set ~tum_camera "
            "(%s; tum_bag.launch takes it from the bag's name). A live camera: calibrate it.",
            info_topic_.c_str(), camera.fx, camera.cx, camera.cy, st::PinholeCamera::tumCameraNames().c_str());
      }
    }
  }
  if (camera != announced_camera_) {
    ROS_INFO("sdf_tracker: camera %dx%d, fx %.2f fy %.2f cx %.2f cy %.2f; %s", camera.width, camera.height, camera.fx,
             camera.fy, camera.cx, camera.cy, camera.distortion.summary(distortion_source).c_str());
    announced_camera_ = camera;
  }
  return camera;
}

void TrackerServer::process(const Frame& frame) {
  const auto started = std::chrono::steady_clock::now();
  const sensor_msgs::Image& image = *frame.image;
  sdf_tracker::TrackingStatus status;
  status.header = image.header;
  {
    std::lock_guard<std::mutex> lock(mailbox_mutex_);
    status.frames_received = frames_received_;
    status.frames_dropped = frames_dropped_;
  }
  auto drop = [&](const std::string& why) {
    ROS_ERROR_THROTTLE(kThrottle_s, "sdf_tracker: dropping a frame from %s: %s", depth_topic_.c_str(), why.c_str());
    status.status = sdf_tracker::TrackingStatus::BAD_INPUT;
    status.status_text = "bad_input: " + why;
    publishStatus(status);
  };

  st::DepthImage depth;
  st::PinholeCamera camera;
  try {
    depth = toDepthImage(image);
    camera = cameraFor(frame);
  } catch (const std::invalid_argument& e) {
    return drop(e.what());
  }
  if (const std::string mismatch = camera.sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
    return drop(mismatch);
  }

  // The robot's odometry at this image (~odom_frame), looked up before the state is locked: it may
  // wait for tf.
  const std::optional<Eigen::Isometry3d> T_odom_C = poses_->odometryCameraPose(image.header.stamp, image.header.frame_id);
  if (!options_.frames.odom_frame.empty()) diagnostics_->odometryLookedUp(poses_->odometryProblem());
  st::FrameReport report;
  // The camera in the tracker's world where the pose graph places it (what goes out), and in the
  // active submap's frame (what its map is read at).
  Eigen::Isometry3d T_W_C, T_active_C;
  bool pose_known = true;
  std::vector<st::io::StampedPose> moved_path_W;  ///< the path as a pose graph solution placed it anew
  {
    std::lock_guard<std::mutex> lock(state_.mutex);
    if (state_.restarted) {
      state_.restarted = false;
      last_stamp_ = ros::Time();
      poses_->clearPath();
    }
    if (!last_stamp_.isZero() && image.header.stamp <= last_stamp_) {
      const double back_s = (last_stamp_ - image.header.stamp).toSec();
      if (options_.time_jump_reset_s > 0.0 && back_s > options_.time_jump_reset_s) {
        ROS_WARN("sdf_tracker: time jumped back %.3f s (from %.6f to %.6f), more than ~time_jump_reset (%.3f s): "
                 "restarting the map", back_s, last_stamp_.toSec(), image.header.stamp.toSec(),
                 options_.time_jump_reset_s);
        state_.pipeline->reset();
        state_.path.clear();
        poses_->clearPath();
      } else {
        // One stray stamp (0, a clock jump) must not wipe the map: the frame is dropped.
        ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: dropping a frame stamped %.6f, %.3f s before the last one "
                          "(%.6f); call ~reset (or set ~time_jump_reset) to start a new map after a jump back",
                          image.header.stamp.toSec(), back_s, last_stamp_.toSec());
        status.status = sdf_tracker::TrackingStatus::BAD_INPUT;
        status.status_text = "bad_input: stamped before the last frame";
        publishStatus(status);
        return;
      }
    }
    std::optional<geometry_msgs::PoseWithCovarianceStamped> pose_request;
    {
      std::lock_guard<std::mutex> mailbox_lock(mailbox_mutex_);
      pose_request.swap(pending_pose_request_);
    }
    if (pose_request) applyPoseRequest(*pose_request, image.header.frame_id);
    // The colour image taken with it, looked for when the frame is fused: one that comes while the
    // frame is tracked is still used, and depth never waits for colour.
    const ros::Time stamp = image.header.stamp;
    report = state_.pipeline->processFrame(depth, camera, stamp.toSec(), T_odom_C,
                                           st::FrameColour([this, stamp] { return colourAt(stamp); }));
    if (report.track.status == st::TrackStatus::kBadInput) {
      return drop(report.track.message);
    }
    last_stamp_ = state_.last_stamp = image.header.stamp;
    frames_coloured_ += report.coloured;
    if (!report.colour_problem.empty()) {
      ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: colour image from %s: %s: the frame is fused without colour",
                        colour_topic_.c_str(), report.colour_problem.c_str());
      colour_problem_ = "colour image: " + report.colour_problem;
    }
    if (report.fused) diagnostics_->frameColoured(report.coloured, colour_problem_);
    colour_problem_.clear();
    T_active_C = state_.pipeline->pose();
    T_W_C = state_.pipeline->mapPose();
    pose_known = state_.pipeline->poseKnown();
    status.consecutive_failures = static_cast<uint32_t>(state_.pipeline->consecutiveFailures());
    if (report.reset) state_.path.detachFromSubmaps();
    if (pose_known && report.track.tracked()) {
      state_.path.add(image.header.stamp.toSec(), report.submap, T_active_C, T_W_C);
    }
    status.submap = static_cast<uint32_t>(report.submap);
    status.map_memory_mb = state_.pipeline->mapMemoryBytes() / 1048576.0;
    status.submaps_swapped = static_cast<uint32_t>(state_.pipeline->closedSubmaps().swappedCount());
    status.loops_closed = static_cast<uint32_t>(state_.pipeline->loopsClosed());
    status.loops_rejected = static_cast<uint32_t>(state_.pipeline->loopsRejected());
    if (report.loop.solved) moved_path_W = state_.path.placed(*state_.pipeline);
  }

  const st::TrackResult& t = report.track;
  const bool was_lost = lost_, was_searching = searching_;
  // A camera whose pose is not known yet (a loaded map, ~relocalise) is searched for, not lost:
  // lost is for one that was tracked and then failed.
  searching_ = !pose_known;
  lost_ = pose_known && static_cast<int>(status.consecutive_failures) >= kLostAfterFailedFrames;
  if (searching_ && !was_searching) {
    ROS_WARN("sdf_tracker: searching the map for the camera; nothing is fused and no pose goes out until a place is "
             "confirmed (%s)", statusText(t).c_str());
  } else if (!searching_ && was_searching) {
    ROS_INFO("sdf_tracker: found the camera in the map; tracking");
  } else if (searching_) {
    ROS_INFO_THROTTLE(10.0, "sdf_tracker: still searching the map for the camera: %s", statusText(t).c_str());
  } else if (lost_ && !was_lost) {
    ROS_ERROR("sdf_tracker: tracking lost after %d failed frames (%s); holding the pose, fusing nothing, and "
              "relocalising as soon as the camera sees mapped geometry again",
              kLostAfterFailedFrames, statusText(t).c_str());
  } else if (!lost_ && was_lost) {
    ROS_INFO("sdf_tracker: relocalised; tracking again");
  } else if (!t.tracked() && !lost_) {
    ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: %s (pose held, frame not fused)", statusText(t).c_str());
  } else if (!t.ok() && !lost_) {
    ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: %s", statusText(t).c_str());
  }
  if (report.reset) ROS_WARN("sdf_tracker: map cleared after repeated failures (ResetAfterFailures)");
  if (report.blocks_swapped_out > 0 || report.blocks_swapped_in > 0) {
    ROS_DEBUG("sdf_tracker: %zu blocks swapped out, %zu read back", report.blocks_swapped_out,
              report.blocks_swapped_in);
  }
  if (!report.swap_notice.empty()) ROS_INFO("sdf_tracker: %s", report.swap_notice.c_str());
  if (!report.swap_warning.empty()) ROS_WARN("sdf_tracker: %s", report.swap_warning.c_str());
  if (!report.swap_error.empty()) ROS_ERROR_THROTTLE(kThrottle_s, "sdf_tracker: %s", report.swap_error.c_str());

  // The message's constants are the core's statuses, in the same order.
  using Msg = sdf_tracker::TrackingStatus;
  using Status = st::TrackStatus;
  static_assert(int(Status::kOk) == Msg::OK && int(Status::kNotConverged) == Msg::NOT_CONVERGED &&
                int(Status::kTooFewPoints) == Msg::TOO_FEW_POINTS && int(Status::kDegenerate) == Msg::DEGENERATE &&
                int(Status::kDiverged) == Msg::DIVERGED && int(Status::kBadInput) == Msg::BAD_INPUT &&
                int(Status::kLowOverlap) == Msg::LOW_OVERLAP && int(Status::kRelocalising) == Msg::RELOCALISING &&
                int(Status::kAmbiguous) == Msg::AMBIGUOUS);
  status.status = static_cast<uint8_t>(t.status);
  status.status_text = statusText(t);
  status.iterations_per_level = t.iterations_per_level;
  status.rms_residual_m = t.rms_residual_m;
  status.valid_points = t.valid_points;
  status.overlap = t.overlap;
  status.inverse_condition = t.inverse_condition;
  status.constrained_rank = t.constrained_rank;
  status.tracking_ms = report.tracking_ms;
  status.fusion_ms = report.fusion_ms;
  status.fused = report.fused;
  status.predicted_by_odometry = report.predicted_by_odometry;
  status.lost = lost_;

  // A pose graph solution that landed moves the camera from this frame on (map -> base, or
  // map -> odom on a robot) and the path behind it.
  const st::LoopReport& loop = report.loop;
  if (loop.found) {
    ROS_INFO("sdf_tracker: loop found: the view of submap %d is in submap %d; solving the pose graph",
             loop.frame_submap, loop.submap);
  }
  if (loop.solved) {
    status.loop_solved = true;
    status.loop_correction_m = loop.correction_m;
    status.loop_correction_deg = loop.correction_deg;
    ROS_INFO("sdf_tracker: pose graph solved in %.1f ms: %d loop(s) kept, %d found wrong and left out; the camera "
             "moved %.3f m, %.2f deg; ~path republished",
             loop.optimise_ms, loop.closed, loop.rejected, loop.correction_m, loop.correction_deg);
    poses_->republishPath(moved_path_W);
  }
  // While the camera is searched for in the map, its pose is not known: nothing goes out until a
  // place is confirmed (the status says how the search goes). A held pose (the frame failed) goes
  // on tf and ~odom, whose covariance says how little it is worth; ~pose, ~path and the
  // trajectory carry estimates only.
  if (pose_known) {
    // The tracker's covariance is in the active submap's frame; the estimate in the world's.
    const Eigen::Matrix3d R_W_active = T_W_C.linear() * T_active_C.linear().transpose();
    poses_->publish(image.header.stamp, image.header.frame_id, T_W_C,
                    t.tracked() ? std::optional<Covariance6d>(rotatedCovariance(t.covariance, R_W_active)) : std::nullopt,
                    T_odom_C);
  }
  publishStatus(status);

  if (pose_known && denoised_pub_.getNumSubscribers() > 0) {
    std::lock_guard<std::mutex> lock(state_.mutex);
    const st::RaycastImage cast = st::raycast(state_.pipeline->map(), camera, T_active_C,
                                              state_.pipeline->config().raycast, &depth);
    denoised_pub_.publish(toImageMsg(cast.depth, image.header));
  }
  // The whole cost of a frame in the node: conversion, tracking, fusion, publishing.
  frame_ms_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
  ROS_INFO_THROTTLE(10.0, "sdf_tracker: %zu frames processed, %u dropped; %.1f ms per frame on average",
                    frame_ms_.size(), status.frames_dropped,
                    std::accumulate(frame_ms_.begin(), frame_ms_.end(), 0.0) / frame_ms_.size());
}

void TrackerServer::publishStatus(const sdf_tracker::TrackingStatus& status) {
  status_pub_.publish(status);
  diagnostics_->frameProcessed(status, (ros::Time::now() - status.header.stamp).toSec());
}

void TrackerServer::applyPoseRequest(const geometry_msgs::PoseWithCovarianceStamped& request,
                                     const std::string& image_frame) {
  const std::string topic = initial_pose_sub_.getTopic();
  try {
    const double ahead_s = (request.header.stamp - ros::Time::now()).toSec();
    if (ahead_s > kMaxRequestAhead_s) {
      std::ostringstream msg;
      msg << std::fixed << std::setprecision(3) << "it is stamped " << request.header.stamp.toSec() << ", " << ahead_s
          << " s ahead of this node's clock (" << ros::Time::now().toSec()
          << "): its sender's clock is not this one (use_sim_time?)";
      throw std::runtime_error(msg.str());
    }
    if (request.header.frame_id.empty()) {
      ROS_WARN("sdf_tracker: the pose on %s has no frame_id: taken in ~map_frame '%s'", topic.c_str(),
               poses_->mapFrame().c_str());
    }
    const Eigen::Isometry3d T_W_C = poses_->requestedCameraPose(request, image_frame, state_.pipeline->mapPose());
    state_.pipeline->relocalise(T_W_C);  // throws, naming Relocalise, when it is off
    const Eigen::Vector3d t_map = poses_->T_map_W() * T_W_C.translation();
    ROS_INFO_THROTTLE(1.0,
                      "sdf_tracker: pose from %s: the camera at (%.3f, %.3f, %.3f) m in %s (x, y and yaw given, "
                      "height and tilt kept); verifying it before anything is fused",
                      topic.c_str(), t_map.x(), t_map.y(), t_map.z(), poses_->mapFrame().c_str());
  } catch (const std::exception& e) {
    ROS_ERROR("sdf_tracker: ignoring the pose on %s: %s", topic.c_str(), e.what());
  }
}

void TrackerServer::checkInputs(const ros::TimerEvent&) {
  // Images without a matching camera_info never reach onFrame: say which input is missing
  // instead of idling. Once frames flow, the image watch is no longer needed.
  std::lock_guard<std::mutex> lock(mailbox_mutex_);
  if (frames_received_ > 0) {
    image_watch_sub_.shutdown();
    return;
  }
  const ros::WallTime now = ros::WallTime::now();
  const bool images = !last_image_wall_.isZero() && (now - last_image_wall_).toSec() < 3.0;
  const bool infos = !last_info_wall_.isZero() && (now - last_info_wall_).toSec() < 3.0;
  if (images && !infos) {
    ROS_ERROR_THROTTLE(10.0, "sdf_tracker: images arrive on %s but no camera_info on %s; frames cannot be used "
                       "(publish camera_info, or set FocalLengthX/Y and CenterPointX/Y)",
                       depth_topic_.c_str(), info_topic_.c_str());
  } else if (images && infos) {
    ROS_WARN_THROTTLE(10.0, "sdf_tracker: images on %s and camera_info on %s arrive but never with the same stamp; "
                      "they are paired by exact stamp", depth_topic_.c_str(), info_topic_.c_str());
  }
}

void TrackerServer::reconfigure(sdf_tracker::SdfTrackerConfig& config, uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(state_.mutex);
  st::Settings candidate{state_.pipeline->config(), camera_settings_};
  try {
    for (const auto& [name, value] : reconfigureValues(config)) st::setParameter(&candidate, name, value);
    st::throwIfInvalid("reconfiguration", candidate.validate());
    state_.pipeline->updateConfig(candidate.pipeline);  // validates again; changes nothing when it throws
    updateColourSubscription(candidate.pipeline.fuse_colour);
    if (!candidate.pipeline.fuse_colour) map_publisher_->setColour(false);
    ROS_INFO("sdf_tracker: reconfigured");
  } catch (const std::invalid_argument& e) {
    ROS_ERROR("sdf_tracker: rejected reconfiguration: %s", e.what());
    config = toReconfigureConfig(st::Settings{state_.pipeline->config(), camera_settings_});  // reports the values still in force
  }
}

}  // namespace sdf_tracker_ros
