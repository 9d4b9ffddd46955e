#include "sdf_tracker/places/place_descriptor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

/// SplitMix64 (Steele, Lea & Flood 2014): a fixed sequence for a seed on every platform.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1), from the top 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  uint64_t state_;
};

}  // namespace

std::vector<std::string> PlaceDescriptorConfig::validate() const {
  Violations v;
  v.requireInRange("grid_width", grid_width, 2, 640);
  v.requireInRange("grid_height", grid_height, 2, 480);
  v.requireInRange("fern_count", fern_count, 1, 100000);
  v.requireInRange("tests_per_fern", tests_per_fern, 1, 8);
  v.requirePositive("min_test_depth_m", min_test_depth_m);
  v.require(max_test_depth_m > min_test_depth_m && std::isfinite(max_test_depth_m),
            "max_test_depth_m must be finite and > min_test_depth_m (got " + std::to_string(max_test_depth_m) +
                " <= " + std::to_string(min_test_depth_m) + ")");
  return v.list();
}

bool PlaceDescriptorConfig::operator==(const PlaceDescriptorConfig& o) const {
  return grid_width == o.grid_width && grid_height == o.grid_height && fern_count == o.fern_count &&
         tests_per_fern == o.tests_per_fern && seed == o.seed && min_test_depth_m == o.min_test_depth_m &&
         max_test_depth_m == o.max_test_depth_m;
}

PlaceEncoder::PlaceEncoder(const PlaceDescriptorConfig& config) : config_(config) {
  throwIfInvalid("place descriptor config", config.validate());
  SplitMix64 random(config.seed);
  const int cells = config.grid_width * config.grid_height;
  tests_.reserve(static_cast<size_t>(config.fern_count) * config.tests_per_fern);
  for (int t = 0; t < config.fern_count * config.tests_per_fern; ++t) {
    const int cell = std::min(cells - 1, static_cast<int>(random.uniform() * cells));
    const double depth = config.min_test_depth_m + random.uniform() * (config.max_test_depth_m - config.min_test_depth_m);
    tests_.push_back({cell, static_cast<float>(depth)});
  }
}

std::vector<float> PlaceEncoder::cellDepths(const DepthImage& depth) const {
  const int gw = config_.grid_width, gh = config_.grid_height;
  std::vector<float> sum(static_cast<size_t>(gw) * gh, 0.0f);
  std::vector<int> measured(sum.size(), 0), seen(sum.size(), 0);
  // Every second pixel each way is plenty for a cell's mean and a quarter of the reads.
  for (int v = 0; v < depth.height(); v += 2) {
    const int row = std::min(gh - 1, v * gh / depth.height());
    for (int u = 0; u < depth.width(); u += 2) {
      const size_t cell = static_cast<size_t>(row) * gw + std::min(gw - 1, u * gw / depth.width());
      const float z = depth.at(u, v);
      ++seen[cell];
      if (DepthImage::isMeasurement(z)) {
        sum[cell] += z;
        ++measured[cell];
      }
    }
  }
  for (size_t c = 0; c < sum.size(); ++c) {
    sum[c] = measured[c] > 0 && 4 * measured[c] >= seen[c] ? sum[c] / static_cast<float>(measured[c]) : 0.0f;
  }
  return sum;
}

PlaceCode PlaceEncoder::encode(const DepthImage& depth) const {
  const std::vector<float> cells = cellDepths(depth);
  PlaceCode code(static_cast<size_t>(config_.fern_count), 0);
  for (int f = 0; f < config_.fern_count; ++f) {
    uint8_t bits = 0;
    for (int b = 0; b < config_.tests_per_fern; ++b) {
      const Test& test = tests_[static_cast<size_t>(f) * config_.tests_per_fern + b];
      const float z = cells[static_cast<size_t>(test.cell)];
      // A cell without a measurement answers "not nearer": no data is far, as the sensor sees it.
      if (z > 0.0f && z < test.depth_m) bits |= static_cast<uint8_t>(1u << b);
    }
    code[static_cast<size_t>(f)] = bits;
  }
  return code;
}

double PlaceEncoder::dissimilarity(const PlaceCode& a, const PlaceCode& b) {
  if (a.size() != b.size() || a.empty()) {
    throw std::invalid_argument("place codes of " + std::to_string(a.size()) + " and " + std::to_string(b.size()) +
                                " ferns cannot be compared");
  }
  size_t differ = 0;
  for (size_t f = 0; f < a.size(); ++f) differ += a[f] != b[f];
  return static_cast<double>(differ) / static_cast<double>(a.size());
}

}  // namespace sdf_tracker
