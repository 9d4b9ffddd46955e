#include "sdf_tracker/fusion/integrator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

/// Narrows [*lo, *hi] to the i for which a + b * i >= 0.
inline void clipToHalfLine(double a, double b, double* lo, double* hi) {
  if (b > 0.0) {
    *lo = std::max(*lo, -a / b);
  } else if (b < 0.0) {
    *hi = std::min(*hi, -a / b);
  } else if (a < 0.0) {
    *hi = -1.0, *lo = 1.0;  // empty
  }
}

}  // namespace

std::vector<std::string> IntegratorConfig::validate() const {
  Violations v;
  v.requireNegative("negative_truncation_m", negative_truncation_m);
  v.requirePositive("max_weight", max_weight);
  v.requireInRange("max_colour_weight", max_colour_weight, 1, 255);
  v.merge("noise.", noise.validate());
  return v.list();
}

Integrator::Integrator(const IntegratorConfig& config) : config_(config) {
  throwIfInvalid("integrator config", config.validate());
}

namespace {

/// The per-voxel update of eq. (1)-(2), the same for every storage: project the voxel, read the
/// depth at the nearest pixel, and average the clamped distance in.
class VoxelFusion {
 public:
  VoxelFusion(const IntegratorConfig& config, const DepthImage& depth, const ColourImage* colour,
              const PinholeCamera& camera, float dmax, float voxel_size)
      : depth_m_(depth.data()),
        rgb_(colour ? colour->data() : nullptr),
        width_(camera.width),
        height_(camera.height),
        fx_(static_cast<float>(camera.fx)),
        fy_(static_cast<float>(camera.fy)),
        cx_(static_cast<float>(camera.cx)),
        cy_(static_cast<float>(camera.cy)),
        dmax_(dmax),
        dmin_(static_cast<float>(config.negative_truncation_m)),
        wmax_(static_cast<float>(config.max_weight)),
        sensor_weights_(config.weighting == MeasurementWeighting::kSensorNoise),
        noise_(config.noise),
        reference_sigma_(config.noise.referenceSigma()),
        colour_band_(kColourBandVoxels * voxel_size),
        max_colour_weight_(config.max_colour_weight) {}

  /// Whether fuse() is given colours to update.
  bool inColour() const { return rgb_ != nullptr; }

  /// Fuses the measurement seen through voxel centre p_C (camera frame) into `voxel`, and its
  /// pixel's colour into `colour` (when given) if the voxel lies near the surface; false when the
  /// voxel is outside the image, has no measurement, or lies too far behind the surface.
  bool fuse(const Eigen::Vector3f& p_C, Voxel* voxel, VoxelColour* colour) const {
    if (p_C.z() <= 0.0f) return false;
    const float inv_z = 1.0f / p_C.z();
    // Nearest pixel; the range test comes before the conversion so rounding is exact.
    const float u_shifted = fx_ * p_C.x() * inv_z + cx_ + 0.5f;
    const float v_shifted = fy_ * p_C.y() * inv_z + cy_ + 0.5f;
    if (!(u_shifted >= 0.0f && v_shifted >= 0.0f && u_shifted < width_ && v_shifted < height_)) return false;
    const int u = static_cast<int>(u_shifted), v = static_cast<int>(v_shifted);
    const size_t pixel = static_cast<size_t>(v) * width_ + u;
    const float z_measured = depth_m_[pixel];
    if (!DepthImage::isMeasurement(z_measured)) return false;
    const float d = z_measured - p_C.z();
    if (d < dmin_) return false;
    const float d_clamped = std::min(d, dmax_);
    const float w_new = sensor_weights_ ? noise_.weight(z_measured, reference_sigma_) : 1.0f;
    const float w_sum = voxel->weight + w_new;
    voxel->distance_m = (voxel->distance_m * voxel->weight + d_clamped * w_new) / w_sum;
    voxel->weight = std::min(w_sum, wmax_);
    if (colour && std::fabs(d) <= colour_band_) fuseColour(rgb_ + 3 * pixel, colour);
    return true;
  }

 private:
  const float* depth_m_;
  const uint8_t* rgb_;  ///< the colour image, or null
  int width_, height_;
  float fx_, fy_, cx_, cy_;
  float dmax_, dmin_, wmax_;
  bool sensor_weights_;
  const DepthNoiseModel& noise_;
  float reference_sigma_;
  float colour_band_;
  int max_colour_weight_;

