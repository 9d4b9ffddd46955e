#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker {

/// A point's or a vertex's red, green and blue.
using Rgb = std::array<uint8_t, 3>;
/// The colour of a surface no image showed in colour, in a map that holds colour.
constexpr Rgb kUnseenColour = {160, 160, 160};

/// Points on the zero level set with unit normals (pointing into free space), world frame; with
/// a colour each when the map holds colour (else `colours` is empty).
struct SurfaceCloud {
  std::vector<Eigen::Vector3f> points_W;
  std::vector<Eigen::Vector3f> normals_W;
  std::vector<Rgb> colours;
};

/// An indexed triangle mesh, world frame; triangles wind counter-clockwise seen from free space.
/// Vertex colours when the map holds colour (else `colours` is empty).
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices_W;
  std::vector<Eigen::Vector3f> normals_W;
  std::vector<Rgb> colours;
  std::vector<Eigen::Vector3i> triangles;
};

/// The colour on a lattice edge at fraction t from voxel a to voxel b: interpolated between the
/// two voxels' colours, the one of them seen in colour where the other was not, else
/// kUnseenColour.
Rgb colourOnEdge(const VoxelColour& a, const VoxelColour& b, float t);

/// One point per lattice edge whose two observed samples change sign, linearly interpolated
/// (position and colour).
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
