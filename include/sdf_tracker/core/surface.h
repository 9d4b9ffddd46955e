#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sdf_tracker/core/tsdf_volume.h"

namespace sdf_tracker {

/// Points on the zero level set with unit normals (pointing into free space), world frame.
struct SurfaceCloud {
  std::vector<Eigen::Vector3f> points_W;
  std::vector<Eigen::Vector3f> normals_W;
};

/// An indexed triangle mesh, world frame; triangles wind counter-clockwise seen from free space.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices_W;
  std::vector<Eigen::Vector3f> normals_W;
  std::vector<Eigen::Vector3i> triangles;
};

/// One point per lattice edge whose two observed samples change sign, linearly interpolated.
/// Parallel over z slices; the order of the result is deterministic.
SurfaceCloud extractSurfaceCloud(const TsdfVolume& volume);

/// Marching tetrahedra (six per cell, sharing the cell's main diagonal, as the reference
/// release) over cells whose eight samples are all observed. Vertices on shared edges are welded.
TriangleMesh extractMesh(const TsdfVolume& volume);

}  // namespace sdf_tracker
