#include "sdf_tracker/core/parameters.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

double parseNumber(const std::string& name, const std::string& text) {
  std::istringstream in(text);
  double value;
  std::string rest;
  if (!(in >> value) || (in >> rest)) {
    throw std::invalid_argument(name + ": expected a number, got \"" + text + "\"");
  }
  return value;
}

int parseInteger(const std::string& name, const std::string& text) {
  const double value = parseNumber(name, text);
  if (value != static_cast<int>(value)) throw std::invalid_argument(name + ": expected an integer, got \"" + text + "\"");
  return static_cast<int>(value);
}

bool parseBool(const std::string& name, const std::string& text) {
  if (text == "true" || text == "1") return true;
  if (text == "false" || text == "0") return false;
  throw std::invalid_argument(name + ": expected true or false, got \"" + text + "\"");
}

namespace {

std::string toText(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

/// A numeric parameter bound to a field through a member accessor.
template <typename T, typename Accessor>
ParameterSpec numeric(const std::string& name, const std::string& description, bool live, Accessor field) {
  return ParameterSpec{
      name, description, live,
      [name, field](Settings& s, const std::string& text) {
        if constexpr (std::is_integral_v<T>) field(s) = parseInteger(name, text);
        else field(s) = static_cast<T>(parseNumber(name, text));
      },
      [field](const Settings& s) { return toText(static_cast<double>(field(s))); }};
}

/// A true/false parameter bound to a bool field.
template <typename Accessor>
ParameterSpec flag(const std::string& name, const std::string& description, bool live, Accessor field) {
  return ParameterSpec{name, description, live,
                       [name, field](Settings& s, const std::string& text) { field(s) = parseBool(name, text); },
                       [field](const Settings& s) { return std::string(field(s) ? "true" : "false"); }};
}

std::vector<ParameterSpec> buildTable() {
  using S = Settings;
  std::vector<ParameterSpec> t;
  // The reference release's parameters, with their reference meaning.
  t.push_back(numeric<double>("CellSize", "voxel edge length [m]", false,
                              [](auto& s) -> auto& { return s.pipeline.volume.voxel_size_m; }));
  t.push_back(numeric<int>("GridSizeX", "voxels along x", false, [](auto& s) -> auto& { return s.pipeline.volume.dims.x(); }));
  t.push_back(numeric<int>("GridSizeY", "voxels along y", false, [](auto& s) -> auto& { return s.pipeline.volume.dims.y(); }));
  t.push_back(numeric<int>("GridSizeZ", "voxels along z", false, [](auto& s) -> auto& { return s.pipeline.volume.dims.z(); }));
  t.push_back(numeric<double>("PositiveTruncationDistance", "Dmax [m], > 0", false,
                              [](auto& s) -> auto& { return s.pipeline.volume.positive_truncation_m; }));
  t.push_back(numeric<double>("NegativeTruncationDistance", "Dmin [m], < 0", true,
                              [](auto& s) -> auto& { return s.pipeline.integrator.negative_truncation_m; }));
  t.push_back(numeric<double>("RobustStatisticCoefficient", "Huber k as a fraction of Dmax", true,
                              [](auto& s) -> auto& { return s.pipeline.tracker.huber_coefficient; }));
  t.push_back(numeric<double>("Regularization", "Tikhonov alpha per iteration", true,
                              [](auto& s) -> auto& { return s.pipeline.tracker.regularization; }));
  t.push_back(numeric<double>("MinPoseChangeToFuseData", "fuse only after moving this much (m and rad)", true,
                              [](auto& s) -> auto& { return s.pipeline.min_pose_change_to_fuse; }));
  t.push_back(numeric<double>("ConvergenceCondition", "a level ends when |delta xi| is below this", true,
                              [](auto& s) -> auto& { return s.pipeline.tracker.convergence_threshold; }));
  t.push_back(numeric<int>("MaximumRaycastSteps", "steps when ray casting from a measured depth", true,
                           [](auto& s) -> auto& { return s.pipeline.raycast.max_refinement_steps; }));
  t.push_back(numeric<double>("MaxWeight", "Wmax, the weight cap", true,
                              [](auto& s) -> auto& { return s.pipeline.integrator.max_weight; }));
  t.push_back(numeric<int>("ImageWidth", "image width (640, 320 or 160)", false, [](auto& s) -> auto& { return s.image_width; }));
  t.push_back(numeric<int>("ImageHeight", "image height (480, 240 or 120)", false,
                           [](auto& s) -> auto& { return s.image_height; }));
  t.push_back(numeric<double>("FocalLengthX", "fx at 640x480 [px]", false, [](auto& s) -> auto& { return s.camera_vga.fx; }));
  t.push_back(numeric<double>("FocalLengthY", "fy at 640x480 [px]", false, [](auto& s) -> auto& { return s.camera_vga.fy; }));
  t.push_back(numeric<double>("CenterPointX", "cx at 640x480 [px]", false, [](auto& s) -> auto& { return s.camera_vga.cx; }));
  t.push_back(numeric<double>("CenterPointY", "cy at 640x480 [px]", false, [](auto& s) -> auto& { return s.camera_vga.cy; }));
  // This package's own parameters.
  t.push_back(ParameterSpec{
      "TrackingSchedule", "coarse-to-fine levels, stride x iterations, e.g. 4x12,2x6,1x2", true,
      [](S& s, const std::string& text) { s.pipeline.tracker.levels = parseSchedule(text); },
      [](const S& s) { return formatSchedule(s.pipeline.tracker.levels); }});
  t.push_back(numeric<double>("MinDepth", "nearer depth is no measurement [m]", true,
                              [](auto& s) -> auto& { return s.pipeline.min_depth_m; }));
  t.push_back(numeric<double>("MaxDepth", "further depth is no measurement [m]", true,
                              [](auto& s) -> auto& { return s.pipeline.max_depth_m; }));
  t.push_back(ParameterSpec{
      "DepthWeighting", "fusion weights: constant (rolling average) or sensor (inverse depth-noise variance)", true,
      [](S& s, const std::string& text) {
        if (text == "constant") s.pipeline.integrator.weighting = MeasurementWeighting::kConstant;
        else if (text == "sensor") s.pipeline.integrator.weighting = MeasurementWeighting::kSensorNoise;
        else throw std::invalid_argument("DepthWeighting: expected constant or sensor, got \"" + text + "\"");
      },
      [](const S& s) {
        return std::string(s.pipeline.integrator.weighting == MeasurementWeighting::kConstant ? "constant" : "sensor");
      }});
  t.push_back(flag("TrackingSensorWeights", "weight tracked points by depth noise", true,
                   [](auto& s) -> auto& { return s.pipeline.tracker.sensor_weights; }));
  t.push_back(flag("NormalizeResiduals", "divide residuals by the field's gradient norm (metric distances)", true,
                   [](auto& s) -> auto& { return s.pipeline.tracker.normalize_by_gradient; }));
  t.push_back(flag("CompactVoxels", "4-byte voxels (half the memory; distance and weight quantised)", false,
                   [](auto& s) -> auto& { return s.pipeline.volume.compact_voxels; }));
  t.push_back(numeric<int>("MinValidPoints", "fewer tracked points than this: too_few_points", true,
                           [](auto& s) -> auto& { return s.pipeline.tracker.min_valid_points; }));
  t.push_back(numeric<double>("MinInverseCondition", "below this the geometry is degenerate", true,
                              [](auto& s) -> auto& { return s.pipeline.tracker.min_inverse_condition; }));
  t.push_back(numeric<int>("ResetAfterFailures", "clear the map after this many failed frames in a row; 0 never", true,
                           [](auto& s) -> auto& { return s.pipeline.reset_after_failures; }));
  t.push_back(numeric<double>("InitialCameraX", "first camera's place in the grid along x (fraction)", false,
                              [](auto& s) -> auto& { return s.pipeline.initial_camera_in_grid.x(); }));
  t.push_back(numeric<double>("InitialCameraY", "first camera's place in the grid along y (fraction)", false,
                              [](auto& s) -> auto& { return s.pipeline.initial_camera_in_grid.y(); }));
  t.push_back(numeric<double>("InitialCameraZ", "first camera's place in the grid along z (fraction)", false,
                              [](auto& s) -> auto& { return s.pipeline.initial_camera_in_grid.z(); }));
  return t;
}

}  // namespace

std::vector<std::string> Settings::validate() const {
  Violations v;
  v.merge("", pipeline.validate());
  v.merge("camera: ", camera_vga.validate());
  try {
    camera();
  } catch (const std::invalid_argument& e) {
    v.require(false, std::string("ImageWidth/ImageHeight: ") + e.what());
  }
  return v.list();
}

const std::vector<ParameterSpec>& parameterTable() {
  static const std::vector<ParameterSpec> table = buildTable();
  return table;
}

const ParameterSpec* findParameter(const std::string& name) {
  const auto& table = parameterTable();
  auto it = std::find_if(table.begin(), table.end(), [&name](const ParameterSpec& p) { return p.name == name; });
  return it == table.end() ? nullptr : &*it;
}

void setParameter(Settings* settings, const std::string& name, const std::string& value) {
  const ParameterSpec* spec = findParameter(name);
  if (!spec) throw std::invalid_argument("unknown parameter \"" + name + "\"");
  spec->set(*settings, value);
}

std::vector<PyramidLevel> parseSchedule(const std::string& text) {
  std::vector<PyramidLevel> levels;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t x = item.find('x');
    try {
      if (x == std::string::npos) throw std::invalid_argument("");
      levels.push_back({parseInteger("stride", item.substr(0, x)), parseInteger("iterations", item.substr(x + 1))});
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("TrackingSchedule: expected stride x iterations like 4x12,2x6,1x2, got \"" + text +
                                  "\"");
    }
  }
  if (levels.empty()) throw std::invalid_argument("TrackingSchedule: empty schedule \"" + text + "\"");
  return levels;
}