  /// The running average, one observation of weight 1, rounded to the nearest level.
  void fuseColour(const uint8_t* rgb, VoxelColour* colour) const {
    const int w = colour->weight;
    const float share = kShareOfNext[w];  // 1 / (w + 1), without a division per voxel
    const auto mix = [share](uint8_t old, uint8_t seen) {
      return static_cast<uint8_t>(static_cast<float>(old) + static_cast<float>(seen - old) * share + 0.5f);
    };
    colour->r = mix(colour->r, rgb[0]);
    colour->g = mix(colour->g, rgb[1]);
    colour->b = mix(colour->b, rgb[2]);
    colour->weight = static_cast<uint8_t>(std::min(w + 1, max_colour_weight_));
  }
  static const std::array<float, 256> kShareOfNext;
};

const std::array<float, 256> VoxelFusion::kShareOfNext = [] {
  std::array<float, 256> share{};
  for (int w = 0; w < 256; ++w) share[w] = 1.0f / static_cast<float>(w + 1);
  return share;
}();

/// The dense grid: each row of voxels is clipped to the viewing frustum, then fused voxel by voxel.
size_t integrateDense(const VoxelFusion& fusion, const PinholeCamera& camera, const Eigen::Isometry3f& T_C_W,
                      double z_far, TsdfVolume* volume) {
  const Eigen::Vector3i dims = volume->dims();
  const double fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  const int width = camera.width, height = camera.height;
  // Moving one voxel along x moves the point in the camera frame by this much.
  const Eigen::Vector3f step_x_C = T_C_W.linear().col(0) * volume->voxelSize();
  const double z_near = 1e-6;
  return volume->withStorage([&](auto* voxels, const auto& codec) {
    size_t updated = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : updated)
    for (int k = 0; k < dims.z(); ++k) {
      for (int j = 0; j < dims.y(); ++j) {
        const Eigen::Vector3f p0_C = T_C_W * volume->position(0, j, k);
        // Only voxels of this row inside the viewing frustum can change: each frustum plane is a
        // linear constraint on i. The per-voxel tests stay; this only skips the rest.
        const Eigen::Vector3d a = p0_C.cast<double>(), b = step_x_C.cast<double>();
        double lo = 0.0, hi = dims.x() - 1.0;
        clipToHalfLine(a.z() - z_near, b.z(), &lo, &hi);
        clipToHalfLine(z_far - a.z(), -b.z(), &lo, &hi);
        clipToHalfLine(fx * a.x() + (cx + 0.5) * a.z(), fx * b.x() + (cx + 0.5) * b.z(), &lo, &hi);
        clipToHalfLine((width - 0.5 - cx) * a.z() - fx * a.x(), (width - 0.5 - cx) * b.z() - fx * b.x(), &lo, &hi);
        clipToHalfLine(fy * a.y() + (cy + 0.5) * a.z(), fy * b.y() + (cy + 0.5) * b.z(), &lo, &hi);
        clipToHalfLine((height - 0.5 - cy) * a.z() - fy * a.y(), (height - 0.5 - cy) * b.z() - fy * b.y(), &lo, &hi);
        if (lo > hi) continue;
        const int i_begin = std::max(0, static_cast<int>(std::ceil(lo)) - 1);
        const int i_end = std::min(dims.x(), static_cast<int>(std::floor(hi)) + 2);
        Eigen::Vector3f p_C = p0_C + static_cast<float>(i_begin) * step_x_C;
        auto* row = voxels + volume->index(0, j, k);
        VoxelColour* colours = fusion.inColour() ? volume->colours() + volume->index(0, j, k) : nullptr;
        for (int i = i_begin; i < i_end; ++i, p_C += step_x_C) {
          Voxel voxel = codec.decode(row[i]);
          if (!fusion.fuse(p_C, &voxel, colours ? colours + i : nullptr)) continue;
          row[i] = codec.encode(voxel);
          ++updated;
        }
      }
    }
    return updated;
  });
}

/// Pixels apart along u and v whose rays decide which blocks a frame needs. Each ray's band is
/// widened by the spacing of these rays, so the blocks found cover every voxel the frame updates
/// except at depth edges narrower than the spacing.
constexpr int kAllocationPixelStride = 4;

