#include "sdf_tracker/map/map_merge.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_set>

namespace sdf_tracker {

namespace {

/// Adds a colour seen `colour.weight` times to `into`: their weighted average, the weight their
/// sum up to the most a voxel's colour holds.
void accumulate(const VoxelColour& colour, VoxelColour* into) {
  if (colour.weight == 0) return;
  const int w0 = into->weight, w1 = colour.weight, w = w0 + w1;
  const auto mix = [&](uint8_t a, uint8_t b) { return static_cast<uint8_t>((a * w0 + b * w1 + w / 2) / w); };
  *into = {mix(into->r, colour.r), mix(into->g, colour.g), mix(into->b, colour.b),
           static_cast<uint8_t>(std::min(w, 255))};
}

/// The part's voxels as they are (a part at the identity).
void addAsIs(const SparseTsdfMap& part, SparseTsdfMap* merged) {
  part.forEachBlock([&](const SparseTsdfMap::BlockIndex& index, const VoxelBlock& block) {
    VoxelBlock* into = merged->find(index);
    if (into == nullptr) {
      merged->insert(index, block);
      return;
    }
    for (int i = 0; i < kBlockVoxels; ++i) accumulate(block.voxels[i], &into->voxels[i]);
    if (!block.colours.empty()) {
      for (int i = 0; i < kBlockVoxels; ++i) accumulate(block.colours[i], &into->colours[i]);
    }
  });
}

/// The part's distance and weight at continuous lattice coordinates: trilinear where all eight
/// samples around are observed, else unobserved.
Voxel resample(const SparseTsdfMap& part, const Eigen::Vector3f& lattice) {
  const Eigen::Vector3f floor = lattice.array().floor();
  const Eigen::Vector3i first = floor.cast<int>();
  const Eigen::Vector3f f = lattice - floor;
  Voxel out{0.0f, 0.0f};
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3i offset(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const Voxel v = part.voxel(first + offset);
    if (v.weight <= 0.0f) return Voxel{part.positiveTruncation(), 0.0f};
    const float w = (offset.x() ? f.x() : 1.0f - f.x()) * (offset.y() ? f.y() : 1.0f - f.y()) *
                    (offset.z() ? f.z() : 1.0f - f.z());
    out.distance_m += w * v.distance_m;
    out.weight += w * v.weight;
  }
  return out;
}

/// The part's voxels resampled at the merged lattice's voxels where it lies moved by T_target_map.
void addMoved(const PlacedMap& placed, SparseTsdfMap* merged) {
  const SparseTsdfMap& part = *placed.map;
  const Eigen::Isometry3f T_target_part = placed.T_target_map.cast<float>();
  // The merged blocks the part's blocks reach once moved (their corners' box, a voxel wider).
  std::unordered_set<uint64_t> keys;
  const float reach = part.voxelSize();
  part.forEachBlock([&](const SparseTsdfMap::BlockIndex& index, const VoxelBlock&) {
    Eigen::AlignedBox3f box;
    const Eigen::Vector3f lo = part.position(SparseTsdfMap::firstVoxel(index));
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3f corner(c & 1 ? kBlockSide : 0, (c >> 1) & 1 ? kBlockSide : 0, (c >> 2) & 1 ? kBlockSide : 0);
      box.extend(T_target_part * (lo + part.voxelSize() * corner));
    }
    const BlockBox blocks =
        merged->blockRange(Eigen::AlignedBox3f(box.min().array() - reach, box.max().array() + reach));
    blocks.forEach([&](const Eigen::Vector3i& b) { keys.insert(SparseTsdfMap::keyOf(b)); });
  });
  const std::vector<SparseTsdfMap::BlockIndex> indices =
      SparseTsdfMap::indicesOf(std::vector<uint64_t>(keys.begin(), keys.end()));
  // Blocks are added first, by one thread; then every block is filled on its own.
  std::vector<VoxelBlock*> blocks(indices.size());
  std::vector<char> added(indices.size(), 0);
  for (size_t i = 0; i < indices.size(); ++i) {
    blocks[i] = merged->find(indices[i]);
    if (blocks[i] == nullptr) {
      blocks[i] = &merged->allocate(indices[i]);
      added[i] = 1;
    }
  }
  const Eigen::Isometry3f T_part_target = T_target_part.inverse();
#pragma omp parallel for schedule(dynamic, 8)
  for (long i = 0; i < static_cast<long>(indices.size()); ++i) {
    const Eigen::Vector3i first = SparseTsdfMap::firstVoxel(indices[i]);
    for (int z = 0; z < kBlockSide; ++z) {
      for (int y = 0; y < kBlockSide; ++y) {
        for (int x = 0; x < kBlockSide; ++x) {
          const Eigen::Vector3f p_part = T_part_target * merged->position(first + Eigen::Vector3i(x, y, z));
          const Eigen::Vector3f lattice = part.toLattice(p_part);
          const int local = VoxelBlock::index(x, y, z);
          const Voxel resampled = resample(part, lattice);
          accumulate(resampled, &blocks[i]->voxels[local]);
          // Colour from the nearest voxel: it is not blended across an edge between two colours.
          if (part.holdsColour() && resampled.weight > 0.0f) {
            const Eigen::Vector3f nearest = (lattice.array() + 0.5f).floor();
            accumulate(part.colour(nearest.cast<int>()), &blocks[i]->colours[local]);
          }
        }
      }
    }
  }
  // A block the part only grazed holds nothing it observed: it is not kept.
  for (size_t i = 0; i < indices.size(); ++i) {
    if (!added[i]) continue;
    const auto& v = blocks[i]->voxels;
    if (std::none_of(v.begin(), v.end(), [](const Voxel& voxel) { return voxel.weight > 0.0f; })) {
      merged->discardUnobserved(indices[i]);
    }
  }
}

}  // namespace

