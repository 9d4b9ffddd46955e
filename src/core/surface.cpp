#include "sdf_tracker/core/surface.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>

namespace sdf_tracker {

namespace {

Eigen::Vector3f normalAt(const TsdfVolume& volume, const Eigen::Vector3f& p_W) {
  FieldSample s;
  if (volume.sample(p_W, &s) && s.gradient.norm() > 0.0f) return s.gradient.normalized();
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

/// A mesh vertex before welding: the lattice edge it lies on and its position.
struct EdgeVertex {
  uint64_t key;
  Eigen::Vector3f p_W;
};

}  // namespace

SurfaceCloud extractSurfaceCloud(const TsdfVolume& volume) {
  const Eigen::Vector3i dims = volume.dims();
  std::vector<SurfaceCloud> slices(dims.z());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z(); ++k) {
    SurfaceCloud& slice = slices[k];
    for (int j = 0; j < dims.y(); ++j) {
      for (int i = 0; i < dims.x(); ++i) {
        const Voxel a = volume.voxel(i, j, k);
        if (a.weight <= 0.0f) continue;
        for (int axis = 0; axis < 3; ++axis) {
          Eigen::Vector3i n(i, j, k);
          n[axis] += 1;
          if (n[axis] >= dims[axis]) continue;
          const Voxel b = volume.voxel(n.x(), n.y(), n.z());
          if (b.weight <= 0.0f || (a.distance_m < 0.0f) == (b.distance_m < 0.0f)) continue;
          const float t = zeroFraction(a.distance_m, b.distance_m);
          Eigen::Vector3f p_W = volume.position(i, j, k);
          p_W[axis] += t * volume.voxelSize();
          slice.points_W.push_back(p_W);
          slice.normals_W.push_back(normalAt(volume, p_W));
        }
      }
    }
  }
  SurfaceCloud cloud;
  for (const SurfaceCloud& slice : slices) {
    cloud.points_W.insert(cloud.points_W.end(), slice.points_W.begin(), slice.points_W.end());
    cloud.normals_W.insert(cloud.normals_W.end(), slice.normals_W.begin(), slice.normals_W.end());
  }
  return cloud;
}

TriangleMesh extractMesh(const TsdfVolume& volume) {
  const Eigen::Vector3i dims = volume.dims();
  // Triangle corners per z slice, as (edge key, position) triples.
  std::vector<std::vector<EdgeVertex>> slices(dims.z() - 1);
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < dims.z() - 1; ++k) {
    std::vector<EdgeVertex>& slice = slices[k];
    for (int j = 0; j < dims.y() - 1; ++j) {
      for (int i = 0; i < dims.x() - 1; ++i) {
        std::array<float, 8> d;
        std::array<uint64_t, 8> index;
        bool observed = true;
        int negatives = 0;
        for (int c = 0; c < 8 && observed; ++c) {
          const Eigen::Vector3i o = cornerOffset(c);
          index[c] = volume.index(i + o.x(), j + o.y(), k + o.z());
          const Voxel voxel = volume.voxel(index[c]);
          observed = voxel.weight > 0.0f;
          d[c] = voxel.distance_m;
          negatives += d[c] < 0.0f;
        }
        if (!observed || negatives == 0 || negatives == 8) continue;

        auto edgeVertex = [&](int a, int b) {
          const float t = zeroFraction(d[a], d[b]);
          const Eigen::Vector3f pa = volume.position(i, j, k) + volume.voxelSize() * cornerOffset(a).cast<float>();
          const Eigen::Vector3f pb = volume.position(i, j, k) + volume.voxelSize() * cornerOffset(b).cast<float>();
          const uint64_t lo = std::min(index[a], index[b]), hi = std::max(index[a], index[b]);
          return EdgeVertex{lo * volume.voxelCount() + hi, pa + t * (pb - pa)};
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
            slice.push_back(poly[0]);
            slice.push_back(poly[m]);
            slice.push_back(poly[m + 1]);
          }
        }
      }
    }
  }

  TriangleMesh mesh;
  std::unordered_map<uint64_t, int> vertex_of_edge;
  for (const auto& slice : slices) {
    for (size_t c = 0; c < slice.size(); c += 3) {
      Eigen::Vector3i triangle;
      for (int m = 0; m < 3; ++m) {
        const EdgeVertex& ev = slice[c + m];
        auto inserted = vertex_of_edge.emplace(ev.key, static_cast<int>(mesh.vertices_W.size()));
        if (inserted.second) mesh.vertices_W.push_back(ev.p_W);
        triangle[m] = inserted.first->second;
      }
      // A quad split can collapse to a sliver where a corner sits exactly on zero.
      if (triangle[0] != triangle[1] && triangle[1] != triangle[2] && triangle[0] != triangle[2]) {
        mesh.triangles.push_back(triangle);
      }
    }
  }
  mesh.normals_W.reserve(mesh.vertices_W.size());
  for (const auto& p : mesh.vertices_W) mesh.normals_W.push_back(normalAt(volume, p));
  return mesh;
}

}  // namespace sdf_tracker