/// The blocks the truncation band [z - Dmax, z - Dmin] of the measurements reaches, sorted and
/// without repeats.
std::vector<SparseTsdfMap::BlockIndex> blocksInBand(const DepthImage& depth, const PinholeCamera& camera,
                                                    const Eigen::Isometry3f& T_W_C, float dmax, float dmin,
                                                    const SparseTsdfMap& map) {
  const float step_m = 0.5f * map.blockSize();
  const float voxel_size = map.voxelSize();
  // Distance between neighbouring sampled rays per metre of depth.
  const float spacing_per_m = kAllocationPixelStride / static_cast<float>(std::min(camera.fx, camera.fy));
  const int rows = (camera.height + kAllocationPixelStride - 1) / kAllocationPixelStride;
  std::vector<std::vector<uint64_t>> per_row(rows);
#pragma omp parallel for schedule(dynamic, 4)
  for (int r = 0; r < rows; ++r) {
    const int v = r * kAllocationPixelStride;
    std::vector<uint64_t>& found = per_row[r];
    // Neighbouring rays mostly meet the same blocks: a small direct-mapped memory of keys already
    // taken keeps the list short before it is sorted.
    std::array<uint64_t, 64> recent;
    recent.fill(~0ull);
    for (int u = 0; u < camera.width; u += kAllocationPixelStride) {
      const float z = depth.at(u, v);
      if (!DepthImage::isMeasurement(z)) continue;
      const Eigen::Vector3f ray_W = T_W_C.linear() * camera.backProject(u, v, 1.0f);  // per metre of depth
      const float z_near = std::max(z - dmax - voxel_size, 0.0f), z_far = z - dmin + voxel_size;
      // Half a block at most between samples; each sample covers a box of this half-size [voxels].
      const int steps = std::max(1, static_cast<int>(std::ceil((z_far - z_near) * ray_W.norm() / step_m)));
      const float slack = (z_far * spacing_per_m + voxel_size) / voxel_size;
      for (int s = 0; s <= steps; ++s) {
        const Eigen::Vector3f centre =
            map.toLattice(T_W_C.translation() + (z_near + (z_far - z_near) * s / steps) * ray_W);
        if (!SparseTsdfMap::withinReach(centre)) continue;
        const SparseTsdfMap::BlockIndex lo = SparseTsdfMap::blockContaining(centre.array() - slack);
        const SparseTsdfMap::BlockIndex hi = SparseTsdfMap::blockContaining(centre.array() + slack);
        for (int bz = lo.z(); bz <= hi.z(); ++bz)
          for (int by = lo.y(); by <= hi.y(); ++by)
            for (int bx = lo.x(); bx <= hi.x(); ++bx) {
              const uint64_t key = SparseTsdfMap::keyOf({bx, by, bz});
              uint64_t& slot = recent[(key * 0x9E3779B97F4A7C15ull) >> 58];
              if (slot != key) found.push_back(slot = key);
            }
      }
    }
  }
  std::vector<uint64_t> keys;
  for (const auto& found : per_row) keys.insert(keys.end(), found.begin(), found.end());
  return SparseTsdfMap::indicesOf(std::move(keys));
}

/// The viewing frustum's four side planes, through the camera centre and the image's outer pixel
/// edges, as unit normals pointing inwards (camera frame), and its depth range.
class Frustum {
 public:
  Frustum(const PinholeCamera& camera, float z_far) : z_far_(z_far) {
    const float fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
    const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
    normals_[0] = Eigen::Vector3f(fx, 0.0f, cx + 0.5f).normalized();
    normals_[1] = Eigen::Vector3f(-fx, 0.0f, camera.width - 0.5f - cx).normalized();
    normals_[2] = Eigen::Vector3f(0.0f, fy, cy + 0.5f).normalized();
    normals_[3] = Eigen::Vector3f(0.0f, -fy, camera.height - 0.5f - cy).normalized();
  }
  /// Whether any part of the sphere (centre in the camera frame) can lie inside.
  bool mayHoldSphere(const Eigen::Vector3f& c_C, float radius) const {
    if (c_C.z() < -radius || c_C.z() > z_far_ + radius) return false;
    for (const Eigen::Vector3f& n : normals_) {
      if (n.dot(c_C) < -radius) return false;
    }
    return true;
  }

 private:
  std::array<Eigen::Vector3f, 4> normals_;
  float z_far_;
};

