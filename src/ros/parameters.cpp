#include "sdf_tracker/ros/parameters.h"

#include <functional>
#include <map>
#include <stdexcept>

#include "sdf_tracker/io/map_file.h"
#include "sdf_tracker/ros/conversions.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker_ros {

namespace st = sdf_tracker;

std::string stripSlash(const std::string& frame_id) {
  const size_t first = frame_id.find_first_not_of('/');
  return first == std::string::npos ? std::string() : frame_id.substr(first);
}

namespace {

st::ParameterValue toValue(const std::string& name, XmlRpc::XmlRpcValue value) {  // the accessors are non-const
  switch (value.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return static_cast<bool>(value);
    case XmlRpc::XmlRpcValue::TypeInt: return static_cast<int>(value);
    case XmlRpc::XmlRpcValue::TypeDouble: return static_cast<double>(value);
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(value);
    default:
      throw std::invalid_argument(name + " has an unsupported type (expected a number, true/false or text)");
  }
}

/// A node option: how to store a value, checked, into NodeOptions.
using OptionSetter = std::function<void(NodeOptions&, const st::ParameterValue&)>;

std::string textOf(const std::string& name, const st::ParameterValue& v) {
  if (const auto* s = std::get_if<std::string>(&v)) return *s;
  throw std::invalid_argument(name + ": expected text, got " + st::toText(v));
}
bool boolOf(const std::string& name, const st::ParameterValue& v) {
  if (const auto* b = std::get_if<bool>(&v)) return *b;
  if (const auto* s = std::get_if<std::string>(&v)) return st::parseBool(name, *s);
  throw std::invalid_argument(name + ": expected true or false, got " + st::toText(v));
}
double nonNegativeOf(const std::string& name, const st::ParameterValue& v) {
  double d;
  if (const auto* i = std::get_if<int>(&v)) d = *i;
  else if (const auto* x = std::get_if<double>(&v)) d = *x;
  else throw std::invalid_argument(name + ": expected a number, got \"" + st::toText(v) + "\"");
  if (!(d >= 0.0 && std::isfinite(d))) throw std::invalid_argument(name + " must be >= 0 (got " + st::toText(v) + ")");
  return d;
}
std::string frameOf(const std::string& name, const st::ParameterValue& v) { return stripSlash(textOf(name, v)); }

const std::map<std::string, OptionSetter>& nodeOptionTable() {
  static const std::map<std::string, OptionSetter> table = {
      {"preset", [](NodeOptions& o, const st::ParameterValue& v) { o.preset = textOf("preset", v); }},
      {"c_name", [](NodeOptions& o, const st::ParameterValue& v) { o.camera_name = textOf("c_name", v); }},
      {"depth_registered",
       [](NodeOptions& o, const st::ParameterValue& v) { o.depth_registered = boolOf("depth_registered", v); }},
      {"colour_topic", [](NodeOptions& o, const st::ParameterValue& v) { o.colour_topic = textOf("colour_topic", v); }},
      {"colour_registered",
       [](NodeOptions& o, const st::ParameterValue& v) { o.colour_registered = boolOf("colour_registered", v); }},
      {"map_frame", [](NodeOptions& o, const st::ParameterValue& v) { o.frames.map_frame = frameOf("map_frame", v); }},
      {"odom_frame", [](NodeOptions& o, const st::ParameterValue& v) { o.frames.odom_frame = frameOf("odom_frame", v); }},
      {"base_frame", [](NodeOptions& o, const st::ParameterValue& v) { o.frames.base_frame = frameOf("base_frame", v); }},
      {"camera_frame",
       [](NodeOptions& o, const st::ParameterValue& v) { o.frames.camera_frame = frameOf("camera_frame", v); }},
      {"imu_topic", [](NodeOptions& o, const st::ParameterValue& v) { o.imu_topic = textOf("imu_topic", v); }},
      {"cloud_rate", [](NodeOptions& o, const st::ParameterValue& v) { o.cloud_rate_hz = nonNegativeOf("cloud_rate", v); }},
      {"mesh_rate", [](NodeOptions& o, const st::ParameterValue& v) { o.mesh_rate_hz = nonNegativeOf("mesh_rate", v); }},
      {"path_length",
       [](NodeOptions& o, const st::ParameterValue& v) {
         const double n = nonNegativeOf("path_length", v);
         if (n < 1 || n > 1e7 || n != std::floor(n)) {
           throw std::invalid_argument("path_length must be a whole number in [1, 10000000] (got " + st::toText(v) + ")");
         }
         o.path_length = static_cast<int>(n);
       }},
      {"time_jump_reset",
       [](NodeOptions& o, const st::ParameterValue& v) { o.time_jump_reset_s = nonNegativeOf("time_jump_reset", v); }},
      {"trajectory_file",
       [](NodeOptions& o, const st::ParameterValue& v) { o.trajectory_file = textOf("trajectory_file", v); }},
      {"mesh_file", [](NodeOptions& o, const st::ParameterValue& v) { o.mesh_file = textOf("mesh_file", v); }},
      {"cloud_file", [](NodeOptions& o, const st::ParameterValue& v) { o.cloud_file = textOf("cloud_file", v); }},
      {"LoadVolume", [](NodeOptions& o, const st::ParameterValue& v) { o.load_volume = textOf("LoadVolume", v); }},
      {"OutputTriangles",
       [](NodeOptions& o, const st::ParameterValue& v) { o.output_triangles = boolOf("OutputTriangles", v); }},
      {"OutputVolume", [](NodeOptions& o, const st::ParameterValue& v) { o.output_volume = boolOf("OutputVolume", v); }},
      {"output_directory",
       [](NodeOptions& o, const st::ParameterValue& v) { o.output_directory = textOf("output_directory", v); }},
      {"tum_camera",
       [](NodeOptions& o, const st::ParameterValue& v) {
         o.tum_camera = textOf("tum_camera", v);
         if (!o.tum_camera.empty()) tumCameraNamed(o.tum_camera);  // refused here, before any frame
       }},
      // Accepted for the reference release's launch file; rviz and ~reset replace its GUI.
      {"InteractiveMode", [](NodeOptions&, const st::ParameterValue& v) { boolOf("InteractiveMode", v); }},
  };
  return table;
}

}  // namespace

