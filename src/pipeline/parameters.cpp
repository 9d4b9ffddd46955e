#include "sdf_tracker/pipeline/parameters.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

// ---------------------------------------------------------------------------------------------
// Text and values

double parseNumber(const std::string& name, const std::string& text) {
  std::istringstream in(text);
  double value;
  std::string rest;
  if (!(in >> value) || (in >> rest) || !std::isfinite(value)) {
    throw std::invalid_argument(name + ": expected a number, got \"" + text + "\"");
  }
  return value;
}

namespace {

/// A whole double within int's range as int; nullopt otherwise (never a conversion with
/// undefined behaviour).
std::optional<int> exactInt(double value) {
  if (!(value == std::floor(value)) || value < std::numeric_limits<int>::min() ||
      value > std::numeric_limits<int>::max()) {
    return std::nullopt;
  }
  return static_cast<int>(value);
}

}  // namespace

int parseInteger(const std::string& name, const std::string& text) {
  const std::optional<int> value = exactInt(parseNumber(name, text));
  if (!value) throw std::invalid_argument(name + ": expected a whole number, got \"" + text + "\"");
  return *value;
}

bool parseBool(const std::string& name, const std::string& text) {
  if (text == "true" || text == "1") return true;
  if (text == "false" || text == "0") return false;
  throw std::invalid_argument(name + ": expected true or false, got \"" + text + "\"");
}

std::string toText(const ParameterValue& value) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(int i) const { return std::to_string(i); }
    std::string operator()(double d) const {
      // The shortest text that reads back to the same double ("0.02", not "0.0200000000000000004"),
      // in plain notation where that is short ("10", not "1e+01").
      const bool plain = d == 0.0 || (std::fabs(d) >= 1e-4 && std::fabs(d) < 1e7);
      for (int digits = 1; digits <= std::numeric_limits<double>::max_digits10; ++digits) {
        std::ostringstream out;
        out << std::setprecision(digits) << d;
        if (plain && out.str().find('e') != std::string::npos) continue;
        if (std::stod(out.str()) == d) return out.str();
      }
      std::ostringstream out;
      out << std::setprecision(std::numeric_limits<double>::max_digits10) << d;
      return out.str();
    }
    std::string operator()(const std::string& s) const { return s; }
  };
  return std::visit(Visitor{}, value);
}

const char* toString(ParameterType type) {
  switch (type) {
    case ParameterType::kBool: return "bool";
    case ParameterType::kInt: return "int";
    case ParameterType::kDouble: return "double";
    case ParameterType::kText: return "text";
  }
  return "unknown";
}

bool Range::contains(double value) const {
  if (!std::isfinite(value)) return false;
  const bool above_low = low_open ? value > low : value >= low;
  const bool below_high = high_open ? value < high : value <= high;
  return above_low && below_high;
}

std::string Range::toString() const {
  return (low_open ? "(" : "[") + sdf_tracker::toText(low) + ", " + sdf_tracker::toText(high) + (high_open ? ")" : "]");
}

const ParameterValue& PresetDefaults::of(Preset preset) const {
  switch (preset) {
    case Preset::kPaper: return paper;
    case Preset::kReference: return reference;
    case Preset::kDefault: break;
  }
  return default_preset;
}

