#include "sdf_tracker/core/tsdf_volume.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "sdf_tracker/core/validation.h"

namespace sdf_tracker {

std::vector<std::string> VolumeConfig::validate() const {
  Violations v;
  v.requireInRange("dims.x", dims.x(), 2, 4096);
  v.requireInRange("dims.y", dims.y(), 2, 4096);
  v.requireInRange("dims.z", dims.z(), 2, 4096);
  v.requirePositive("voxel_size_m", voxel_size_m);
  v.requireFinite("origin_W.x", origin_W.x());
  v.requireFinite("origin_W.y", origin_W.y());
  v.requireFinite("origin_W.z", origin_W.z());
  v.requirePositive("positive_truncation_m", positive_truncation_m);
  if (v.list().empty()) {
    const double voxels = static_cast<double>(dims.x()) * dims.y() * dims.z();
    std::ostringstream s;
    s << "dims " << dims.x() << "x" << dims.y() << "x" << dims.z() << " need "
      << voxels * sizeof(Voxel) / (1 << 30) << " GiB; at most 16 GiB is allowed";
    v.require(voxels * sizeof(Voxel) <= 16.0 * (1ull << 30), s.str());
  }
  return v.list();
}

TsdfVolume::TsdfVolume(const VolumeConfig& config) : config_(config) {
  throwIfInvalid("volume config", config.validate());
  voxel_size_ = static_cast<float>(config.voxel_size_m);
  inv_voxel_size_ = 1.0f / voxel_size_;
  positive_truncation_ = static_cast<float>(config.positive_truncation_m);
  origin_ = config.origin_W.cast<float>();
  stride_y_ = static_cast<size_t>(config.dims.x());
  stride_z_ = stride_y_ * config.dims.y();
  voxel_count_ = stride_z_ * config.dims.z();
  clear();
}

void TsdfVolume::clear() {
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
  const Voxel v000 = codec.decode(v[b]);
  const Voxel v100 = codec.decode(v[b + 1]);
  const Voxel v010 = codec.decode(v[b + stride_y_]);
  const Voxel v110 = codec.decode(v[b + stride_y_ + 1]);
  const Voxel v001 = codec.decode(v[b + stride_z_]);
  const Voxel v101 = codec.decode(v[b + stride_z_ + 1]);
  const Voxel v011 = codec.decode(v[b + stride_z_ + stride_y_]);
  const Voxel v111 = codec.decode(v[b + stride_z_ + stride_y_ + 1]);
  if (v000.weight <= 0.0f || v100.weight <= 0.0f || v010.weight <= 0.0f || v110.weight <= 0.0f ||
      v001.weight <= 0.0f || v101.weight <= 0.0f || v011.weight <= 0.0f || v111.weight <= 0.0f) {
    return false;
  }
  const float x = f.x(), y = f.y(), z = f.z();
  // Interpolate along x on the four x-edges, then along y, then along z.
  const float d00 = v000.distance_m + x * (v100.distance_m - v000.distance_m);
  const float d10 = v010.distance_m + x * (v110.distance_m - v010.distance_m);
  const float d01 = v001.distance_m + x * (v101.distance_m - v001.distance_m);
  const float d11 = v011.distance_m + x * (v111.distance_m - v011.distance_m);
  const float d0 = d00 + y * (d10 - d00);
  const float d1 = d01 + y * (d11 - d01);
  out->distance_m = d0 + z * (d1 - d0);

  const float gx00 = v100.distance_m - v000.distance_m;
  const float gx10 = v110.distance_m - v010.distance_m;
  const float gx01 = v101.distance_m - v001.distance_m;
  const float gx11 = v111.distance_m - v011.distance_m;
  const float gx0 = gx00 + y * (gx10 - gx00);
  const float gx1 = gx01 + y * (gx11 - gx01);
  const float gy0 = d10 - d00;
  const float gy1 = d11 - d01;
  out->gradient = Eigen::Vector3f(gx0 + z * (gx1 - gx0), gy0 + z * (gy1 - gy0), d1 - d0) * inv_voxel_size_;
  return true;
}

bool TsdfVolume::sampleDistance(const Eigen::Vector3f& p_W, float* distance_m) const {
  FieldSample s;
  if (!sample(p_W, &s)) return false;
  *distance_m = s.distance_m;
  return true;
}

}  // namespace sdf_tracker