void readParameters(const ros::NodeHandle& pnh, st::Settings* settings, NodeOptions* options,
                    std::vector<std::string>* warnings, std::vector<std::string>* notes) {
  // Every private parameter, typed as the server holds it.
  std::map<std::string, st::ParameterValue> given;
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
    try {
      given[name] = toValue(name, value);
    } catch (const std::invalid_argument& e) {
      errors.require(false, e.what());
    }
  }

  // The preset first: it gives every other parameter its starting value.
  *options = NodeOptions();
  if (given.count("preset")) {
    try {
      options->preset = textOf("preset", given["preset"]);
      *settings = st::preset(options->preset);
    } catch (const std::invalid_argument& e) {
      errors.require(false, std::string("~preset: ") + e.what());
      *settings = st::preset("default");
    }
  } else {
    *settings = st::preset(options->preset);
  }

  for (const auto& [name, value] : given) {
    try {
      if (st::findParameter(name)) {
        // A number typed as text in a launch file (<param type="str">) still reads as a number.
        if (const auto* text = std::get_if<std::string>(&value)) st::setParameterFromText(settings, name, *text);
        else st::setParameter(settings, name, value);
        if (name.rfind("FocalLength", 0) == 0 || name.rfind("CenterPoint", 0) == 0) {
          options->intrinsics_from_parameters = true;
        }
      } else if (const auto option = nodeOptionTable().find(name); option != nodeOptionTable().end()) {
        option->second(*options, value);
      } else {
        warnings->push_back("ignoring unknown parameter ~" + name);
      }
    } catch (const std::invalid_argument& e) {
      errors.require(false, std::string("~") + e.what());
    }
  }
  // The frames of the tree this node publishes into: map names one, and no two are the same.
  const FrameOptions& f = options->frames;
  errors.require(!f.map_frame.empty(), "~map_frame must name a frame (got \"\")");
  const std::vector<std::pair<const char*, std::string>> frames = {
      {"map_frame", f.map_frame}, {"odom_frame", f.odom_frame}, {"base_frame", f.base_frame},
      {"camera_frame", f.camera_frame}};
  for (size_t a = 0; a < frames.size(); ++a) {
    for (size_t b = a + 1; b < frames.size(); ++b) {
      errors.require(frames[a].second.empty() || frames[a].second != frames[b].second,
                     std::string("~") + frames[a].first + " and ~" + frames[b].first + " are both \"" +
                         frames[a].second + "\": a frame cannot be its own parent");
    }
  }
  errors.require(
      options->tum_camera.empty() || !options->intrinsics_from_parameters,
      "~tum_camera (" + options->tum_camera + ") and FocalLength/CenterPoint both give the intrinsics: set one");
  for (const auto& entry : given) options->given_parameters.push_back(entry.first);
  const bool loads_dense_map = st::io::readsAsDenseGrid(options->load_volume);
  if (const auto note = settings->keepToOneMapWhereNeeded(options->given_parameters, loads_dense_map)) {
    notes->push_back(*note);
  }
  if (errors.list().empty()) errors.merge("", settings->validate());
  st::throwIfInvalid("parameters of " + pnh.getNamespace(), errors.list());
  for (const std::string& note : settings->withoutEffect(options->given_parameters)) warnings->push_back("~" + note);
}

