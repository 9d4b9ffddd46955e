#include "sdf_tracker/ros/tracker_server.h"

#include <algorithm>
#include <iomanip>
#include <sstream>

#include <geometry_msgs/PoseStamped.h>
#include <image_transport/camera_common.h>
#include <geometry_msgs/TransformStamped.h>
#include <visualization_msgs/Marker.h>

#include "sdf_tracker/TrackingStatus.h"
#include "sdf_tracker/core/raycaster.h"
#include "sdf_tracker/core/surface.h"
#include "sdf_tracker/core/validation.h"
#include "sdf_tracker/ros/conversions.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

namespace {

constexpr double kThrottle_s = 2.0;

std::string toText(const XmlRpc::XmlRpcValue& value) {
  XmlRpc::XmlRpcValue v = value;  // the accessors are non-const
  std::ostringstream out;
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return static_cast<bool>(v) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt: return std::to_string(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: out << std::setprecision(17) << static_cast<double>(v); return out.str();
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(v);
    default: throw std::invalid_argument("has an unsupported type (expected a number, boolean or string)");
  }
}

/// The node's own parameters (everything that is not in the core's table).
bool applyNodeOption(NodeOptions* o, const std::string& name, const std::string& text) {
  if (name == "c_name") o->camera_name = text;
  else if (name == "depth_registered") o->depth_registered = st::parseBool(name, text);
  else if (name == "world_frame") o->world_frame = text;
  else if (name == "odom_frame") o->odom_frame = text;
  else if (name == "camera_frame") o->camera_frame = text;
  else if (name == "cloud_rate") o->cloud_rate_hz = st::parseNumber(name, text);
  else if (name == "mesh_rate") o->mesh_rate_hz = st::parseNumber(name, text);
  else if (name == "trajectory_file") o->trajectory_file = text;
  else if (name == "mesh_file") o->mesh_file = text;
  else if (name == "cloud_file") o->cloud_file = text;
  else if (name == "LoadVolume") o->load_volume = text;
  else if (name == "OutputTriangles") o->output_triangles = st::parseBool(name, text);
  else if (name == "OutputVolume") o->output_volume = st::parseBool(name, text);
  else if (name == "output_directory") o->output_directory = text;
  else if (name == "InteractiveMode" || name == "preset") return true;  // handled by the caller
  else return false;
  return true;
}

/// dynamic_reconfigure's generic message view of a config, so live parameters go through the
/// same name table as start-up ones.
std::vector<std::pair<std::string, std::string>> configValues(const sdf_tracker::SdfTrackerConfig& config) {
  dynamic_reconfigure::Config msg;
  config.__toMessage__(msg);
  std::vector<std::pair<std::string, std::string>> values;
  for (const auto& p : msg.doubles) {
    std::ostringstream out;
    out << std::setprecision(17) << p.value;
    values.emplace_back(p.name, out.str());
  }
  for (const auto& p : msg.ints) values.emplace_back(p.name, std::to_string(p.value));
  for (const auto& p : msg.strs) values.emplace_back(p.name, p.value);
  for (const auto& p : msg.bools) values.emplace_back(p.name, p.value ? "true" : "false");
  return values;
}

sdf_tracker::SdfTrackerConfig configFromSettings(const st::Settings& settings) {
  dynamic_reconfigure::Config msg;
  for (const auto& description : sdf_tracker::SdfTrackerConfig::__getParamDescriptions__()) {
    const st::ParameterSpec* spec = st::findParameter(description->name);
    const std::string text = spec->get(settings);
    if (description->type == "double") {
      dynamic_reconfigure::DoubleParameter p;
      p.name = description->name, p.value = std::stod(text);
      msg.doubles.push_back(p);
    } else if (description->type == "int") {
      dynamic_reconfigure::IntParameter p;
      p.name = description->name, p.value = std::stoi(text);
      msg.ints.push_back(p);
    } else if (description->type == "bool") {
      dynamic_reconfigure::BoolParameter p;
      p.name = description->name, p.value = text == "true";
      msg.bools.push_back(p);
    } else {
      dynamic_reconfigure::StrParameter p;
      p.name = description->name, p.value = text;
      msg.strs.push_back(p);
    }
  }
  sdf_tracker::SdfTrackerConfig config = sdf_tracker::SdfTrackerConfig::__getDefault__();
  config.__fromMessage__(msg);
  return config;
}

std::string statusText(const st::TrackResult& result) {
  std::string text = st::toString(result.status);
  if (!result.message.empty()) text += ": " + result.message;
  return text;
}

}  // namespace