ParameterValue ParameterSpec::checkValue(const ParameterValue& value) const {
  auto wrongType = [&]() {
    return std::invalid_argument(name + ": expected " + (type == ParameterType::kBool ? "true or false"
                                                         : type == ParameterType::kInt ? "a whole number"
                                                         : type == ParameterType::kDouble ? "a number"
                                                                                          : "text") +
                                 ", got \"" + sdf_tracker::toText(value) + "\"");
  };
  ParameterValue typed;
  switch (type) {
    case ParameterType::kBool:
      if (!std::holds_alternative<bool>(value)) throw wrongType();
      typed = value;
      break;
    case ParameterType::kInt:
      if (std::holds_alternative<int>(value)) {
        typed = value;
      } else if (const double* d = std::get_if<double>(&value)) {
        const std::optional<int> whole = exactInt(*d);
        if (!whole) throw wrongType();
        typed = *whole;
      } else {
        throw wrongType();
      }
      break;
    case ParameterType::kDouble:
      if (const int* i = std::get_if<int>(&value)) typed = static_cast<double>(*i);
      else if (std::holds_alternative<double>(value)) typed = value;
      else throw wrongType();
      break;
    case ParameterType::kText:
      if (!std::holds_alternative<std::string>(value)) throw wrongType();
      typed = value;
      break;
  }
  if (range) {
    const double number = std::holds_alternative<int>(typed) ? std::get<int>(typed) : std::get<double>(typed);
    if (!range->contains(number)) {
      throw std::invalid_argument(name + " must be in " + range->toString() + (unit.empty() ? "" : " " + unit) +
                                  " (got " + sdf_tracker::toText(typed) + ")");
    }
  }
  if (!choices.empty() && std::find(choices.begin(), choices.end(), std::get<std::string>(typed)) == choices.end()) {
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : " or ") + c;
    throw std::invalid_argument(name + ": expected " + list + ", got \"" + std::get<std::string>(typed) + "\"");
  }
  if (check_text) check_text(std::get<std::string>(typed));
  return typed;
}

ParameterValue ParameterSpec::parse(const std::string& text) const {
  switch (type) {
    case ParameterType::kBool: return checkValue(parseBool(name, text));
    case ParameterType::kInt: return checkValue(parseInteger(name, text));
    case ParameterType::kDouble: return checkValue(parseNumber(name, text));
    case ParameterType::kText: return checkValue(text);
  }
  throw std::logic_error("unreachable");
}

// ---------------------------------------------------------------------------------------------
// The table