std::vector<std::pair<std::string, st::ParameterValue>> reconfigureValues(const sdf_tracker::SdfTrackerConfig& config) {
  dynamic_reconfigure::Config msg;
  config.__toMessage__(msg);
  std::vector<std::pair<std::string, st::ParameterValue>> values;
  for (const auto& p : msg.doubles) values.emplace_back(p.name, p.value);
  for (const auto& p : msg.ints) values.emplace_back(p.name, static_cast<int>(p.value));
  for (const auto& p : msg.strs) values.emplace_back(p.name, p.value);
  for (const auto& p : msg.bools) values.emplace_back(p.name, static_cast<bool>(p.value));
  return values;
}

sdf_tracker::SdfTrackerConfig toReconfigureConfig(const st::Settings& settings) {
  dynamic_reconfigure::Config msg;
  for (const auto& description : sdf_tracker::SdfTrackerConfig::__getParamDescriptions__()) {
    const st::ParameterSpec* spec = st::findParameter(description->name);
    if (!spec) throw std::logic_error("cfg/SdfTracker.cfg names " + description->name + ", which the table lacks");
    const st::ParameterValue value = spec->get(settings);
    if (const auto* d = std::get_if<double>(&value)) {
      dynamic_reconfigure::DoubleParameter p;
      p.name = description->name, p.value = *d;
      msg.doubles.push_back(p);
    } else if (const auto* i = std::get_if<int>(&value)) {
      dynamic_reconfigure::IntParameter p;
      p.name = description->name, p.value = *i;
      msg.ints.push_back(p);
    } else if (const auto* b = std::get_if<bool>(&value)) {
      dynamic_reconfigure::BoolParameter p;
      p.name = description->name, p.value = *b;
      msg.bools.push_back(p);
    } else {
      dynamic_reconfigure::StrParameter p;
      p.name = description->name, p.value = std::get<std::string>(value);
      msg.strs.push_back(p);
    }
  }
  sdf_tracker::SdfTrackerConfig config = sdf_tracker::SdfTrackerConfig::__getDefault__();
  config.__fromMessage__(msg);
  return config;
}

}  // namespace sdf_tracker_ros