/// The sparse map: the blocks the band reaches are added, then every block the frustum may hold
/// (new or seen before, so free space is carved as in the dense grid) is fused voxel by voxel.
size_t integrateSparse(const VoxelFusion& fusion, const DepthImage& depth, const PinholeCamera& camera,
                       const Eigen::Isometry3d& T_W_C, float dmin, float z_far, SparseTsdfMap* map) {
  const Eigen::Isometry3f T_W_C_f = T_W_C.cast<float>();
  const Eigen::Isometry3f T_C_W = T_W_C.inverse().cast<float>();
  std::vector<SparseTsdfMap::BlockIndex> added;
  for (const auto& index : blocksInBand(depth, camera, T_W_C_f, map->positiveTruncation(), dmin, *map)) {
    if (!map->find(index)) {
      map->allocate(index);
      added.push_back(index);
    }
  }
  const Frustum frustum(camera, z_far);
  const float radius = 0.5f * std::sqrt(3.0f) * map->blockSize();
  // From a block's first voxel to its centre, in the camera frame.
  const Eigen::Vector3f centre_offset_C =
      T_C_W.linear() * Eigen::Vector3f::Constant(0.5f * (kBlockSide - 1) * map->voxelSize());
  std::vector<std::pair<Eigen::Vector3f, VoxelBlock*>> visible;  // first voxel's centre in the camera frame
  map->forEachBlockIn(map->blockRange(camera.viewBox(T_W_C_f, z_far)), [&](const SparseTsdfMap::BlockIndex& index,
                                                                             VoxelBlock& block) {
    const Eigen::Vector3f first_C = T_C_W * map->position(SparseTsdfMap::firstVoxel(index));
    if (frustum.mayHoldSphere(first_C + centre_offset_C, radius)) {
      visible.emplace_back(first_C, &block);
    }
  });

  const uint64_t revision = map->beginRevision();
  const Eigen::Matrix3f step_C = T_C_W.linear() * map->voxelSize();  // column a: one voxel along axis a
  size_t updated = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : updated)
  for (size_t n = 0; n < visible.size(); ++n) {
    VoxelBlock& block = *visible[n].second;
    size_t block_updated = 0;
    Voxel* voxel = block.voxels.data();
    VoxelColour* colour = fusion.inColour() ? block.colours.data() : nullptr;
    for (int z = 0; z < kBlockSide; ++z) {
      for (int y = 0; y < kBlockSide; ++y) {
        Eigen::Vector3f p_C = visible[n].first + step_C.col(2) * static_cast<float>(z) +
                              step_C.col(1) * static_cast<float>(y);
        for (int x = 0; x < kBlockSide; ++x, p_C += step_C.col(0), ++voxel) {
          block_updated += fusion.fuse(p_C, voxel, colour);
          if (colour) ++colour;
        }
      }
    }
    if (block_updated > 0) block.changed_at = revision;
    updated += block_updated;
  }
  // Blocks the band's rays grazed but no voxel of which the frame saw hold nothing: drop them.
  for (const auto& index : added) {
    if (map->find(index)->changed_at != revision) map->discardUnobserved(index);
  }
  return updated;
}

}  // namespace

size_t Integrator::integrate(const DepthImage& depth, const PinholeCamera& camera, const Eigen::Isometry3d& T_W_C,
                             TsdfMap* map, const ColourImage* colour) const {
  if (const std::string mismatch = camera.sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
    throw std::invalid_argument(mismatch);
  }
  if (colour) {
    if (const std::string mismatch = colour->sizeMismatch(depth.width(), depth.height()); !mismatch.empty()) {
      throw std::invalid_argument(mismatch);
    }
  }
  // Beyond the furthest measurement (plus the negative band) every voxel is too far behind.
  const float max_depth_m = depth.maxMeasurement();
  if (max_depth_m <= 0.0f) return 0;
  const double z_far = max_depth_m - config_.negative_truncation_m;
  if (colour) map->enableColour();
  const VoxelFusion fusion(config_, depth, colour, camera, map->positiveTruncation(), map->voxelSize());
  if (map->type() == MapType::kSparse) {
    return integrateSparse(fusion, depth, camera, T_W_C, static_cast<float>(config_.negative_truncation_m),
                           static_cast<float>(z_far), static_cast<SparseTsdfMap*>(map));
  }
  return integrateDense(fusion, camera, T_W_C.inverse().cast<float>(), z_far, static_cast<TsdfVolume*>(map));
}

}  // namespace sdf_tracker
