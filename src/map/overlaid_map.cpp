#include "sdf_tracker/map/overlaid_map.h"

#include <stdexcept>
#include <string>

namespace sdf_tracker {

namespace {

/// The overlay's rule over two ways of sampling (a map's, or its region sampler's).
template <typename SampleOver, typename SampleUnder>
bool sampleOverlaid(const SampleOver& over, const SampleUnder& under, float settled_weight, FieldSample* out) {
  FieldSample o;
  const bool has_over = over(&o);
  if (has_over && o.weight >= settled_weight) {
    *out = o;
    return true;
  }
  FieldSample u;
  if (!under(&u)) {
    if (has_over) *out = o;
    return has_over;
  }
  if (!has_over) {
    *out = u;
    return true;
  }
  const float share_over = o.weight / (o.weight + u.weight);
  out->distance_m = u.distance_m + share_over * (o.distance_m - u.distance_m);
  out->gradient = u.gradient + share_over * (o.gradient - u.gradient);
  out->weight = o.weight + u.weight;
  return true;
}

class OverlaidSampler final : public FieldSampler {
 public:
  OverlaidSampler(std::unique_ptr<FieldSampler> over, std::unique_ptr<FieldSampler> under, float settled_weight)
      : over_(std::move(over)), under_(std::move(under)), settled_weight_(settled_weight) {}
  bool sample(const Eigen::Vector3f& p_W, FieldSample* out) const override {
    return sampleOverlaid([&](FieldSample* s) { return over_->sample(p_W, s); },
                          [&](FieldSample* s) { return under_->sample(p_W, s); }, settled_weight_, out);
  }

 private:
  std::unique_ptr<FieldSampler> over_, under_;
  float settled_weight_;
};

[[noreturn]] void readOnly(const char* call) {
  throw std::logic_error(std::string("OverlaidMap::") + call + ": a view of two maps cannot be changed");
}

}  // namespace

OverlaidMap::OverlaidMap(const TsdfMap& over, const TsdfMap& under, float settled_weight)
    : TsdfMap(under.config(), under.type()), over_(over), under_(under), settled_weight_(settled_weight) {
  if (!over.config().sameGrid(under.config())) {
    throw std::invalid_argument("OverlaidMap: the two maps' lattices differ");
  }
  if (!(settled_weight > 0.0f)) {
    throw std::invalid_argument("OverlaidMap: settled_weight must be positive, not " + std::to_string(settled_weight));
  }
}

bool OverlaidMap::sample(const Eigen::Vector3f& p_W, FieldSample* out) const {
  return sampleOverlaid([&](FieldSample* s) { return over_.sample(p_W, s); },
                        [&](FieldSample* s) { return under_.sample(p_W, s); }, settled_weight_, out);
}

Eigen::AlignedBox3f OverlaidMap::holdableRegion() const {
  return over_.holdableRegion().merged(under_.holdableRegion());
}

std::unique_ptr<FieldSampler> OverlaidMap::sampler(const Eigen::AlignedBox3f& region_W) const {
  return std::make_unique<OverlaidSampler>(over_.sampler(region_W), under_.sampler(region_W), settled_weight_);
}

void OverlaidMap::clear() { readOnly("clear"); }
void OverlaidMap::enableColour() { readOnly("enableColour"); }
std::unique_ptr<TsdfMap> OverlaidMap::clone() const { readOnly("clone"); }

}  // namespace sdf_tracker
