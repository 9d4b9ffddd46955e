#include "sdf_tracker/surface/surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "sdf_tracker/map/tsdf_volume.h"

namespace sdf_tracker {

namespace {

Eigen::Vector3f normalAt(const TsdfMap& map, const Eigen::Vector3f& p_W) {
  FieldSample s;
  if (map.sample(p_W, &s) && s.gradient.norm() > 0.0f) return s.gradient.normalized();
  return Eigen::Vector3f::Zero();
}

/// Where the segment between samples a and b crosses zero, as a fraction from a.
inline float zeroFraction(float da, float db) { return da / (da - db); }

/// Corner c of a cell: bit 0 = +x, bit 1 = +y, bit 2 = +z.
inline Eigen::Vector3i cornerOffset(int c) { return {c & 1, (c >> 1) & 1, (c >> 2) & 1}; }

/// The Freudenthal split of a cube into six tetrahedra around the 0-7 diagonal. Neighbouring cells
/// split their shared faces the same way, so the mesh has no cracks.
constexpr std::array<std::array<int, 4>, 6> kTetrahedra = {{
    {0, 1, 3, 7}, {0, 3, 2, 7}, {0, 2, 6, 7}, {0, 6, 4, 7}, {0, 4, 5, 7}, {0, 5, 1, 7}}};

SurfaceCloud concatenate(const std::vector<SurfaceCloud>& parts) {
  SurfaceCloud cloud;
  for (const SurfaceCloud& part : parts) {
    cloud.points_W.insert(cloud.points_W.end(), part.points_W.begin(), part.points_W.end());
    cloud.normals_W.insert(cloud.normals_W.end(), part.normals_W.begin(), part.normals_W.end());
    cloud.colours.insert(cloud.colours.end(), part.colours.begin(), part.colours.end());
  }
  return cloud;
}

/// A mesh vertex before welding: the lattice edge it lies on, its position and its colour (when
/// the map holds colour).
struct EdgeVertex {
  uint64_t key;
  Eigen::Vector3f p_W;
  Rgb colour;
};

/// The crossings on the (up to three) lattice edges from voxel (i, j, k) towards +x, +y and +z;
/// normals from `field`.
void crossingsFromVoxel(const TsdfVolume& lattice, const TsdfMap& field, int i, int j, int k, SurfaceCloud* out) {
  const Eigen::Vector3i dims = lattice.dims();
  const Voxel a = lattice.voxel(i, j, k);
  if (a.weight <= 0.0f) return;
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::Vector3i n(i, j, k);
    n[axis] += 1;
    if (n[axis] >= dims[axis]) continue;
    const Voxel b = lattice.voxel(n.x(), n.y(), n.z());
    if (b.weight <= 0.0f || (a.distance_m < 0.0f) == (b.distance_m < 0.0f)) continue;
    const float t = zeroFraction(a.distance_m, b.distance_m);
    Eigen::Vector3f p_W = lattice.position(i, j, k);
    p_W[axis] += t * lattice.voxelSize();
    out->points_W.push_back(p_W);
    out->normals_W.push_back(normalAt(field, p_W));
    if (lattice.holdsColour()) {
      out->colours.push_back(colourOnEdge(lattice.colour(i, j, k), lattice.colour(n.x(), n.y(), n.z()), t));
    }
  }
}

/// Marching tetrahedra in the cell whose lowest corner is voxel (i, j, k): appends each triangle's
/// three corners. Edge keys are the lattice indices of the edge's ends.
void trianglesOfCell(const TsdfVolume& lattice, int i, int j, int k, std::vector<EdgeVertex>* out) {
  std::array<float, 8> d;
  std::array<uint64_t, 8> index;
  int negatives = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3i o = cornerOffset(c);
    index[c] = lattice.index(i + o.x(), j + o.y(), k + o.z());
    const Voxel voxel = lattice.voxel(index[c]);
    if (voxel.weight <= 0.0f) return;
    d[c] = voxel.distance_m;
    negatives += d[c] < 0.0f;
  }
  if (negatives == 0 || negatives == 8) return;

