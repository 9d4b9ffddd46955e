#include "sdf_tracker/map/tsdf_map.h"

#include <atomic>
#include <cmath>
#include <sstream>
#include <utility>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

const char* toString(MapType type) {
  switch (type) {
    case MapType::kDense: return "dense";
    case MapType::kSparse: return "sparse";
  }
  return "unknown";
}

std::string voxelProblem(const Voxel& voxel, double positive_truncation_m) {
  // The truncation is stored in double and clamped to in float (compact voxels round to its
  // 1/32767th): allow for the rounding. Called for every voxel a file holds: words only on failure.
  const double highest_m = positive_truncation_m * (1.0 + 1e-4);
  const bool distance_ok = voxel.distance_m >= -kMaxTruncationDistance_m && voxel.distance_m <= highest_m;
  const bool weight_ok = voxel.weight >= 0.0f && voxel.weight <= kMaxVoxelWeight;
  if (distance_ok && weight_ok) return "";
  std::ostringstream s;
  if (!distance_ok) {
    s << "distance " << voxel.distance_m << " m is not within [" << -kMaxTruncationDistance_m << ", "
      << positive_truncation_m << "] m";
  } else {
    s << "weight " << voxel.weight << " is not within [0, " << kMaxVoxelWeight << "]";
  }
  return s.str();
}

std::vector<std::string> VolumeConfig::validate() const {
  Violations v;
  v.requirePositive("voxel_size_m", voxel_size_m);
  // Positions are 32-bit floats: 2^23 voxels out, one float step is a voxel.
  const double reach_m = (voxel_size_m > 0.0 && std::isfinite(voxel_size_m) ? voxel_size_m : 0.0) * (1 << 23);
  const char* axes[3] = {"origin_W.x", "origin_W.y", "origin_W.z"};
  for (int axis = 0; axis < 3; ++axis) {
    std::ostringstream rule;
    rule << axes[axis] << " must lie within " << reach_m << " m of the world's origin (2^23 voxels: farther out, 32-bit "
         << "positions no longer tell neighbouring voxels apart) (got " << origin_W[axis] << ")";
    v.require(std::fabs(origin_W[axis]) <= reach_m, rule.str());
  }
  v.requirePositive("positive_truncation_m", positive_truncation_m);
  if (type == MapType::kSparse) {
    v.require(!compact_voxels, "compact_voxels applies to the dense grid only");
    return v.list();
  }
  v.requireInRange("dims.x", dims.x(), 2, 4096);
  v.requireInRange("dims.y", dims.y(), 2, 4096);
  v.requireInRange("dims.z", dims.z(), 2, 4096);
  return v.list();
}

std::string VolumeConfig::describe() const {
  std::ostringstream s;
  if (type == MapType::kSparse) {
    s << "sparse map of " << voxel_size_m << " m voxels in blocks of " << kBlockSide << "^3";
  } else {
    s << "dense grid " << dims.x() << "x" << dims.y() << "x" << dims.z() << " of " << voxel_size_m << " m";
  }
  return s.str();
}

TsdfMap::TsdfMap(VolumeConfig config, MapType type) : config_(std::move(config)) {
  static std::atomic<uint64_t> next_identity{1};
  identity_ = next_identity++;
  config_.type = type;
  throwIfInvalid("volume config", config_.validate());
  voxel_size_ = static_cast<float>(config_.voxel_size_m);
  inv_voxel_size_ = 1.0f / voxel_size_;
  positive_truncation_ = static_cast<float>(config_.positive_truncation_m);
  origin_ = config_.origin_W.cast<float>();
}

namespace {

/// Samples through the map's own sample(): for storage with nothing to prepare.
class DirectSampler final : public FieldSampler {
 public:
  explicit DirectSampler(const TsdfMap& map) : map_(map) {}
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override { return map_.sample(p_W, out); }

 private:
  const TsdfMap& map_;
};

}  // namespace

std::unique_ptr<FieldSampler> TsdfMap::sampler(const Eigen::AlignedBox3f& /*region_W*/) const {
  return std::make_unique<DirectSampler>(*this);
}

std::unique_ptr<TsdfMap> makeMap(const VolumeConfig& config) {
  if (config.type == MapType::kSparse) return std::make_unique<SparseTsdfMap>(config);
  return std::make_unique<TsdfVolume>(config);
}

}  // namespace sdf_tracker