void readParameters(const ros::NodeHandle& pnh, st::Settings* settings, NodeOptions* options,
                    std::vector<std::string>* unknown) {
  std::string preset_name = "default";
  pnh.param<std::string>("preset", preset_name, preset_name);
  *settings = st::preset(preset_name);

  std::vector<std::string> all;
  pnh.getParamNames(all);
  const std::string prefix = pnh.getNamespace() + "/";
  st::Violations errors;
  for (const std::string& full : all) {
    if (full.rfind(prefix, 0) != 0) continue;
    const std::string name = full.substr(prefix.size());
    if (name.find('/') != std::string::npos) continue;  // nested namespaces belong to others
    XmlRpc::XmlRpcValue value;
    pnh.getParam(name, value);
    std::string text;
    try {
      text = toText(value);
    } catch (const std::invalid_argument& e) {
      errors.require(false, "~" + name + " " + e.what());
      continue;
    }
    try {
      if (st::findParameter(name)) {
        st::setParameter(settings, name, text);
        if (name.rfind("FocalLength", 0) == 0 || name.rfind("CenterPoint", 0) == 0) {
          options->intrinsics_from_parameters = true;
        }
      } else if (!applyNodeOption(options, name, text)) {
        unknown->push_back(name);
      }
    } catch (const std::invalid_argument& e) {
      errors.require(false, e.what());  // names the parameter and the value
    }
  }
  errors.merge("", settings->validate());
  errors.require(options->cloud_rate_hz >= 0.0, "~cloud_rate must be >= 0");
  errors.require(options->mesh_rate_hz >= 0.0, "~mesh_rate must be >= 0");
  st::throwIfInvalid("parameters of " + pnh.getNamespace(), errors.list());
}

TrackerServer::TrackerServer(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh), pnh_(pnh), it_(nh) {
  std::vector<std::string> unknown;
  readParameters(pnh_, &settings_, &options_, &unknown);
  for (const auto& name : unknown) ROS_WARN("sdf_tracker: ignoring unknown parameter ~%s", name.c_str());
  if (pnh_.hasParam("InteractiveMode")) {
    ROS_INFO("sdf_tracker: InteractiveMode is accepted for compatibility; use rviz and the ~reset service instead");
  }
  pipeline_ = std::make_unique<st::SdfPipeline>(settings_.pipeline);
  if (options_.load_volume != "none" && !options_.load_volume.empty()) {
    pipeline_->setVolume(st::io::readVti(options_.load_volume));
    ROS_INFO("sdf_tracker: tracking against the map in %s", options_.load_volume.c_str());
  }
  path_.header.frame_id = options_.world_frame;

  const std::string depth_topic =
      options_.camera_name + (options_.depth_registered ? "/depth_registered/image" : "/depth/image");
  if (options_.intrinsics_from_parameters) {
    depth_only_sub_ = it_.subscribe(depth_topic, 1, [this](const sensor_msgs::ImageConstPtr& image) {
      depthCallback(image, nullptr);
    });
    depth_topic_ = depth_only_sub_.getTopic();
  } else {
    depth_sub_ = it_.subscribeCamera(depth_topic, 1, &TrackerServer::depthCallback, this);
    depth_topic_ = depth_sub_.getTopic();
  }
  info_topic_ = image_transport::getCameraInfoTopic(depth_topic_);
  info_watch_sub_ = nh_.subscribe<sensor_msgs::CameraInfo>(
      info_topic_, 1, [this](const sensor_msgs::CameraInfoConstPtr& info) {
        std::lock_guard<std::mutex> lock(mutex_);
        last_info_wall_ = ros::WallTime::now();
        last_info_ = info;
      });
  last_frame_wall_ = ros::WallTime::now();
  watchdog_timer_ = nh_.createTimer(ros::Duration(2.0), &TrackerServer::checkInputs, this);
  denoised_pub_ = it_.advertise(options_.camera_name + "/depth/image_denoised", 1);
  pose_pub_ = pnh_.advertise<geometry_msgs::PoseStamped>("pose", 10);
  path_pub_ = pnh_.advertise<nav_msgs::Path>("path", 1, true);
  status_pub_ = pnh_.advertise<sdf_tracker::TrackingStatus>("status", 10);
  cloud_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("cloud", 1, true);
  mesh_pub_ = pnh_.advertise<visualization_msgs::Marker>("mesh", 1, true);
  reset_srv_ = pnh_.advertiseService("reset", &TrackerServer::reset, this);
  save_mesh_srv_ = pnh_.advertiseService("save_mesh", &TrackerServer::saveMesh, this);
  save_volume_srv_ = pnh_.advertiseService("save_volume", &TrackerServer::saveVolume, this);
  load_volume_srv_ = pnh_.advertiseService("load_volume", &TrackerServer::loadVolume, this);
  if (options_.cloud_rate_hz > 0.0) {
    cloud_timer_ = nh_.createTimer(ros::Duration(1.0 / options_.cloud_rate_hz), &TrackerServer::publishCloud, this);
  }
  if (options_.mesh_rate_hz > 0.0) {
    mesh_timer_ = nh_.createTimer(ros::Duration(1.0 / options_.mesh_rate_hz), &TrackerServer::publishMesh, this);
  }
  // Start the reconfigure server from our values, not the cfg file's defaults.
  configFromSettings(settings_).__toServer__(pnh_);
  reconfigure_server_ = std::make_unique<dynamic_reconfigure::Server<sdf_tracker::SdfTrackerConfig>>(pnh_);
  reconfigure_server_->setCallback(
      [this](sdf_tracker::SdfTrackerConfig& config, uint32_t level) { reconfigure(config, level); });

  const auto& v = settings_.pipeline.volume;
  ROS_INFO("sdf_tracker: listening on %s (%s); grid %dx%dx%d of %.3f m; intrinsics from %s", depth_topic_.c_str(),
           info_topic_.c_str(), v.dims.x(), v.dims.y(), v.dims.z(),
           v.voxel_size_m, options_.intrinsics_from_parameters ? "parameters" : "camera_info");
}