std::string formatSchedule(const std::vector<PyramidLevel>& levels) {
  std::ostringstream out;
  for (size_t i = 0; i < levels.size(); ++i) out << (i ? "," : "") << levels[i].stride << 'x' << levels[i].max_iterations;
  return out.str();
}

std::vector<std::string> presetNames() { return {"default", "paper", "reference"}; }

Settings preset(const std::string& name) {
  Settings s;  // the struct defaults are the reference release's node defaults
  PipelineConfig& p = s.pipeline;
  if (name == "reference") {
    // The reference release's launch file: 200^3 voxels of 2 cm, truncation 0.08 / -0.04, 12/8/2.
    p.volume.dims = Eigen::Vector3i(200, 200, 200);
    p.volume.voxel_size_m = 0.02;
    p.volume.positive_truncation_m = 0.08;
    p.integrator.negative_truncation_m = -0.04;
    p.tracker.levels = {{4, 12}, {2, 8}, {1, 2}};
    p.min_pose_change_to_fuse = 0.01;
  } else if (name == "paper") {
    // Table II: 3 cm voxels, truncation 0.1 / -0.06, strides 4/2/1 with 12/6/2 iterations.
    p.volume.dims = Eigen::Vector3i(200, 200, 200);
    p.volume.voxel_size_m = 0.03;
    p.volume.positive_truncation_m = 0.1;
    p.integrator.negative_truncation_m = -0.06;
    p.tracker.levels = {{4, 12}, {2, 6}, {1, 2}};
  } else if (name == "default") {
    // The paper's algorithm with three measured improvements: depth-noise weights in fusion and
    // tracking, residuals normalised by the field's gradient, and a symmetric truncation band
    // (noise behind the surface is not cut off more than noise in front of it).
    p.volume.dims = Eigen::Vector3i(256, 256, 256);
    p.volume.voxel_size_m = 0.02;
    p.volume.positive_truncation_m = 0.1;
    p.integrator.negative_truncation_m = -0.1;
    p.integrator.weighting = MeasurementWeighting::kSensorNoise;
    p.tracker.sensor_weights = true;
    p.tracker.normalize_by_gradient = true;
    p.tracker.levels = {{4, 12}, {2, 6}, {1, 2}};
  } else {
    throw std::invalid_argument("unknown preset \"" + name + "\" (known: default, paper, reference)");
  }
  return s;
}

}  // namespace sdf_tracker
