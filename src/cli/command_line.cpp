#include "sdf_tracker/cli/command_line.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/pipeline/parameters.h"

namespace sdf_tracker::tools {

CommandLine::CommandLine(int argc, char** argv, const std::vector<std::string>& options_with_value,
                         const std::vector<std::string>& flags, const std::vector<std::string>& positional_names)
    : positional_names_(positional_names) {
  auto contains = [](const std::vector<std::string>& list, const std::string& s) {
    return std::find(list.begin(), list.end(), s) != list.end();
  };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      if (positional_.size() >= positional_names_.size()) throw std::invalid_argument("unexpected argument \"" + arg + "\"");
      positional_.push_back(arg);
      continue;
    }
    const std::string name = arg.substr(2);
    if (contains(flags, name)) {
      values_[name].push_back("true");
    } else if (contains(options_with_value, name)) {
      if (i + 1 >= argc) throw std::invalid_argument("option --" + name + " needs a value");
      values_[name].push_back(argv[++i]);
    } else {
      throw std::invalid_argument("unknown option \"" + arg + "\" (see --help)");
    }
  }
}

const std::string& CommandLine::positional(size_t i) const {
  if (i >= positional_.size()) {
    throw std::invalid_argument("missing " + (i < positional_names_.size() ? positional_names_[i] : "argument") + " (see --help)");
  }
  return positional_[i];
}

std::string CommandLine::get(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  if (it == values_.end()) return fallback;
  if (it->second.size() > 1 && it->second.front() != it->second.back()) {
    throw std::invalid_argument("--" + name + " is given twice (\"" + it->second.front() + "\" and \"" +
                                it->second.back() + "\"): give it once");
  }
  return it->second.back();
}

std::vector<std::string> CommandLine::getAll(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

std::string CommandLine::require(const std::string& name) const {
  if (!has(name)) throw std::invalid_argument("missing required option --" + name);
  return get(name);
}

double CommandLine::getDouble(const std::string& name, double fallback) const {
  if (!has(name)) return fallback;
  std::istringstream in(get(name));
  double value;
  std::string rest;
  if (!(in >> value) || (in >> rest) || !std::isfinite(value)) {
    throw std::invalid_argument("--" + name + ": expected a number, got \"" + get(name) + "\"");
  }
  return value;
}

int CommandLine::getInt(const std::string& name, int fallback) const {
  return wholeNumber(getDouble(name, fallback), "--" + name, get(name));
}

int wholeNumber(double value, const std::string& what, const std::string& text) {
  // Written so that NaN fails the comparisons.
  if (!(value == std::floor(value) && value >= std::numeric_limits<int>::min() &&
        value <= std::numeric_limits<int>::max())) {
    throw std::invalid_argument(what + ": expected a whole number, got \"" + text + "\"");
  }
  return static_cast<int>(value);
}

int runTool(const char* tool, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  }
}

TumSequence openSequence(const CommandLine& args) {
  TumSequence sequence = TumSequence::open(args.positional(0));
  if (args.has("frames")) {
    const int frames = parseInteger("--frames", args.get("frames"));
    if (frames < 1) throw std::invalid_argument("--frames must be at least 1 (got " + args.get("frames") + ")");
    sequence.truncate(static_cast<size_t>(frames));
  }
  if (sequence.size() == 0) throw std::runtime_error(args.positional(0) + "/depth.txt lists no frame");
  if (!sequence.distortionHint().empty()) std::cerr << "note: " << sequence.distortionHint() << "\n";
  return sequence;
}

}  // namespace sdf_tracker::tools