namespace {

constexpr Readers kAll = Readers::kAll;
constexpr Readers kNodeOnly = Readers::kNodeOnly;
constexpr bool kLive = true;
constexpr bool kAtStart = false;
/// The dense grid's extent along x, y and z, and the first camera's place in it: read by
/// MapType=dense only.
constexpr const char* kGridSizeParameters[] = {"GridSizeX", "GridSizeY", "GridSizeZ"};
constexpr const char* kInitialCameraParameters[] = {"InitialCameraX", "InitialCameraY", "InitialCameraZ"};

/// Whether the user gave parameter `name` (`given`: names as typed).
bool isGiven(const std::vector<std::string>& given, const std::string& name) {
  return std::find(given.begin(), given.end(), name) != given.end();
}

Range closed(double low, double high) { return {low, high, false, false}; }
Range leftOpen(double low, double high) { return {low, high, true, false}; }
Range rightOpen(double low, double high) { return {low, high, false, true}; }

PresetDefaults same(const ParameterValue& value) { return {value, value, value}; }

/// A row whose value lives in one field of type T, reached through `field(settings)`.
template <typename T, typename Field>
ParameterSpec bound(std::string name, std::string unit, std::string description, std::optional<Range> range,
                    PresetDefaults defaults, bool live, Readers readers, Field field) {
  ParameterType type;
  if constexpr (std::is_same_v<T, bool>) type = ParameterType::kBool;
  else if constexpr (std::is_integral_v<T>) type = ParameterType::kInt;
  else type = ParameterType::kDouble;
  using Stored = std::conditional_t<std::is_same_v<T, bool>, bool, std::conditional_t<std::is_integral_v<T>, int, double>>;
  return ParameterSpec{std::move(name), type, std::move(unit), std::move(description), range, {}, nullptr,
                       std::move(defaults), live, readers,
                       [field](Settings& s, const ParameterValue& v) { field(s) = static_cast<T>(std::get<Stored>(v)); },
                       [field](const Settings& s) { return ParameterValue(static_cast<Stored>(field(s))); }};
}

std::vector<ParameterSpec> buildTable() {
  using S = Settings;
  std::vector<ParameterSpec> t;
  // The reference release's parameters, with their reference meaning.
  t.push_back(bound<double>("CellSize", "m", "voxel edge length", closed(0.001, 1.0), {0.02, 0.03, 0.02}, kAtStart,
                            kAll, [](auto& s) -> auto& { return s.pipeline.volume.voxel_size_m; }));
  for (int axis = 0; axis < 3; ++axis) {
    t.push_back(bound<int>(kGridSizeParameters[axis], "voxels",
                           std::string("dense grid: voxels along ") + char('x' + axis), closed(8, 2048),
                           {256, 200, 200}, kAtStart, kAll,
                           [axis](auto& s) -> auto& { return s.pipeline.volume.dims[axis]; }));
  }
  t.push_back(bound<double>("PositiveTruncationDistance", "m", "Dmax: distances are clamped to at most this",
                            leftOpen(0.0, kMaxTruncationDistance_m), {0.1, 0.1, 0.08}, kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.volume.positive_truncation_m; }));
  t.push_back(bound<double>("NegativeTruncationDistance", "m", "Dmin: voxels further behind the surface are not updated",
                            rightOpen(-kMaxTruncationDistance_m, 0.0), {-0.06, -0.06, -0.04}, kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.integrator.negative_truncation_m; }));
  t.push_back(bound<double>("RobustStatisticCoefficient", "", "Huber threshold as a fraction of Dmax",
                            leftOpen(0.0, 10.0), same(0.02), kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.tracker.huber_coefficient; }));
  t.push_back(bound<double>("Regularization", "", "Tikhonov alpha added per iteration", closed(0.0, 1e6), same(0.01),
                            kLive, kAll, [](auto& s) -> auto& { return s.pipeline.tracker.regularization; }));
  t.push_back(bound<double>("MinPoseChangeToFuseData", "m+rad", "fuse only after the camera moved this much",
                            closed(0.0, 10.0), {0.0, 0.0, 0.01}, kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.min_pose_change_to_fuse; }));
  t.push_back(bound<double>("ConvergenceCondition", "", "a level ends when |delta xi| falls below this",
                            closed(0.0, 1.0), same(1e-4), kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.tracker.convergence_threshold; }));
  t.push_back(bound<int>("MaximumRaycastSteps", "", "steps when refining a measured depth (image_denoised)",
                         closed(0, 10000), same(12), kLive, kAll,
                         [](auto& s) -> auto& { return s.pipeline.raycast.max_refinement_steps; }));
  t.push_back(bound<double>("MaxWeight", "", "Wmax, the weight cap of the running average", leftOpen(0.0, kMaxVoxelWeight),
                            same(64.0), kLive, kAll, [](auto& s) -> auto& { return s.pipeline.integrator.max_weight; }));
  t.push_back(bound<bool>("Colour", "",
                          "fuse the colour images registered to the depth into the map (a colour per voxel, 4 bytes "
                          "more), for coloured meshes and clouds; off: no colour is read or stored; tracking is the same "
                          "either way",
                          {}, {true, false, false}, kLive, kAll, [](auto& s) -> auto& { return s.pipeline.fuse_colour; }));
  t.push_back(bound<int>("ColourMaxWeight", "",
                         "the most a voxel's colour weighs (one a frame): lower follows a change of light sooner",
                         closed(1, 255), same(16), kLive, kAll,
                         [](auto& s) -> auto& { return s.pipeline.integrator.max_colour_weight; }));
  t.push_back(bound<int>("ImageWidth", "px", "image width (640, 320 or 160); scales the intrinsics", closed(1, 10000),
                         same(640), kAtStart, kNodeOnly, [](auto& s) -> auto& { return s.camera.image_width; }));
  t.push_back(bound<int>("ImageHeight", "px", "image height (480, 240 or 120)", closed(1, 10000), same(480), kAtStart,
                         kNodeOnly, [](auto& s) -> auto& { return s.camera.image_height; }));
  t.push_back(bound<double>("FocalLengthX", "px", "fx at 640x480; set: used instead of camera_info", closed(1.0, 1e5),
                            same(520.0), kAtStart, kNodeOnly, [](auto& s) -> auto& { return s.camera.vga.fx; }));
  t.push_back(bound<double>("FocalLengthY", "px", "fy at 640x480", closed(1.0, 1e5), same(520.0), kAtStart, kNodeOnly,
                            [](auto& s) -> auto& { return s.camera.vga.fy; }));
  t.push_back(bound<double>("CenterPointX", "px", "cx at 640x480", closed(0.0, 1e5), same(319.5), kAtStart, kNodeOnly,
                            [](auto& s) -> auto& { return s.camera.vga.cx; }));
  t.push_back(bound<double>("CenterPointY", "px", "cy at 640x480", closed(0.0, 1e5), same(239.5), kAtStart, kNodeOnly,
                            [](auto& s) -> auto& { return s.camera.vga.cy; }));
  // This package's own parameters.
  t.push_back(ParameterSpec{
      "TrackingSchedule", ParameterType::kText, "", "coarse-to-fine levels, stride x iterations, e.g. 4x12,2x6,1x2",
      std::nullopt, {}, [](const std::string& text) { parseSchedule(text); },
      {std::string("4x12,2x8"), std::string("4x12,2x6,1x2"), std::string("4x12,2x8,1x2")},
      kLive, kAll, [](S& s, const ParameterValue& v) { s.pipeline.tracker.levels = parseSchedule(std::get<std::string>(v)); },
      [](const S& s) { return ParameterValue(formatSchedule(s.pipeline.tracker.levels)); }});
  t.push_back(bound<double>("MinDepth", "m", "nearer depth is no measurement", closed(0.0, 100.0), same(0.4), kLive,
                            kAll, [](auto& s) -> auto& { return s.pipeline.min_depth_m; }));
  t.push_back(bound<double>("MaxDepth", "m", "further depth is no measurement", leftOpen(0.0, 100.0), same(8.0), kLive,
                            kAll, [](auto& s) -> auto& { return s.pipeline.max_depth_m; }));
  t.push_back(ParameterSpec{
      "DepthWeighting", ParameterType::kText, "",
      "fusion weights: constant (rolling average) or sensor (inverse depth-noise variance)", std::nullopt,
      {"constant", "sensor"}, nullptr, {std::string("sensor"), std::string("constant"), std::string("constant")}, kLive, kAll,
      [](S& s, const ParameterValue& v) {
        s.pipeline.integrator.weighting =
            std::get<std::string>(v) == "sensor" ? MeasurementWeighting::kSensorNoise : MeasurementWeighting::kConstant;
      },
      [](const S& s) {
        return ParameterValue(
            std::string(s.pipeline.integrator.weighting == MeasurementWeighting::kConstant ? "constant" : "sensor"));
      }});
  t.push_back(bound<bool>("TrackingSensorWeights", "", "weight tracked points by depth noise", {}, {true, false, false},
                          kLive, kAll, [](auto& s) -> auto& { return s.pipeline.tracker.sensor_weights; }));
  t.push_back(bound<bool>("NormalizeResiduals", "", "divide residuals by the field's gradient norm (metric distances)",
                          {}, {true, false, false}, kLive, kAll,
                          [](auto& s) -> auto& { return s.pipeline.tracker.normalize_by_gradient; }));
  t.push_back(ParameterSpec{
      "MapType", ParameterType::kText, "",
      "dense: one grid of GridSizeX/Y/Z voxels (fixed extent); sparse: 8^3-voxel blocks allocated where surfaces "
      "are seen (grows with the scene)",
      std::nullopt, {"dense", "sparse"}, nullptr, {std::string("sparse"), std::string("dense"), std::string("dense")},
      kAtStart, kAll,
      [](S& s, const ParameterValue& v) {
        s.pipeline.volume.type = std::get<std::string>(v) == "sparse" ? MapType::kSparse : MapType::kDense;
      },
      [](const S& s) { return ParameterValue(std::string(toString(s.pipeline.volume.type))); }});
  t.push_back(bound<double>("MaxMemoryMB", "MiB",
                            "sparse map: beyond this, blocks far from the camera (with submaps: whole closed submaps) "
                            "go to a swap file in SwapDirectory and come back when needed again; 0 no limit",
                            closed(0.0, 1e7), same(0.0), kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.max_map_memory_mb; }));
  t.push_back(ParameterSpec{
      "SwapDirectory", ParameterType::kText, "", "where MaxMemoryMB's swap file goes (empty: the system's temporary "
      "directory); the file has no name and vanishes when the process ends",
      std::nullopt, {}, nullptr, same(std::string()), kAtStart, kAll,
      [](S& s, const ParameterValue& v) { s.pipeline.swap_directory = std::get<std::string>(v); },
      [](const S& s) { return ParameterValue(s.pipeline.swap_directory); }});
  t.push_back(bound<bool>("CompactVoxels", "", "4-byte voxels (half the memory; distance and weight quantised)", {},
                          same(false), kAtStart, kAll, [](auto& s) -> auto& { return s.pipeline.volume.compact_voxels; }));
  t.push_back(bound<int>("MinValidPoints", "", "fewer tracked points than this: too_few_points", closed(6, 1e8),
                         same(200), kLive, kAll, [](auto& s) -> auto& { return s.pipeline.tracker.min_valid_points; }));
  t.push_back(bound<double>("MinInverseCondition", "", "below this the geometry is degenerate", closed(0.0, 1.0),
                            {1e-3, 1e-4, 1e-4}, kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.tracker.min_inverse_condition; }));
  t.push_back(bound<double>("MinOverlap", "",
                            "fewer of the image's points than this fraction near mapped surfaces at the estimate: "
                            "low_overlap, not fused; 0 off",
                            closed(0.0, 1.0), {0.5, 0.0, 0.0}, kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.tracker.min_overlap; }));
  t.push_back(bound<bool>("SolveConstrainedDirections", "",
                          "degenerate geometry: solve the directions it constrains, predict the rest "
                          "(off: the frame fails)",
                          {}, {true, false, false}, kLive, kAll,
                          [](auto& s) -> auto& { return s.pipeline.tracker.solve_constrained_directions; }));
  t.push_back(bound<bool>("MotionPrediction", "",
                          "start tracking from a constant-velocity prediction scaled to the time since the last frame",
                          {}, {true, false, false}, kLive, kAll,
                          [](auto& s) -> auto& { return s.pipeline.predict_motion; }));
  t.push_back(bound<double>("OdometryError", "",
                            "a robot's odometry beside the tracker (the node's ~odom_frame, offline --odometry): "
                            "the standard deviation of its motion between two frames, a fraction of the distance "
                            "and angle travelled",
                            closed(1e-4, 1.0), same(0.05), kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.odometry_error; }));
  t.push_back(bound<int>("ResetAfterFailures", "frames", "clear the map after this many failed frames in a row; 0 never",
                         closed(0, 1e6), same(0), kLive, kAll,
                         [](auto& s) -> auto& { return s.pipeline.reset_after_failures; }));
  t.push_back(bound<bool>("Relocalise", "",
                          "when tracking from the held pose fails, and in a loaded map: search the whole map for the "
                          "camera, fusing nothing until a candidate is confirmed (off: the held pose only)",
                          {}, {true, false, false}, kLive, kAll, [](auto& s) -> auto& { return s.pipeline.relocalise; }));
  t.push_back(bound<int>("RelocaliseCandidates", "", "keyframes a relocalising frame tries besides the held pose",
                         closed(0, 1000), same(3), kLive, kAll,
                         [](auto& s) -> auto& { return s.pipeline.relocaliser.candidates_per_frame; }));
  t.push_back(bound<int>("RelocaliseConfirmFrames", "frames",
                         "frames in a row a candidate must go on tracking before it is accepted", closed(1, 1000),
                         same(3), kLive, kAll, [](auto& s) -> auto& { return s.pipeline.relocaliser.confirm_frames; }));
  t.push_back(bound<double>("RelocaliseMinOverlap", "",
                            "a candidate is kept only with this fraction of the image's points on mapped surfaces "
                            "(the rest may be ground the map never saw)",
                            closed(0.0, 1.0), same(0.4), kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.relocaliser.min_overlap; }));
  t.push_back(bound<double>("RelocaliseMaxContradiction", "",
                            "a candidate is kept only with at most this fraction of the image's points where the map "
                            "saw free space, or seen through a mapped surface",
                            closed(0.0, 1.0), same(0.05), kLive, kAll,
                            [](auto& s) -> auto& { return s.pipeline.relocaliser.max_contradiction; }));
  t.push_back(bound<double>("SubmapSize", "m",
                            "sparse map: the map as submaps along the path (what loop closure moves), a new one once "
                            "the camera is this far from where the active one started; 0 one map (the default preset's "
                            "1 m holds for a sparse map)",
                            closed(0.0, 1e4), {1.0, 0.0, 0.0}, kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.submaps.max_distance_m; }));
  t.push_back(bound<double>("SubmapTurn", "deg",
                            "with SubmapSize: a new submap also once the camera has turned this much from the way "
                            "it looked when the active one started",
                            closed(0.1, 180.0), same(60.0), kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.submaps.max_rotation_deg; }));
  t.push_back(bound<int>("SubmapHandoverFrames", "frames",
                         "with SubmapSize: a new submap's first frames are tracked against the one before and fused "
                         "into both",
                         closed(1, 1000), same(10), kAtStart, kAll,
                         [](auto& s) -> auto& { return s.pipeline.submaps.handover_frames; }));
  t.push_back(bound<double>("SubmapTrackRecent", "m",
                            "with SubmapSize: frames are tracked against the active submap and the submaps the camera "
                            "left within this much path before it, read as one map; 0: against the active one alone, "
                            "after SubmapHandoverFrames against the one before",
                            closed(0.0, 1e4), same(4.0), kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.submaps.track_recent_m; }));
  t.push_back(bound<bool>("LoopClosure", "",
                          "with SubmapSize: find the view again in submaps that are not recent (the place memory, "
                          "verified and confirmed as a relocalisation is) and place every submap anew by a pose graph",
                          {}, {true, false, false}, kAtStart, kAll,
                          [](auto& s) -> auto& { return s.pipeline.loops.enabled; }));
  t.push_back(bound<double>("LoopSearchRadius", "m",
                            "with LoopClosure: keyframes of older submaps this close to the camera, where the graph "
                            "places them, are loop candidates",
                            closed(0.05, 100.0), same(2.0), kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.loops.search_radius_m; }));
  t.push_back(bound<double>("LoopMaxDrift", "m",
                            "with LoopClosure: a place found further than this from where the graph puts the camera "
                            "is refused as a loop, however well it fits (the drift since must be within it)",
                            closed(0.05, 100.0), same(2.0), kAtStart, kAll,
                            [](auto& s) -> auto& { return s.pipeline.loops.max_drift_m; }));
  t.push_back(bound<int>("LoopCheckFrames", "frames",
                         "with LoopClosure: a tracked frame is looked at for a loop every this many frames",
                         closed(1, 100000), same(15), kAtStart, kAll,
                         [](auto& s) -> auto& { return s.pipeline.loops.check_interval_frames; }));
  for (int axis = 0; axis < 3; ++axis) {
    t.push_back(bound<double>(kInitialCameraParameters[axis], "",
                              std::string("dense grid: first camera's place along ") + char('x' + axis) +
                                  " (fraction of the extent)",
                              closed(-1.0, 2.0), same(axis == 2 ? 0.0 : 0.5), kAtStart, kAll,
                              [axis](auto& s) -> auto& { return s.pipeline.initial_camera_in_grid[axis]; }));
  }
  return t;
}

}  // namespace