TrackerServer::~TrackerServer() {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    writeTrajectory();
    if (!options_.mesh_file.empty()) st::io::writePly(options_.mesh_file, st::extractMesh(pipeline_->volume()));
    if (!options_.cloud_file.empty()) st::io::writePly(options_.cloud_file, st::extractSurfaceCloud(pipeline_->volume()));
    if (options_.output_triangles) {
      st::io::writeObj(outputPath("", "triangles.obj"), st::extractMesh(pipeline_->volume()));
    }
    if (options_.output_volume) st::io::writeVti(outputPath("", "sdf_volume.vti"), pipeline_->volume());
  } catch (const std::exception& e) {
    ROS_ERROR("sdf_tracker: at shut-down: %s", e.what());
  }
}

std::string TrackerServer::outputPath(const std::string& requested, const std::string& default_name) const {
  return requested.empty() ? options_.output_directory + "/" + default_name : requested;
}

void TrackerServer::writeTrajectory() {
  if (options_.trajectory_file.empty()) return;
  st::io::writeTrajectory(options_.trajectory_file, trajectory_);
  ROS_INFO("sdf_tracker: wrote %zu poses to %s", trajectory_.size(), options_.trajectory_file.c_str());
}

void TrackerServer::checkInputs(const ros::TimerEvent&) {
  // Images without a matching camera_info never reach depthCallback: say so instead of idling.
  const ros::WallTime now = ros::WallTime::now();
  std::lock_guard<std::mutex> lock(mutex_);
  if (options_.intrinsics_from_parameters || (now - last_frame_wall_).toSec() < 3.0) return;
  const uint32_t publishers = depth_sub_.getNumPublishers();
  if (publishers == 0) return;
  if (last_info_wall_.isZero() || (now - last_info_wall_).toSec() > 3.0) {
    ROS_ERROR_THROTTLE(10.0, "sdf_tracker: %s has a publisher but no camera_info arrives on %s; frames cannot be "
                       "used (publish camera_info, or set FocalLengthX/Y and CenterPointX/Y)",
                       depth_topic_.c_str(), info_topic_.c_str());
  } else {
    ROS_WARN_THROTTLE(10.0, "sdf_tracker: no frame for %.0f s although %s and %s have publishers: are their stamps "
                      "equal?", (now - last_frame_wall_).toSec(), depth_topic_.c_str(), info_topic_.c_str());
  }
}

