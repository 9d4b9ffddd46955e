#pragma once

#include <map>
#include <string>
#include <vector>

#include "sdf_tracker/io/tum_sequence.h"

namespace sdf_tracker::tools {

/// A small "--name value" parser for the command-line tools. Options listed as flags take no
/// value; every other option takes exactly one; repeated options keep every value in order.
/// Arguments without "--" fill the named positional arguments in order.
class CommandLine {
 public:
  /// Throws std::invalid_argument for an unknown option, a missing value or a surplus argument.
  CommandLine(int argc, char** argv, const std::vector<std::string>& options_with_value,
              const std::vector<std::string>& flags, const std::vector<std::string>& positional_names = {});

  bool has(const std::string& name) const { return values_.count(name) > 0; }
  /// The option's value; throws std::invalid_argument when it was given twice with different
  /// values (only getAll() options repeat).
  std::string get(const std::string& name, const std::string& fallback = "") const;
  std::vector<std::string> getAll(const std::string& name) const;
  /// Throws std::invalid_argument naming the option when missing.
  std::string require(const std::string& name) const;
  int getInt(const std::string& name, int fallback) const;
  double getDouble(const std::string& name, double fallback) const;
  /// The i-th positional argument; throws std::invalid_argument naming it when it was not given.
  const std::string& positional(size_t i) const;

 private:
  std::map<std::string, std::vector<std::string>> values_;
  std::vector<std::string> positional_names_, positional_;
};

/// `value` as an int when it is a whole number an int can hold; otherwise throws
/// std::invalid_argument("<what>: expected a whole number, got <text>"), never an undefined cast.
int wholeNumber(double value, const std::string& what, const std::string& text);

/// The converters' input: the TUM-layout folder given as the first positional argument, cut to
/// its first --frames N when that option is given; its distortion hint, if any, on stderr.
/// Throws when the folder lists no frame.
TumSequence openSequence(const CommandLine& args);

/// A tool's main(): runs `run` and turns any exception into "<tool>: error: <what>" on stderr and
/// exit code 1.
int runTool(const char* tool, int (*run)(int, char**), int argc, char** argv);

}  // namespace sdf_tracker::tools
