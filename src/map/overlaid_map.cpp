#include "sdf_tracker/map/overlaid_map.h"

#include <stdexcept>
#include <string>

#include "sdf_tracker/map/map_merge.h"

namespace sdf_tracker {

namespace {

[[noreturn]] void readOnly(const char* call) {
  throw std::logic_error(std::string("OverlaidMap::") + call + ": a view of two maps cannot be changed");
}

}  // namespace

class OverlaidMap::Sampler final : public FieldSampler {
 public:
  Sampler(const OverlaidMap& map, const Eigen::AlignedBox3f& region_W)
      : map_(map), over_(map.over_, region_W), under_(map.under_, region_W) {}
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override {
    return map_.sampleVia(p_W, [&](const SparseTsdfMap::Cell& cell, Voxel(&c)[8]) { over_.corners(cell, c); },
                          [&](const SparseTsdfMap::Cell& cell, Voxel(&c)[8]) { under_.corners(cell, c); }, out);
  }

 private:
  const OverlaidMap& map_;
  SparseTsdfMap::RegionReader over_, under_;
};

OverlaidMap::OverlaidMap(const SparseTsdfMap& over, const SparseTsdfMap& under, float settled_weight)
    : TsdfMap(under.config(), under.type()), over_(over), under_(under), settled_weight_(settled_weight) {
  if (!over.config().sameGrid(under.config())) {
    throw std::invalid_argument("OverlaidMap: the two maps' lattices differ");
  }
  if (!(settled_weight > 0.0f)) {
    throw std::invalid_argument("OverlaidMap: settled_weight must be positive, not " + std::to_string(settled_weight));
  }
}

template <typename ReadOver, typename ReadUnder>
bool OverlaidMap::sampleVia(const Eigen::Vector3f& p_W, const ReadOver& readOver, const ReadUnder& readUnder,
                            FieldSample* out) const {
  // One grid: the cell is found once for both maps.
  SparseTsdfMap::Cell cell;
  if (!over_.cellAt(p_W, &cell)) return false;  // outside the blocks' reach, for both
  Voxel over[8];
  readOver(cell, over);
  bool settled = true;
  for (const Voxel& v : over) settled = settled && v.weight >= settled_weight_;
  if (!settled) {
    Voxel under[8];
    readUnder(cell, under);
    for (int c = 0; c < 8; ++c) {
      if (over[c].weight < settled_weight_) accumulate(under[c], &over[c]);  // else over's voxel stands
    }
  }
  return interpolate(over, cell.fraction, out);
}

bool OverlaidMap::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  return sampleVia(p_W, [&](const SparseTsdfMap::Cell& cell, Voxel(&c)[8]) { over_.corners(cell, c); },
                   [&](const SparseTsdfMap::Cell& cell, Voxel(&c)[8]) { under_.corners(cell, c); }, out);
}

Eigen::AlignedBox3f OverlaidMap::holdableRegion() const {
  return over_.holdableRegion().merged(under_.holdableRegion());
}

std::unique_ptr<FieldSampler> OverlaidMap::sampler(const Eigen::AlignedBox3f& region_W) const {
  return std::make_unique<Sampler>(*this, region_W);
}

void OverlaidMap::clear() { readOnly("clear"); }
void OverlaidMap::enableColour() { readOnly("enableColour"); }
std::unique_ptr<TsdfMap> OverlaidMap::clone() const { readOnly("clone"); }

}  // namespace sdf_tracker