const std::vector<ParameterSpec>& parameterTable() {
  static const std::vector<ParameterSpec> table = buildTable();
  return table;
}

const ParameterSpec* findParameter(const std::string& name) {
  const auto& table = parameterTable();
  auto it = std::find_if(table.begin(), table.end(), [&name](const ParameterSpec& p) { return p.name == name; });
  return it == table.end() ? nullptr : &*it;
}

void setParameter(Settings* settings, const std::string& name, const ParameterValue& value) {
  const ParameterSpec* spec = findParameter(name);
  if (!spec) throw std::invalid_argument("unknown parameter \"" + name + "\"");
  spec->set(*settings, spec->checkValue(value));
}

void setParameterFromText(Settings* settings, const std::string& name, const std::string& text) {
  const ParameterSpec* spec = findParameter(name);
  if (!spec) throw std::invalid_argument("unknown parameter \"" + name + "\"");
  spec->set(*settings, spec->parse(text));
}

// ---------------------------------------------------------------------------------------------
// Settings

std::vector<std::string> Settings::validate() const {
  Violations v;
  for (const ParameterSpec& spec : parameterTable()) {
    try {
      spec.checkValue(spec.get(*this));
    } catch (const std::invalid_argument& e) {
      v.require(false, e.what());
    }
  }
  const PipelineConfig& p = pipeline;
  auto text = [](double value) { return toText(value); };
  if (!(p.max_depth_m > p.min_depth_m)) {
    v.require(false, "MaxDepth (" + text(p.max_depth_m) + " m) must be greater than MinDepth (" + text(p.min_depth_m) +
                         " m)");
  }
  if (p.volume.positive_truncation_m < p.volume.voxel_size_m || -p.integrator.negative_truncation_m < p.volume.voxel_size_m) {
    v.require(false, "the truncation band (NegativeTruncationDistance " + text(p.integrator.negative_truncation_m) +
                         " m, PositiveTruncationDistance " + text(p.volume.positive_truncation_m) +
                         " m) must reach at least one CellSize (" + text(p.volume.voxel_size_m) +
                         " m) on each side of the surface");
  }
  if (p.volume.compact_voxels && p.volume.type == MapType::kSparse) {
    v.require(false, "CompactVoxels=true applies to MapType=dense only (MapType is sparse)");
  }
  if (p.max_map_memory_mb > 0.0 && p.volume.type == MapType::kDense) {
    v.require(false, "MaxMemoryMB=" + text(p.max_map_memory_mb) +
                         " applies to MapType=sparse only (the dense grid's memory is fixed by GridSizeX/Y/Z)");
  }
  if (p.submaps.enabled() && p.volume.type == MapType::kDense) {
    v.require(false, "SubmapSize=" + text(p.submaps.max_distance_m) + " applies to MapType=sparse only");
  }
  if (p.loops.enabled && !p.submaps.enabled()) {
    // Named by what keeps to one map: a dense grid holds no submaps at all.
    if (p.volume.type == MapType::kDense) {
      v.require(false, "LoopClosure=true applies to MapType=sparse only: loops move submaps, which a dense grid "
                       "cannot hold (set LoopClosure=false, or MapType=sparse)");
    } else {
      v.require(false, "LoopClosure=true needs SubmapSize > 0: loops move submaps (got SubmapSize=" +
                           text(p.submaps.max_distance_m) + ")");
    }
  }
  if (p.volume.compact_voxels && p.integrator.max_weight > VoxelCodec<CompactVoxel>::kMaxWeight) {
    v.require(false, "MaxWeight must be at most " + text(VoxelCodec<CompactVoxel>::kMaxWeight) +
                         " with CompactVoxels=true (got " + text(p.integrator.max_weight) + ")");
  }
  try {
    camera.camera();
  } catch (const std::invalid_argument& e) {
    v.require(false, std::string("ImageWidth/ImageHeight: ") + e.what());
  }
  // The components' own checks name struct fields; with the table's rules above they only speak
  // for fields the table does not hold (set in code, not by a user).
  if (v.list().empty()) v.merge("", pipeline.validate());
  return v.list();
}