  auto edgeVertex = [&](int a, int b) {
    const float t = zeroFraction(d[a], d[b]);
    const Eigen::Vector3f pa = lattice.position(i, j, k) + lattice.voxelSize() * cornerOffset(a).cast<float>();
    const Eigen::Vector3f pb = lattice.position(i, j, k) + lattice.voxelSize() * cornerOffset(b).cast<float>();
    const uint64_t lo = std::min(index[a], index[b]), hi = std::max(index[a], index[b]);
    const Rgb colour = lattice.holdsColour() ? colourOnEdge(lattice.colour(index[a]), lattice.colour(index[b]), t)
                                             : kUnseenColour;
    return EdgeVertex{lo * lattice.voxelCount() + hi, pa + t * (pb - pa), colour};
  };
  for (const auto& tet : kTetrahedra) {
    std::array<int, 4> inside, outside;
    int n_in = 0, n_out = 0;
    for (int c : tet) (d[c] < 0.0f ? inside[n_in++] : outside[n_out++]) = c;
    if (n_in == 0 || n_out == 0) continue;
    // Corners of the crossing polygon: one triangle (1|3 split) or a quad (2|2 split).
    std::array<EdgeVertex, 4> poly;
    int n_poly = 0;
    if (n_in == 1 || n_out == 1) {
      const bool lone_inside = n_in == 1;
      const int lone = lone_inside ? inside[0] : outside[0];
      for (int m = 0; m < 3; ++m) poly[n_poly++] = edgeVertex(lone, lone_inside ? outside[m] : inside[m]);
    } else {
      poly[n_poly++] = edgeVertex(inside[0], outside[0]);
      poly[n_poly++] = edgeVertex(inside[0], outside[1]);
      poly[n_poly++] = edgeVertex(inside[1], outside[1]);
      poly[n_poly++] = edgeVertex(inside[1], outside[0]);
    }
    // Wind so the face normal points from the inside corners towards the outside ones.
    Eigen::Vector3f towards_free = Eigen::Vector3f::Zero();
    for (int m = 0; m < n_out; ++m) towards_free += cornerOffset(outside[m]).cast<float>() / n_out;
    for (int m = 0; m < n_in; ++m) towards_free -= cornerOffset(inside[m]).cast<float>() / n_in;
    // The diagonals' cross product orients a quad robustly even when one side is tiny.
    const Eigen::Vector3f face =
        n_poly == 3 ? Eigen::Vector3f((poly[1].p_W - poly[0].p_W).cross(poly[2].p_W - poly[0].p_W))
                    : Eigen::Vector3f((poly[2].p_W - poly[0].p_W).cross(poly[3].p_W - poly[1].p_W));
    if (face.dot(towards_free) < 0.0f) std::reverse(poly.begin(), poly.begin() + n_poly);
    for (int m = 1; m + 1 < n_poly; ++m) {
      out->push_back(poly[0]);
      out->push_back(poly[m]);
      out->push_back(poly[m + 1]);
    }
  }
}

/// Joins triangle corners into an indexed mesh, one vertex per lattice edge; normals from `field`,
/// the corners' colours with `coloured`.
TriangleMesh weld(const std::vector<std::vector<EdgeVertex>>& pieces, const TsdfMap& field, bool coloured) {
  TriangleMesh mesh;
  std::unordered_map<uint64_t, int> vertex_of_edge;
  for (const auto& piece : pieces) {
    for (size_t c = 0; c < piece.size(); c += 3) {
      Eigen::Vector3i triangle;
      for (int m = 0; m < 3; ++m) {
        const EdgeVertex& ev = piece[c + m];
        auto inserted = vertex_of_edge.emplace(ev.key, static_cast<int>(mesh.vertices_W.size()));
        if (inserted.second) {
          mesh.vertices_W.push_back(ev.p_W);
          if (coloured) mesh.colours.push_back(ev.colour);
        }
        triangle[m] = inserted.first->second;
      }
      // A quad split can collapse to a sliver where a corner sits exactly on zero.
      if (triangle[0] != triangle[1] && triangle[1] != triangle[2] && triangle[0] != triangle[2]) {
        mesh.triangles.push_back(triangle);
      }
    }
  }
  mesh.normals_W.reserve(mesh.vertices_W.size());
  for (const auto& p : mesh.vertices_W) mesh.normals_W.push_back(normalAt(field, p));
  return mesh;
}

/// A block and the first layer of its +x, +y and +z neighbours as a (kBlockSide + 1)^3 dense grid
/// at the block's place: every cell and edge that starts in the block lies inside it.
TsdfVolume paddedBlock(const SparseTsdfMap& map, const SparseTsdfMap::BlockIndex& index) {
  const Eigen::Vector3i first = SparseTsdfMap::firstVoxel(index);
  VolumeConfig config = map.config();
  config.dims = Eigen::Vector3i::Constant(kBlockSide + 1);
  config.origin_W = map.config().origin_W + map.config().voxel_size_m * first.cast<double>();
  TsdfVolume padded(config);
  if (map.holdsColour()) padded.enableColour();
  const VoxelBlock* block = map.find(index);
  for (int k = 0; k <= kBlockSide; ++k) {
    for (int j = 0; j <= kBlockSide; ++j) {
      for (int i = 0; i <= kBlockSide; ++i) {
        const bool inside = i < kBlockSide && j < kBlockSide && k < kBlockSide && block;
        const Eigen::Vector3i voxel = first + Eigen::Vector3i(i, j, k);
        padded.setVoxel(i, j, k, inside ? block->voxels[VoxelBlock::index(i, j, k)] : map.voxel(voxel));
        if (map.holdsColour()) {
          padded.setColour(i, j, k, inside ? block->colours[VoxelBlock::index(i, j, k)] : map.colour(voxel));
        }
      }
    }
  }
  return padded;
}

