#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_map.h"

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
/// Parallel (over z slices of a dense grid, over blocks of a sparse map); the order of the result
/// is deterministic.
SurfaceCloud extractSurfaceCloud(const TsdfMap& map);

/// Marching tetrahedra (six per cell, sharing the cell's main diagonal, as the reference
/// release) over cells whose eight samples are all observed. Vertices on shared edges are welded
/// (within a block, for a sparse map: blocks are meshed apart, so a block can be re-meshed alone).
TriangleMesh extractMesh(const TsdfMap& map);

/// A sparse map's mesh in the cells whose lowest corner lies in `block` (empty when the block does
/// not exist): the pieces extractMesh joins.
TriangleMesh extractBlockMesh(const SparseTsdfMap& map, const SparseTsdfMap::BlockIndex& block);

/// Appends `part` to `mesh` (its triangles re-indexed; vertices are not welded across them).
void appendMesh(const TriangleMesh& part, TriangleMesh* mesh);

}  // namespace sdf_tracker