std::optional<std::string> Settings::keepToOneMapWhereNeeded(const std::vector<std::string>& given,
                                                             bool loads_dense_map) {
  if (!pipeline.submaps.enabled()) {
    // One map typed (SubmapSize=0): loop closure, which moves submaps, goes too unless typed.
    if (!pipeline.loops.enabled || isGiven(given, "LoopClosure")) return std::nullopt;
    pipeline.loops.enabled = false;
    return "no loop closure (LoopClosure=false): SubmapSize=0 keeps one map, and loops move submaps";
  }
  if (isGiven(given, "SubmapSize")) return std::nullopt;
  std::string why;
  if (!pipeline.loops.enabled && isGiven(given, "LoopClosure")) why = "LoopClosure=false, and submaps serve loop closure";
  else if (pipeline.volume.type == MapType::kDense) why = "MapType=dense holds no submaps";
  else if (loads_dense_map) why = "the map loaded is a dense grid (.vti), which holds no submaps";
  if (why.empty()) return std::nullopt;
  std::string note = "one map, no submaps (SubmapSize=0): " + why;
  pipeline.submaps.max_distance_m = 0.0;
  if (pipeline.loops.enabled && !isGiven(given, "LoopClosure")) {
    pipeline.loops.enabled = false;
    note += ", and no loop closure (LoopClosure=false), which moves submaps";
  }
  return note;
}

