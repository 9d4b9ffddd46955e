#include "sdf_tracker/surface/chunked_mesh.h"

#include <utility>

namespace sdf_tracker {

std::vector<ChunkedMesher::Chunk> ChunkedMesher::update(const SparseTsdfMap& map, uint64_t revision, bool everything) {
  restarted_ = everything || map.identity() != map_identity_ || map.clearedAt() > meshed_revision_;
  std::vector<uint64_t> dirty;  // chunk keys
  if (restarted_) {
    map.forEachBlock([&dirty](const SparseTsdfMap::BlockIndex& block, const VoxelBlock&) {
      dirty.push_back(SparseTsdfMap::keyOf(SparseTsdfMap::chunkOf(block)));
    });
    shown_.clear();
  } else {
    // A block's cells read the first voxels of its +x, +y and +z neighbours: a change moves the
    // triangles of the block and of the seven blocks below it.
    for (const SparseTsdfMap::BlockIndex& block : map.changedSince(meshed_revision_)) {
      for (int n = 0; n < 8; ++n) {
        dirty.push_back(
            SparseTsdfMap::keyOf(SparseTsdfMap::chunkOf(block - Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1))));
      }
    }
  }
  map_identity_ = map.identity();
  meshed_revision_ = revision;

  const std::vector<ChunkIndex> chunks = SparseTsdfMap::indicesOf(std::move(dirty));
  std::vector<Chunk> meshed(chunks.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t c = 0; c < chunks.size(); ++c) {
    meshed[c].index = chunks[c];
    map.forEachBlockIn(SparseTsdfMap::blocksOf(chunks[c]), [&](const SparseTsdfMap::BlockIndex& block, const VoxelBlock&) {
      appendMesh(extractBlockMesh(map, block), &meshed[c].mesh);
    });
  }
  // Chunks without a surface that were never shown need not be sent.
  std::vector<Chunk> changed;
  for (Chunk& chunk : meshed) {
    const uint64_t key = SparseTsdfMap::keyOf(chunk.index);
    const bool has_surface = !chunk.mesh.triangles.empty();
    if (has_surface) {
      shown_.insert(key);
    } else if (shown_.erase(key) == 0) {
      continue;
    }
    changed.push_back(std::move(chunk));
  }
  return changed;
}

}  // namespace sdf_tracker
