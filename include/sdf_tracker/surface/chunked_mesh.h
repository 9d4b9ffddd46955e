#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/surface/surface.h"

namespace sdf_tracker {

/// A sparse map's mesh kept up to date in chunks of kChunkBlocks^3 blocks: each update re-meshes
/// only the chunks whose triangles a change of the map can have moved, so a viewer is sent what
/// changed, at a cost that follows the frame's reach rather than the map's size.
class ChunkedMesher {
 public:
  using ChunkIndex = Eigen::Vector3i;
  struct Chunk {
    ChunkIndex index;
    TriangleMesh mesh;  ///< empty: the chunk no longer holds a surface
  };

  /// The chunks whose mesh may differ from what the last update returned, in a fixed order, given
  /// that `map` holds every change up to `revision` (its revision() for a live map; a copy kept by
  /// SparseTsdfMap::copyBlocksFrom holds those up to the source's revision when its changed blocks
  /// were listed). Every chunk with a surface when `everything` is set, when the map is not the
  /// one of the last update (identity) or was cleared since; restarted() then tells.
  std::vector<Chunk> update(const SparseTsdfMap& map, uint64_t revision, bool everything = false);
  /// Whether the last update started over: whatever was shown before it is to be dropped.
  bool restarted() const { return restarted_; }

 private:
  uint64_t map_identity_ = 0;
  uint64_t meshed_revision_ = 0;
  /// Keys (SparseTsdfMap::keyOf of the chunk index) of the chunks last returned with a surface.
  std::unordered_set<uint64_t> shown_;
  bool restarted_ = false;
};

}  // namespace sdf_tracker