std::vector<std::string> Settings::withoutEffect(const std::vector<std::string>& given) const {
  std::vector<std::string> notes;
  if (pipeline.volume.type == MapType::kSparse) {
    std::string grid;
    int count = 0;
    for (const auto& names : {kGridSizeParameters, kInitialCameraParameters}) {
      for (int axis = 0; axis < 3; ++axis) {
        if (!isGiven(given, names[axis])) continue;
        grid += (count++ ? ", " : "") + std::string(names[axis]) + "=" + toText(findParameter(names[axis])->get(*this));
      }
    }
    if (count > 0) {
      notes.push_back(grid + (count > 1 ? " have" : " has") + " no effect with MapType=sparse, whose blocks grow "
                      "with the scene wherever the camera goes; set MapType=dense for one grid sized and placed "
                      "by them");
    }
  }
  if (isGiven(given, "SwapDirectory") && !(pipeline.max_map_memory_mb > 0.0)) {
    notes.push_back("SwapDirectory=" + pipeline.swap_directory + " has no effect without MaxMemoryMB, the bound "
                    "beyond which blocks go to a swap file there; set MaxMemoryMB too");
  }
  if (!pipeline.submaps.enabled()) {
    for (const char* name : {"SubmapTurn", "SubmapHandoverFrames", "SubmapTrackRecent"}) {
      if (!isGiven(given, name)) continue;
      notes.push_back(std::string(name) + "=" + toText(findParameter(name)->get(*this)) +
                      " has no effect without SubmapSize, the distance at which a new submap starts; set "
                      "SubmapSize too");
    }
  }
  if (!pipeline.loops.enabled) {
    for (const char* name : {"LoopSearchRadius", "LoopMaxDrift", "LoopCheckFrames"}) {
      if (!isGiven(given, name)) continue;
      notes.push_back(std::string(name) + "=" + toText(findParameter(name)->get(*this)) +
                      " has no effect without LoopClosure=true; set it too");
    }
  }
  return notes;
}