SurfaceCloud denseCloud(const TsdfVolume& volume) {
  const Eigen::Vector3i dims = volume.dims();
  std::vector<SurfaceCloud> slices(dims.z());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z(); ++k) {
    for (int j = 0; j < dims.y(); ++j) {
      for (int i = 0; i < dims.x(); ++i) crossingsFromVoxel(volume, volume, i, j, k, &slices[k]);
    }
  }
  return concatenate(slices);
}

SurfaceCloud sparseCloud(const SparseTsdfMap& map) {
  const std::vector<SparseTsdfMap::BlockIndex> blocks = map.blockIndices();
  std::vector<SurfaceCloud> parts(blocks.size());
#pragma omp parallel for schedule(dynamic, 8)
  for (size_t b = 0; b < blocks.size(); ++b) {
    const TsdfVolume padded = paddedBlock(map, blocks[b]);
    for (int k = 0; k < kBlockSide; ++k) {
      for (int j = 0; j < kBlockSide; ++j) {
        for (int i = 0; i < kBlockSide; ++i) crossingsFromVoxel(padded, map, i, j, k, &parts[b]);
      }
    }
  }
  return concatenate(parts);
}

TriangleMesh denseMesh(const TsdfVolume& volume) {
  const Eigen::Vector3i dims = volume.dims();
  std::vector<std::vector<EdgeVertex>> slices(dims.z() - 1);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z() - 1; ++k) {
    for (int j = 0; j < dims.y() - 1; ++j) {
      for (int i = 0; i < dims.x() - 1; ++i) trianglesOfCell(volume, i, j, k, &slices[k]);
    }
  }
  return weld(slices, volume, volume.holdsColour());
}

}  // namespace

Rgb colourOnEdge(const VoxelColour& a, const VoxelColour& b, float t) {
  if (a.weight == 0 && b.weight == 0) return kUnseenColour;
  if (b.weight == 0) return {a.r, a.g, a.b};
  if (a.weight == 0) return {b.r, b.g, b.b};
  const auto mix = [t](uint8_t x, uint8_t y) { return static_cast<uint8_t>(std::lround(x + t * (y - x))); };
  return {mix(a.r, b.r), mix(a.g, b.g), mix(a.b, b.b)};
}

SurfaceCloud extractSurfaceCloud(const TsdfMap& map) {
  if (map.type() == MapType::kSparse) return sparseCloud(static_cast<const SparseTsdfMap&>(map));
  return denseCloud(static_cast<const TsdfVolume&>(map));
}

TriangleMesh extractMesh(const TsdfMap& map) {
  if (map.type() == MapType::kDense) return denseMesh(static_cast<const TsdfVolume&>(map));
  const auto& sparse = static_cast<const SparseTsdfMap&>(map);
  const std::vector<SparseTsdfMap::BlockIndex> blocks = sparse.blockIndices();
  std::vector<TriangleMesh> parts(blocks.size());
#pragma omp parallel for schedule(dynamic, 8)
  for (size_t b = 0; b < blocks.size(); ++b) parts[b] = extractBlockMesh(sparse, blocks[b]);
  TriangleMesh mesh;
  for (const TriangleMesh& part : parts) appendMesh(part, &mesh);
  return mesh;
}

void appendMesh(const TriangleMesh& part, TriangleMesh* mesh) {
  const int offset = static_cast<int>(mesh->vertices_W.size());
  mesh->vertices_W.insert(mesh->vertices_W.end(), part.vertices_W.begin(), part.vertices_W.end());
  mesh->normals_W.insert(mesh->normals_W.end(), part.normals_W.begin(), part.normals_W.end());
  mesh->colours.insert(mesh->colours.end(), part.colours.begin(), part.colours.end());
  for (const Eigen::Vector3i& t : part.triangles) mesh->triangles.push_back(t + Eigen::Vector3i::Constant(offset));
}

TriangleMesh extractBlockMesh(const SparseTsdfMap& map, const SparseTsdfMap::BlockIndex& block) {
  const TsdfVolume padded = paddedBlock(map, block);
  std::vector<std::vector<EdgeVertex>> corners(1);
  for (int k = 0; k < kBlockSide; ++k) {
    for (int j = 0; j < kBlockSide; ++j) {
      for (int i = 0; i < kBlockSide; ++i) trianglesOfCell(padded, i, j, k, &corners[0]);
    }
  }
  return weld(corners, map, map.holdsColour());
}

}  // namespace sdf_tracker
