#include "sdf_tracker/map/overlaid_map.h"

#include <stdexcept>
#include <string>

#include "sdf_tracker/map/map_merge.h"

namespace sdf_tracker {

namespace {

[[noreturn]] void readOnly(const char* call) {
  throw std::logic_error(std::string("OverlaidMap::") + call + ": an overlay of two maps cannot be changed");
}

}  // namespace

OverlaidMap::OverlaidMap(const SparseTsdfMap& over, const SparseTsdfMap& under, float settled_weight)
    : TsdfMap(under.config(), under.type()),
      over_(over),
      under_(under),
      settled_weight_(settled_weight),
      combined_(under.config()),
      over_revision_read_(over.revision()) {
  if (!over.config().sameGrid(under.config())) {
    throw std::invalid_argument("OverlaidMap: the two maps' lattices differ");
  }
  if (!(settled_weight > 0.0f)) {
    throw std::invalid_argument("OverlaidMap: settled_weight must be positive, not " + std::to_string(settled_weight));
  }
  combine(under.blockIndices());
  under_revision_read_ = under.revision();
  tables_ = std::make_unique<SparseTsdfMap::RegionReader>(combined_, Eigen::AlignedBox3f(), layersBeneath());
}

std::vector<const SparseTsdfMap*> OverlaidMap::layersBeneath() const { return {&under_, &over_}; }

bool OverlaidMap::isCurrent() const {
  return over_.revision() == over_revision_read_ && under_.revision() == under_revision_read_;
}

void OverlaidMap::update() {
  if (isCurrent()) return;
  if (over_.revision() != over_revision_read_ || under_.clearedAt() > under_revision_read_) {
    // Over's changes are not followed block by block: every block is combined again.
    combined_.clear();
    combine(under_.blockIndices());
  } else {
    if (under_.removedAt() > under_revision_read_) {
      // Blocks under no longer holds are not listed as changed: those are dropped here.
      for (const SparseTsdfMap::BlockIndex& index : combined_.blockIndices()) {
        if (!under_.find(index)) combined_.remove(index);
      }
    }
    combine(under_.changedSince(under_revision_read_));
  }
  under_revision_read_ = under_.revision();
  over_revision_read_ = over_.revision();
}

void OverlaidMap::requireCurrent(const char* call) const {
  if (!isCurrent()) {
    throw std::logic_error(std::string("OverlaidMap::") + call +
                           ": a map it overlays changed since it last took them in (call update() first)");
  }
}

void OverlaidMap::combine(const std::vector<SparseTsdfMap::BlockIndex>& blocks) {
  // Only blocks both maps hold: where over holds none, under's block is read as it is (as
  // mergeMaps() takes a block that one part alone holds). Blocks are added first, by one thread;
  // then every block is filled on its own.
  struct Combination {
    const VoxelBlock* over;
    const VoxelBlock* under;
    VoxelBlock* into;
  };
  std::vector<Combination> combinations;
  for (const SparseTsdfMap::BlockIndex& index : blocks) {
    if (const VoxelBlock* over = over_.find(index)) {
      combinations.push_back({over, under_.find(index), &combined_.allocate(index)});
    }
  }
#pragma omp parallel for schedule(dynamic, 16)
  for (long i = 0; i < static_cast<long>(combinations.size()); ++i) {
    const Combination& c = combinations[i];
    for (int v = 0; v < kBlockVoxels; ++v) {
      Voxel voxel = c.over->voxels[v];
      if (voxel.weight < settled_weight_) accumulate(c.under->voxels[v], &voxel);  // else over's stands
      c.into->voxels[v] = voxel;
    }
  }
}

bool OverlaidMap::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  requireCurrent("sample");
  return tables_->sample(p_W, out);
}

Eigen::AlignedBox3f OverlaidMap::holdableRegion() const {
  return over_.holdableRegion().merged(under_.holdableRegion());
}

std::unique_ptr<FieldSampler> OverlaidMap::sampler(const Eigen::AlignedBox3f& region_W) const {
  requireCurrent("sampler");
  return std::make_unique<SparseTsdfMap::RegionReader>(combined_, region_W, layersBeneath());
}

void OverlaidMap::clear() { readOnly("clear"); }
void OverlaidMap::enableColour() { readOnly("enableColour"); }
std::unique_ptr<TsdfMap> OverlaidMap::clone() const { readOnly("clone"); }

}  // namespace sdf_tracker
