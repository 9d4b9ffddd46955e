#include "sdf_tracker/relocalisation/coarse_field.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "sdf_tracker/map/sparse_tsdf_map.h"

namespace sdf_tracker {

namespace {

constexpr float kFar = std::numeric_limits<float>::infinity();

/// Felzenszwalb & Huttenlocher's lower envelope of parabolas along one line of n samples `stride`
/// apart: f becomes min_q (p - q)^2 + f(q), and seed the seed of the minimising q (a feature
/// transform: Maurer et al. show the nearest site survives the separable passes). v, z, d, s are
/// scratch of at least n (+1) entries.
void distanceTransform1d(float* f, int32_t* seed, int n, size_t stride, std::vector<int>& v, std::vector<float>& z,
                         std::vector<float>& d, std::vector<int32_t>& s) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const float fq = f[q * stride];
    if (fq == kFar) continue;
    float cut = -kFar;
    while (k >= 0) {
      const int p = v[k];
      cut = ((fq + static_cast<float>(q) * q) - (f[p * stride] + static_cast<float>(p) * p)) / (2.0f * (q - p));
      if (cut > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kFar : cut;
    z[k + 1] = kFar;
  }
  if (k < 0) return;  // nothing on this line: it stays far
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const float dq = static_cast<float>(q - v[j]);
    d[q] = dq * dq + f[v[j] * stride];
    s[q] = seed[v[j] * stride];
  }
  for (int q = 0; q < n; ++q) {
    f[q * stride] = d[q];
    seed[q * stride] = s[q];
  }
}

/// The positions of the observed voxels within half a voxel of a surface: a voxel-exact surface,
/// which is all a lattice of several voxels per cell needs, read without interpolating (a fraction
/// of what extracting the surface costs on a large map).
std::vector<Eigen::Vector3f> surfaceVoxels(const TsdfMap& map) {
  const float near = 0.5f * map.voxelSize();
  std::vector<Eigen::Vector3f> points;
  if (map.type() == MapType::kSparse) {
    const auto& sparse = static_cast<const SparseTsdfMap&>(map);
    sparse.forEachBlock([&](const SparseTsdfMap::BlockIndex& index, const VoxelBlock& block) {
      const Eigen::Vector3i first = SparseTsdfMap::firstVoxel(index);
      for (int z = 0; z < kBlockSide; ++z)
        for (int y = 0; y < kBlockSide; ++y)
          for (int x = 0; x < kBlockSide; ++x) {
            const Voxel& v = block.voxels[VoxelBlock::index(x, y, z)];
            if (v.weight > 0.0f && std::fabs(v.distance_m) < near) points.push_back(map.position(first + Eigen::Vector3i(x, y, z)));
          }
    });
  } else {
    const auto& dense = static_cast<const TsdfVolume&>(map);
    const Eigen::Vector3i dims = dense.dims();
    for (int k = 0; k < dims.z(); ++k)
      for (int j = 0; j < dims.y(); ++j)
        for (int i = 0; i < dims.x(); ++i) {
          const Voxel v = dense.voxel(i, j, k);
          if (v.weight > 0.0f && std::fabs(v.distance_m) < near) points.push_back(dense.position(i, j, k));
        }
  }
  return points;
}

}  // namespace

TsdfVolume buildCoarseField(const TsdfMap& map, double cell_m, double reach_m, size_t max_cells) {
  if (!(cell_m > 0.0) || !(reach_m > cell_m)) {
    throw std::invalid_argument("coarse field: reach (" + std::to_string(reach_m) + " m) must exceed the cell (" +
                                std::to_string(cell_m) + " m)");
  }
  const std::vector<Eigen::Vector3f> surface = surfaceVoxels(map);
  if (surface.empty()) throw std::invalid_argument("coarse field: the map holds no surface");
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3f& p : surface) box.extend(p.cast<double>());
  box.min().array() -= reach_m;
  box.max().array() += reach_m;
  const Eigen::Vector3d extent = box.sizes();
  // The cell that keeps the lattice within max_cells (and within a dense grid's 4096 per axis).
  double cell = cell_m;
  const double cells_at_request = (extent / cell).array().ceil().prod();
  if (cells_at_request > static_cast<double>(max_cells)) cell *= std::cbrt(cells_at_request / static_cast<double>(max_cells));
  cell = std::max(cell, extent.maxCoeff() / 4095.0);

  VolumeConfig config;
  config.type = MapType::kDense;
  config.voxel_size_m = cell;
  config.positive_truncation_m = std::max(reach_m, 1.5 * cell);
  config.origin_W = box.min();
  config.dims = ((extent / cell).array().ceil().cast<int>() + 1).max(2).matrix();
  TsdfVolume field(config);
  const Eigen::Vector3i dims = config.dims;
  const size_t nx = static_cast<size_t>(dims.x()), nxy = nx * dims.y(), n = nxy * dims.z();

  // Each lattice sample nearest to a surface point is a seed, keeping that point; the transform
  // finds every sample's nearest seed (squared distances in cells, along x, y and z in turn), and
  // the distance is then the exact one to that seed's point.
  std::vector<float> f(n, kFar);
  std::vector<int32_t> seed(n, -1);
  std::vector<Eigen::Vector3f> seed_points;
  for (const Eigen::Vector3f& p : surface) {
    const Eigen::Vector3d lattice = (p.cast<double>() - config.origin_W) / cell;
    const Eigen::Vector3i at = lattice.array().round().cast<int>().max(0).min(dims.array() - 1).matrix();
    const size_t i = at.z() * nxy + at.y() * nx + at.x();
    if (seed[i] < 0) {
      seed[i] = static_cast<int32_t>(seed_points.size());
      seed_points.push_back(p);
      f[i] = 0.0f;
    } else if ((p - field.position(at)).squaredNorm() < (seed_points[seed[i]] - field.position(at)).squaredNorm()) {
      seed_points[seed[i]] = p;  // the point nearest the sample speaks for it
    }
  }
  const int longest = dims.maxCoeff();
  const Eigen::Vector3i line_count(dims.y() * dims.z(), dims.x() * dims.z(), dims.x() * dims.y());
  const size_t strides[3] = {1, nx, nxy};
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
#pragma omp parallel
    {
      std::vector<int> v(longest);
      std::vector<float> z(longest + 1), d(longest);
      std::vector<int32_t> s(longest);
#pragma omp for schedule(static)
      for (int line = 0; line < line_count[axis]; ++line) {
        const int i1 = line % dims[a1], i2 = line / dims[a1];
        const size_t start = i1 * strides[a1] + i2 * strides[a2];
        distanceTransform1d(f.data() + start, seed.data() + start, dims[axis], strides[axis], v, z, d, s);
      }
    }
  }
  const float truncation = static_cast<float>(config.positive_truncation_m);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < dims.z(); ++k) {
    for (int j = 0; j < dims.y(); ++j) {
      for (int i = 0; i < dims.x(); ++i) {
        const size_t at = k * nxy + j * nx + i;
        const float distance =
            seed[at] < 0 ? truncation : (seed_points[seed[at]] - field.position(i, j, k)).norm();
        field.setVoxel(at, Voxel{std::min(truncation, distance), 1.0f});
      }
    }
  }
  return field;
}

}  // namespace sdf_tracker