void TrackerServer::depthCallback(const sensor_msgs::ImageConstPtr& image,
                                  const sensor_msgs::CameraInfoConstPtr& synchronised_info) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_frame_wall_ = ros::WallTime::now();
  const std::string& topic = depth_topic_;
  sdf_tracker::TrackingStatus status;
  status.header = image->header;
  if (last_seq_ && image->header.seq > *last_seq_ + 1) frames_dropped_ += image->header.seq - *last_seq_ - 1;
  last_seq_ = image->header.seq;
  status.frames_dropped = frames_dropped_;

  auto drop = [&](const std::string& why) {
    ROS_ERROR_THROTTLE(kThrottle_s, "sdf_tracker: dropping a frame from %s: %s", topic.c_str(), why.c_str());
    status.status = sdf_tracker::TrackingStatus::BAD_INPUT;
    status.status_text = "bad_input: " + why;
    status_pub_.publish(status);
  };

  st::DepthImage depth;
  st::PinholeCamera camera;
  try {
    depth = toDepthImage(*image);
    if (options_.intrinsics_from_parameters) {
      camera = settings_.camera();
      const sensor_msgs::CameraInfoConstPtr info = last_info_;
      if (!warned_intrinsics_ && info && info->K[0] > 0.0 &&
          (std::abs(info->K[0] - camera.fx) > 1e-3 || std::abs(info->K[2] - camera.cx) > 1e-3)) {
        ROS_WARN("sdf_tracker: FocalLength/CenterPoint parameters (fx %.2f, cx %.2f) disagree with %s (fx %.2f, "
                 "cx %.2f); using the parameters",
                 camera.fx, camera.cx, info_topic_.c_str(), info->K[0], info->K[2]);
        warned_intrinsics_ = true;
      }
    } else {
      camera = toCamera(*synchronised_info);
    }
  } catch (const std::invalid_argument& e) {
    return drop(e.what());
  }
  if (depth.width() != camera.width || depth.height() != camera.height) {
    return drop("image is " + std::to_string(depth.width()) + "x" + std::to_string(depth.height()) +
                " but the camera is " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
  if (!last_stamp_.isZero() && image->header.stamp < last_stamp_) {
    ROS_WARN("sdf_tracker: time went backwards on %s (bag restarted?): resetting the map", topic.c_str());
    pipeline_->reset();
    trajectory_.clear();
    path_.poses.clear();
  }
  last_stamp_ = image->header.stamp;

  const st::FrameReport report = pipeline_->processFrame(depth, camera);
  ++frames_processed_;
  sum_frame_ms_ += report.tracking_ms + report.fusion_ms;
  ROS_INFO_THROTTLE(5.0, "sdf_tracker: %u frames processed, %u dropped, %.1f ms per frame on average (%.1f frames/s)",
                    frames_processed_, frames_dropped_, sum_frame_ms_ / frames_processed_,
                    1000.0 * frames_processed_ / sum_frame_ms_);
  const st::TrackResult& t = report.track;
  status.status = static_cast<uint8_t>(t.status);
  status.status_text = statusText(t);
  status.iterations_per_level = t.iterations_per_level;
  status.rms_residual_m = t.rms_residual_m;
  status.valid_points = t.valid_points;
  status.inverse_condition = t.inverse_condition;
  status.tracking_ms = report.tracking_ms;
  status.fusion_ms = report.fusion_ms;
  status.fused = report.fused;
  status_pub_.publish(status);
  if (t.status == st::TrackStatus::kBadInput) {
    ROS_ERROR_THROTTLE(kThrottle_s, "sdf_tracker: dropping a frame from %s: %s", topic.c_str(), t.message.c_str());
    return;
  }
  if (!t.ok()) ROS_WARN_THROTTLE(kThrottle_s, "sdf_tracker: %s (pose held, frame not fused)", status.status_text.c_str());
  if (report.reset) ROS_WARN("sdf_tracker: map cleared after %d failed frames in a row", settings_.pipeline.reset_after_failures);

  last_camera_frame_ = options_.camera_frame.empty() ? image->header.frame_id : options_.camera_frame;
  trajectory_.push_back({image->header.stamp.toSec(), pipeline_->pose()});
  publishPose(image->header, pipeline_->pose(), last_camera_frame_);

  if (denoised_pub_.getNumSubscribers() > 0) {
    const st::RaycastImage cast =
        st::raycast(pipeline_->volume(), camera, pipeline_->pose(), settings_.pipeline.raycast, &depth);
    denoised_pub_.publish(toImageMsg(cast.depth, image->header));
  }
}

void TrackerServer::publishPose(const std_msgs::Header& header, const Eigen::Isometry3d& T_W_C,
                                const std::string& camera_frame) {
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = header.stamp;
  pose.header.frame_id = options_.world_frame;
  pose.pose = toPoseMsg(T_W_C);
  pose_pub_.publish(pose);
  path_.header.stamp = header.stamp;
  path_.poses.push_back(pose);
  path_pub_.publish(path_);

  std::vector<geometry_msgs::TransformStamped> transforms;
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = header.stamp;
  tf.header.frame_id = options_.world_frame;
  std::string parent = options_.world_frame;
  if (!options_.odom_frame.empty()) {  // map -> odom stays identity: this tracker has no loop closure
    tf.child_frame_id = options_.odom_frame;
    tf.transform.rotation.w = 1.0;
    transforms.push_back(tf);
    tf.header.frame_id = parent = options_.odom_frame;
  }
  tf.child_frame_id = camera_frame;
  tf.transform.translation.x = pose.pose.position.x;
  tf.transform.translation.y = pose.pose.position.y;
  tf.transform.translation.z = pose.pose.position.z;
  tf.transform.rotation = pose.pose.orientation;
  transforms.push_back(tf);
  tf_broadcaster_.sendTransform(transforms);
}

template <typename Extract, typename Convert>
void TrackerServer::publishMap(const ros::Publisher& publisher, Extract extract, Convert convert) {
  if (publisher.getNumSubscribers() == 0) return;  // extraction walks the whole grid
  std_msgs::Header header;
  decltype(extract()) map;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    map = extract();
    header.stamp = last_stamp_;
  }
  header.frame_id = options_.world_frame;
  publisher.publish(convert(map, header));
}

