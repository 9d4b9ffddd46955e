#pragma once

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/fusion/integrator.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"
#include "sdf_tracker/sim/synthetic.h"
#include "scratch_directory.h"

namespace sdf_tracker::test {

/// A QVGA camera keeps the unit tests in milliseconds while leaving tens of thousands of points.
inline PinholeCamera testCamera() { return PinholeCamera::tumFreiburg1().scaledTo(320, 240); }

/// A grid of 1 cm voxels around the desk as seen from the desk path's start (the far walls fall
/// outside it).
inline VolumeConfig roomVolume() {
  VolumeConfig config;
  config.dims = Eigen::Vector3i(256, 192, 256);
  config.voxel_size_m = 0.01;
  config.origin_W = Eigen::Vector3d(-1.28, -0.6, 0.3);
  config.positive_truncation_m = 0.05;
  return config;
}

/// Exact (noise-free) depth of the synthetic room from T_W_C.
inline DepthImage renderRoom(const Eigen::Isometry3d& T_W_C, const PinholeCamera& camera = testCamera()) {
  synthetic::NoiseModel no_noise;
  no_noise.enabled = false;
  return synthetic::Scene::indoorRoom().render(camera, T_W_C, no_noise, 0);
}

/// A pose perturbed by a translation along a fixed oblique direction and a rotation about another.
inline Eigen::Isometry3d perturbed(const Eigen::Isometry3d& T, double translation_m, double rotation_rad) {
  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.linear() = Eigen::AngleAxisd(rotation_rad, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  delta.translation() = translation_m * Eigen::Vector3d(2, -1, 1).normalized();
  return T * delta;
}

/// The sum of every voxel's weight: changes whenever anything is fused.
inline double totalWeight(const TsdfMap& map) {
  double sum = 0.0;
  if (map.type() == MapType::kSparse) {
    static_cast<const SparseTsdfMap&>(map).forEachBlock([&sum](const SparseTsdfMap::BlockIndex&, const VoxelBlock& block) {
      for (const Voxel& v : block.voxels) sum += v.weight;
    });
  } else {
    const auto& volume = static_cast<const TsdfVolume&>(map);
    for (size_t i = 0; i < volume.voxelCount(); ++i) sum += volume.voxel(i).weight;
  }
  return sum;
}

/// Writes `text` to `path` as it is (binary).
inline void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// Runs `fn` in a child process whose address space is capped at `megabytes` more than now (as
/// ulimit -v would cap a process): an allocation beyond that fails there. True when fn returned
/// true. Works under AddressSanitizer too, whose reservations are already made when it forks.
template <typename Fn>
bool withinMemory(size_t megabytes, Fn&& fn) {
  const pid_t child = fork();
  if (child == 0) {
    std::ifstream status("/proc/self/statm");
    size_t pages = 0;
    status >> pages;
    const rlim_t limit = static_cast<rlim_t>(pages) * sysconf(_SC_PAGESIZE) + (megabytes << 20);
    const rlimit cap{limit, limit};
    setrlimit(RLIMIT_AS, &cap);
    _exit(fn() ? 0 : 1);
  }
  int status = 0;
  waitpid(child, &status, 0);
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace sdf_tracker::test
