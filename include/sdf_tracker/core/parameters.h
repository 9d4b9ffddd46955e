#pragma once

#include <functional>
#include <string>
#include <vector>

#include "sdf_tracker/core/camera.h"
#include "sdf_tracker/core/pipeline.h"

namespace sdf_tracker {

/// All user-facing settings: the pipeline plus the reference release's camera parameters
/// (intrinsics given for 640x480 and scaled to ImageWidth x ImageHeight).
struct Settings {
  PipelineConfig pipeline;
  PinholeCamera camera_vga;  ///< FocalLengthX/Y, CenterPointX/Y at 640x480
  int image_width = 640;
  int image_height = 480;

  /// camera_vga at image_width x image_height; throws std::invalid_argument for a size that is not
  /// VGA, QVGA or QQVGA-like.
  PinholeCamera camera() const { return camera_vga.scaledTo(image_width, image_height); }
  std::vector<std::string> validate() const;
};

/// One named parameter. Names are the reference release's (CamelCase) so its launch files keep
/// working; parameters of our own follow the same style.
struct ParameterSpec {
  std::string name;
  std::string description;
  bool live;  ///< may change while running (dynamic reconfigure)
  std::function<void(Settings&, const std::string&)> set;
  std::function<std::string(const Settings&)> get;
};

/// The one table that maps parameter names to fields.
const std::vector<ParameterSpec>& parameterTable();
/// nullptr when unknown.
const ParameterSpec* findParameter(const std::string& name);

/// Sets one parameter from text ("0.02", "4x12,2x6,1x2", "true"). Throws std::invalid_argument
/// naming the parameter and the value when the name is unknown or the text does not parse;
/// range checks happen in Settings::validate().
void setParameter(Settings* settings, const std::string& name, const std::string& value);

/// Presets: "paper" (Table II), "reference" (the reference release's launch file) and "default"
/// (this package's tuned defaults). Throws std::invalid_argument for another name.
Settings preset(const std::string& name);
std::vector<std::string> presetNames();

/// Text -> value for parameters; throw std::invalid_argument naming `name` and the text.
double parseNumber(const std::string& name, const std::string& text);
int parseInteger(const std::string& name, const std::string& text);
bool parseBool(const std::string& name, const std::string& text);  ///< true/false (or 1/0)

/// "4x12,2x6,1x2" <-> levels (stride x iterations, coarse to fine).
std::vector<PyramidLevel> parseSchedule(const std::string& text);
std::string formatSchedule(const std::vector<PyramidLevel>& levels);

}  // namespace sdf_tracker