void TrackerServer::publishCloud(const ros::TimerEvent&) {
  publishMap(cloud_pub_, [this] { return st::extractSurfaceCloud(pipeline_->volume()); }, toCloudMsg);
}

void TrackerServer::publishMesh(const ros::TimerEvent&) {
  publishMap(mesh_pub_, [this] { return st::extractMesh(pipeline_->volume()); }, toMarker);
}

void TrackerServer::reconfigure(sdf_tracker::SdfTrackerConfig& config, uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(mutex_);
  st::Settings candidate = settings_;
  try {
    for (const auto& [name, value] : configValues(config)) st::setParameter(&candidate, name, value);
    pipeline_->updateConfig(candidate.pipeline);  // validates; throws and changes nothing when invalid
    settings_ = candidate;
    ROS_INFO("sdf_tracker: reconfigured");
  } catch (const std::invalid_argument& e) {
    ROS_ERROR("sdf_tracker: rejected reconfiguration: %s", e.what());
    config = configFromSettings(settings_);  // reports the values still in force
  }
}

bool TrackerServer::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  std::lock_guard<std::mutex> lock(mutex_);
  pipeline_->reset();
  trajectory_.clear();
  path_.poses.clear();
  ROS_INFO("sdf_tracker: map and pose reset");
  return true;
}

bool TrackerServer::answer(sdf_tracker::SavePath::Response& res, const std::function<std::string()>& action) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    res.message = action();
    res.success = true;
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;  // the call itself succeeded; the response says whether the action did
}

bool TrackerServer::saveMesh(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "mesh.ply");
    const st::TriangleMesh mesh = st::extractMesh(pipeline_->volume());
    const bool obj = path.size() > 4 && path.compare(path.size() - 4, 4, ".obj") == 0;
    obj ? st::io::writeObj(path, mesh) : st::io::writePly(path, mesh);
    writeTrajectory();
    return "wrote " + std::to_string(mesh.triangles.size()) + " triangles to " + path;
  });
}

bool TrackerServer::saveVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "sdf_volume.vti");
    st::io::writeVti(path, pipeline_->volume());
    writeTrajectory();
    return "wrote the volume to " + path;
  });
}

bool TrackerServer::loadVolume(sdf_tracker::SavePath::Request& req, sdf_tracker::SavePath::Response& res) {
  return answer(res, [&] {
    const std::string path = outputPath(req.path, "sdf_volume.vti");
    pipeline_->setVolume(st::io::readVti(path, settings_.pipeline.volume.compact_voxels));
    trajectory_.clear();
    path_.poses.clear();
    return "tracking against " + path;
  });
}

}  // namespace sdf_tracker_ros