// ---------------------------------------------------------------------------------------------
// Schedules and presets

std::vector<PyramidLevel> parseSchedule(const std::string& text) {
  std::vector<PyramidLevel> levels;
  std::istringstream in(text);
  std::string item;
  const std::string rule = "TrackingSchedule: expected levels of stride x iterations (stride 1 to 64, iterations 1 to "
                           "1000) like 4x12,2x6,1x2, got \"" + text + "\"";
  while (std::getline(in, item, ',')) {
    const size_t x = item.find('x');
    if (x == std::string::npos) throw std::invalid_argument(rule);
    try {
      const PyramidLevel level{parseInteger("stride", item.substr(0, x)), parseInteger("iterations", item.substr(x + 1))};
      if (level.stride < 1 || level.stride > 64 || level.max_iterations < 1 || level.max_iterations > 1000) {
        throw std::invalid_argument("");
      }
      levels.push_back(level);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument(rule);
    }
  }
  if (levels.empty()) throw std::invalid_argument(rule);
  return levels;
}

std::string formatSchedule(const std::vector<PyramidLevel>& levels) {
  std::ostringstream out;
  for (size_t i = 0; i < levels.size(); ++i) out << (i ? "," : "") << levels[i].stride << 'x' << levels[i].max_iterations;
  return out.str();
}

std::vector<std::string> presetNames() { return {"default", "paper", "reference"}; }

Settings preset(const std::string& name) {
  Preset which;
  if (name == "default") which = Preset::kDefault;
  else if (name == "paper") which = Preset::kPaper;
  else if (name == "reference") which = Preset::kReference;
  else throw std::invalid_argument("unknown preset \"" + name + "\" (known: default, paper, reference)");
  Settings settings;
  for (const ParameterSpec& spec : parameterTable()) spec.set(settings, spec.checkValue(spec.defaults.of(which)));
  return settings;
}

}  // namespace sdf_tracker
