#pragma once

#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/pipeline/pipeline.h"

namespace sdf_tracker {

/// The reference release's camera parameters: intrinsics given for 640x480 and scaled to
/// ImageWidth x ImageHeight. The node reads them (when set) instead of camera_info.
struct CameraSettings {
  PinholeCamera vga;  ///< FocalLengthX/Y, CenterPointX/Y at 640x480
  int image_width = 640;
  int image_height = 480;

  /// `vga` at image_width x image_height; throws std::invalid_argument for a size that is not
  /// VGA, QVGA or QQVGA-like.
  PinholeCamera camera() const { return vga.scaledTo(image_width, image_height); }
};

/// All user-facing settings: the pipeline's configuration and the camera parameters.
struct Settings {
  PipelineConfig pipeline;
  CameraSettings camera;
  /// Every violation, in the user's words: parameter names as typed ("CellSize must be in
  /// (0, 1] m (got -0.1)"), ranges of every table row and the rules that tie parameters together.
  std::vector<std::string> validate() const;
  /// The parameters in `given` (names as the user typed them) that these settings leave without
  /// effect, one sentence each: GridSizeX/Y/Z when MapType is sparse. They are accepted, since
  /// the reference release's launch files set them, but the user must be told. Empty when every
  /// given parameter takes effect.
  std::vector<std::string> withoutEffect(const std::vector<std::string>& given) const;
  /// The default preset's submaps (SubmapSize 1 m) and loop closure hold for a sparse map (under
  /// MaxMemoryMB too: whole submaps are swapped). Where the user did not type SubmapSize (`given`:
  /// names as typed) and typed LoopClosure=false (submaps serve loop closure), or the map cannot
  /// hold submaps (MapType=dense, or `loads_dense_map`: the map to be loaded is a dense grid), it
  /// sets one map, and loop closure off unless typed, and says so in a sentence to show the user
  /// once; where one map was asked for (SubmapSize=0) and LoopClosure not typed, loop closure off,
  /// said alike. A SubmapSize or LoopClosure the user typed is left for validate() to refuse with
  /// the other parameter's name.
  std::optional<std::string> keepToOneMapWhereNeeded(const std::vector<std::string>& given, bool loads_dense_map);
};

/// A parameter's value as it travels between the command line, the ROS parameter server,
/// dynamic_reconfigure and the table: typed, so nothing is rounded through text.
using ParameterValue = std::variant<bool, int, double, std::string>;

enum class ParameterType { kBool, kInt, kDouble, kText };
const char* toString(ParameterType type);

/// Which programs read a parameter. The offline runner refuses the node-only ones (it takes its
/// intrinsics from the sequence), so nothing is accepted and then ignored.
enum class Readers { kAll, kNodeOnly };

/// The presets, in the order of PresetDefaults' members.
enum class Preset { kDefault, kPaper, kReference };

/// A numeric interval; each end may be open (excluded) or closed.
struct Range {
  double low;
  double high;
  bool low_open = false;
  bool high_open = false;

  bool contains(double value) const;
  std::string toString() const;  ///< "(0, 1]"
};

/// A parameter's starting value in each preset.
struct PresetDefaults {
  ParameterValue default_preset;  ///< this package's tuned defaults
  ParameterValue paper;           ///< the paper's Table II
  ParameterValue reference;       ///< the reference release's launch file
  const ParameterValue& of(Preset preset) const;
};

/// One row of the parameter table: the single record of a setting. Names are the reference
/// release's (CamelCase) so its launch files keep working; parameters of our own follow the same
/// style.
struct ParameterSpec {
  std::string name;
  ParameterType type;
  std::string unit;  ///< "m", "px", "" for none
  std::string description;
  std::optional<Range> range;        ///< numbers: the accepted values
  std::vector<std::string> choices;  ///< text with a fixed set of values (empty: free text)
  /// Free text's own rule: throws std::invalid_argument saying what is expected (may be empty).
  std::function<void(const std::string&)> check_text;
  PresetDefaults defaults;
  bool live;  ///< may change while running (dynamic reconfigure)
  Readers readers;
  /// Stores a value of this row's type in the field (after checkValue).
  std::function<void(Settings&, const ParameterValue&)> set;
  std::function<ParameterValue(const Settings&)> get;

  /// Converts a value to this row's type (an int for a double, a whole double for an int) and
  /// checks type, range and choices. Throws std::invalid_argument naming the parameter and value.
  ParameterValue checkValue(const ParameterValue& value) const;
  /// Text ("0.02", "true", "4x12,2x6,1x2") to a checked value; throws like checkValue.
  ParameterValue parse(const std::string& text) const;
};

/// The one table that maps parameter names to fields.
const std::vector<ParameterSpec>& parameterTable();
/// nullptr when unknown.
const ParameterSpec* findParameter(const std::string& name);

/// Sets one parameter. Throws std::invalid_argument naming the parameter and the value when the
/// name is unknown, the value has the wrong type or lies outside the row's range: nothing is
/// clamped. Rules between parameters are checked by Settings::validate().
void setParameter(Settings* settings, const std::string& name, const ParameterValue& value);
/// The same from text, as typed on a command line.
void setParameterFromText(Settings* settings, const std::string& name, const std::string& text);

/// Full-precision text of a value ("0.1", "true", "4x12,2x6,1x2").
std::string toText(const ParameterValue& value);

/// A preset's settings: every table row at its preset default. Throws std::invalid_argument for
/// an unknown name. Names: "default", "paper", "reference".
Settings preset(const std::string& name);
std::vector<std::string> presetNames();

/// Text -> value; throw std::invalid_argument naming `name` and the text.
double parseNumber(const std::string& name, const std::string& text);
/// Whole numbers within int's range only (no silent conversion of 1e10 or 2.5).
int parseInteger(const std::string& name, const std::string& text);
bool parseBool(const std::string& name, const std::string& text);  ///< true/false (or 1/0)

/// "4x12,2x6,1x2" <-> levels (stride x iterations, coarse to fine).
std::vector<PyramidLevel> parseSchedule(const std::string& text);
std::string formatSchedule(const std::vector<PyramidLevel>& levels);

}  // namespace sdf_tracker
