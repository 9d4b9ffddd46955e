#include "sdf_tracker/map/tsdf_volume.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/util/memory.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

TsdfVolume::TsdfVolume(const VolumeConfig& config) : TsdfMap(config, MapType::kDense) {
  stride_y_ = static_cast<size_t>(config.dims.x());
  stride_z_ = stride_y_ * config.dims.y();
  voxel_count_ = stride_z_ * config.dims.z();
  std::ostringstream grid;
  grid << "a dense grid of " << config.dims.x() << "x" << config.dims.y() << "x" << config.dims.z() << " voxels";
  requireMemory(voxel_count_ * (compact() ? sizeof(CompactVoxel) : sizeof(Voxel)), grid.str());
  clear();
}

bool TsdfVolume::observesNothing() const {
  return withStorage([this](const auto* voxels, const auto& codec) {
    return std::none_of(voxels, voxels + voxel_count_, [&codec](const auto& v) { return codec.decode(v).weight > 0.0f; });
  });
}

void TsdfVolume::enableColour() {
  if (!colours_.empty()) return;
  std::ostringstream what;
  what << "the colours of a dense grid of " << config_.dims.x() << "x" << config_.dims.y() << "x" << config_.dims.z()
       << " voxels";
  requireMemory(voxel_count_ * sizeof(VoxelColour), what.str());
  colours_.assign(voxel_count_, VoxelColour{});
}

void TsdfVolume::clear() {
  std::vector<VoxelColour>().swap(colours_);
  const Voxel unseen{positive_truncation_, 0.0f};
  if (compact()) {
    std::vector<Voxel>().swap(voxels_);
    compact_.assign(voxel_count_, VoxelCodec<CompactVoxel>(positive_truncation_).encode(unseen));
  } else {
    std::vector<CompactVoxel>().swap(compact_);
    voxels_.assign(voxel_count_, unseen);
  }
}

void TsdfVolume::copySlabsFrom(const TsdfVolume& source, int k_begin, int k_end) {
  if (!config_.sameGrid(source.config_)) {
    throw std::invalid_argument("copySlabsFrom: the volumes differ in geometry or storage");
  }
  k_begin = std::max(0, k_begin);
  k_end = std::min(config_.dims.z(), k_end);
  if (k_begin >= k_end) return;
  const size_t first = index(0, 0, k_begin), last = index(0, 0, k_end);
  if (compact()) std::copy(source.compact_.begin() + first, source.compact_.begin() + last, compact_.begin() + first);
  else std::copy(source.voxels_.begin() + first, source.voxels_.begin() + last, voxels_.begin() + first);
  if (source.holdsColour()) {
    enableColour();
    std::copy(source.colours_.begin() + first, source.colours_.begin() + last, colours_.begin() + first);
  } else if (holdsColour()) {
    std::fill(colours_.begin() + first, colours_.begin() + last, VoxelColour{});
  }
}

bool TsdfVolume::locate(const Eigen::Vector3f& p_W, size_t* base, Eigen::Vector3f* frac) const {
  const Eigen::Vector3f g = toLattice(p_W);
  const float fx = std::floor(g.x()), fy = std::floor(g.y()), fz = std::floor(g.z());
  // Written so that NaN fails every comparison and is rejected.
  if (!(fx >= 0.0f && fy >= 0.0f && fz >= 0.0f && fx < config_.dims.x() - 1 &&
        fy < config_.dims.y() - 1 && fz < config_.dims.z() - 1)) {
    return false;
  }
  *base = index(static_cast<int>(fx), static_cast<int>(fy), static_cast<int>(fz));
  *frac = Eigen::Vector3f(g.x() - fx, g.y() - fy, g.z() - fz);
  return true;
}

bool TsdfVolume::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  return withStorage([&](const auto* voxels, const auto& codec) { return sampleFrom(voxels, codec, p_W, out); });
}

template <typename Stored>
bool TsdfVolume::sampleFrom(const Stored* v, const VoxelCodec<Stored>& codec, const Eigen::Vector3f& p_W,
                            FieldSample* out) const {
  size_t b;
  Eigen::Vector3f f;
  if (!locate(p_W, &b, &f)) return false;
  const Voxel corners[8] = {codec.decode(v[b]),
                            codec.decode(v[b + 1]),
                            codec.decode(v[b + stride_y_]),
                            codec.decode(v[b + stride_y_ + 1]),
                            codec.decode(v[b + stride_z_]),
                            codec.decode(v[b + stride_z_ + 1]),
                            codec.decode(v[b + stride_z_ + stride_y_]),
                            codec.decode(v[b + stride_z_ + stride_y_ + 1])};
  return interpolate(corners, f, out);
}

}  // namespace sdf_tracker