SparseTsdfMap mergeMaps(const std::vector<PlacedMap>& parts) {
  if (parts.empty()) throw std::invalid_argument("mergeMaps: no maps to merge");
  for (size_t k = 0; k < parts.size(); ++k) {
    if (parts[k].map == nullptr) throw std::invalid_argument("mergeMaps: part " + std::to_string(k) + " is no map");
    if (!parts[k].map->config().sameGrid(parts[0].map->config())) {
      throw std::invalid_argument("mergeMaps: part " + std::to_string(k) + " (" + parts[k].map->config().describe() +
                                  ") is not on the lattice of part 0 (" + parts[0].map->config().describe() + ")");
    }
    if (!parts[k].T_target_map.matrix().allFinite()) {
      throw std::invalid_argument("mergeMaps: part " + std::to_string(k) + " has a non-finite pose");
    }
  }
  SparseTsdfMap merged(parts[0].map->config());
  if (std::any_of(parts.begin(), parts.end(), [](const PlacedMap& part) { return part.map->holdsColour(); })) {
    merged.enableColour();
  }
  const uint64_t revision = merged.beginRevision();
  for (const PlacedMap& part : parts) {
    if (part.T_target_map.matrix() == Eigen::Matrix4d::Identity()) {
      addAsIs(*part.map, &merged);
    } else {
      addMoved(part, &merged);
    }
  }
  merged.forEachBlock([revision](const SparseTsdfMap::BlockIndex&, VoxelBlock& block) { block.changed_at = revision; });
  return merged;
}

const SparseTsdfMap& GrowingMerge::update(const std::vector<Part>& parts) {
  std::vector<State> states;
  std::vector<PlacedMap> placed;
  for (const Part& part : parts) {
    states.push_back({part.identity, part.revision, part.placed.T_target_map.matrix()});
    placed.push_back(part.placed);
  }
  const size_t kept = merged_states_.size();
  if (merged_ && states == merged_states_) {
    parts_merged_ = 0;
    return *merged_;
  }
  if (merged_ && kept < states.size() && std::equal(merged_states_.begin(), merged_states_.end(), states.begin())) {
    std::vector<PlacedMap> added{{merged_.get(), Eigen::Isometry3d::Identity()}};
    added.insert(added.end(), placed.begin() + static_cast<std::ptrdiff_t>(kept), placed.end());
    merged_ = std::make_unique<SparseTsdfMap>(mergeMaps(added));
    parts_merged_ = states.size() - kept;
  } else {
    merged_ = std::make_unique<SparseTsdfMap>(mergeMaps(placed));
    parts_merged_ = states.size();
  }
  merged_states_ = std::move(states);
  return *merged_;
}

}  // namespace sdf_tracker
