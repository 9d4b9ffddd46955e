#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sdf_tracker {

/// Collects every violated constraint of a configuration as a sentence naming the field and the
/// value ("voxel_size_m must be > 0 (got -0.1)"), so one call reports all of them.
class Violations {
 public:
  template <typename T>
  void requirePositive(const std::string& name, T value) {
    if (!(std::isfinite(static_cast<double>(value)) && value > 0)) add(name, "must be > 0", value);
  }
  template <typename T>
  void requireNonNegative(const std::string& name, T value) {
    if (!(std::isfinite(static_cast<double>(value)) && value >= 0)) add(name, "must be >= 0", value);
  }
  template <typename T>
  void requireNegative(const std::string& name, T value) {
    if (!(std::isfinite(static_cast<double>(value)) && value < 0)) add(name, "must be < 0", value);
  }
  template <typename T>
  void requireFinite(const std::string& name, T value) {
    if (!std::isfinite(static_cast<double>(value))) add(name, "must be finite", value);
  }
  template <typename T>
  void requireInRange(const std::string& name, T value, T low, T high) {
    if (!(std::isfinite(static_cast<double>(value)) && value >= low && value <= high)) {
      std::ostringstream rule;
      rule << "must be in [" << low << ", " << high << "]";
      add(name, rule.str(), value);
    }
  }
  void require(bool ok, const std::string& sentence) {
    if (!ok) list_.push_back(sentence);
  }
  /// Prefixes and appends another component's violations ("tracker." + ...).
  void merge(const std::string& prefix, const std::vector<std::string>& other) {
    for (const auto& s : other) list_.push_back(prefix + s);
  }

  const std::vector<std::string>& list() const { return list_; }

 private:
  template <typename T>
  void add(const std::string& name, const std::string& rule, T value) {
    std::ostringstream s;
    s << name << " " << rule << " (got " << value << ")";
    list_.push_back(s.str());
  }
  std::vector<std::string> list_;
};

/// Joins violations into one message and throws std::invalid_argument when there are any.
inline void throwIfInvalid(const std::string& what, const std::vector<std::string>& violations) {
  if (violations.empty()) return;
  std::string msg = "invalid " + what + ":";
  for (const auto& v : violations) msg += "\n  - " + v;
  throw std::invalid_argument(msg);
}

}  // namespace sdf_tracker
