#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdf_tracker/camera/depth_image.h"

namespace sdf_tracker {

/// How a view is summarised for recognising the place later: the depth image averaged down to a
/// small grid of cells (whatever the camera's resolution), then randomised ferns on it (Glocker et
/// al., "Real-time RGB-D camera relocalization", 2013): each fern asks `tests_per_fern` questions
/// "is this cell nearer than this depth?" and keeps the answers as the bits of one byte. Views
/// from nearby poses answer most ferns alike. The tests follow from `seed` alone (a generator of
/// our own, not the standard library's), so a saved place memory can be read by any build.
struct PlaceDescriptorConfig {
  int grid_width = 40;
  int grid_height = 30;
  int fern_count = 500;
  int tests_per_fern = 4;  ///< bits per fern's code, at most 8
  uint64_t seed = 1;
  /// The depths the tests compare against are drawn from this range [m].
  double min_test_depth_m = 0.5;
  double max_test_depth_m = 4.0;

  std::vector<std::string> validate() const;
  bool operator==(const PlaceDescriptorConfig& other) const;
  bool operator!=(const PlaceDescriptorConfig& other) const { return !(*this == other); }
};

/// One code per fern.
using PlaceCode = std::vector<uint8_t>;

/// Encodes views as PlaceCodes. Immutable after construction; thread safe.
class PlaceEncoder {
 public:
  /// Throws std::invalid_argument naming every violation of the config.
  explicit PlaceEncoder(const PlaceDescriptorConfig& config);

  const PlaceDescriptorConfig& config() const { return config_; }

  /// The mean measured depth of each grid cell (row-major, grid_width x grid_height), 0 where
  /// fewer than a quarter of the cell's pixels hold a measurement. Depth as the tracker takes it:
  /// metres, 0 or NaN for no measurement.
  std::vector<float> cellDepths(const DepthImage& depth) const;
  PlaceCode encode(const DepthImage& depth) const;
  /// The fraction of ferns whose codes differ: 0 for the same view, near 1 for unrelated ones.
  /// Both codes must come from encoders of the same config.
  static double dissimilarity(const PlaceCode& a, const PlaceCode& b);

 private:
  struct Test {
    int cell;
    float depth_m;
  };
  PlaceDescriptorConfig config_;
  std::vector<Test> tests_;  ///< fern f's tests are [f * tests_per_fern, (f + 1) * tests_per_fern)
};

}  // namespace sdf_tracker
