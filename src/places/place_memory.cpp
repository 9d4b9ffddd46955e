#include "sdf_tracker/places/place_memory.h"

#include <algorithm>
#include <stdexcept>

#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

namespace {

const PlaceMemoryConfig& validated(const PlaceMemoryConfig& config) {
  throwIfInvalid("place memory config", config.validate());
  return config;
}

}  // namespace

std::vector<std::string> PlaceMemoryConfig::validate() const {
  Violations v;
  v.merge("descriptor.", descriptor.validate());
  v.requireNonNegative("check_translation_m", check_translation_m);
  v.requireNonNegative("check_rotation_rad", check_rotation_rad);
  v.requireNonNegative("keyframe_spacing_m", keyframe_spacing_m);
  v.requireNonNegative("keyframe_spacing_rad", keyframe_spacing_rad);
  v.requireInRange("min_novelty", min_novelty, 0.0, 1.0);
  v.requireInRange("max_keyframes", max_keyframes, 0, 10000000);
  return v.list();
}

PlaceMemory::PlaceMemory(const PlaceMemoryConfig& config)
    : config_(validated(config)), encoder_(config.descriptor) {}

size_t PlaceMemory::bytesPerKeyframe() const {
  return sizeof(Keyframe) + static_cast<size_t>(config_.descriptor.fern_count) * sizeof(PlaceCode::value_type);
}

bool PlaceMemory::offer(const DepthImage& depth, const Eigen::Isometry3d& T_W_C) {
  if (keyframes_.size() >= static_cast<size_t>(config_.max_keyframes)) return false;
  if (checked_any_) {
    const Eigen::Isometry3d motion = T_W_C_last_checked_.inverse() * T_W_C;
    if (motion.translation().norm() < config_.check_translation_m && rotationAngle(motion) < config_.check_rotation_rad) {
      return false;
    }
  }
  checked_any_ = true;
  T_W_C_last_checked_ = T_W_C;
  PlaceCode code = encoder_.encode(depth);
  for (const Keyframe& keyframe : keyframes_) {
    const Eigen::Isometry3d offset = keyframe.T_W_C.inverse() * T_W_C;
    if (offset.translation().norm() < config_.keyframe_spacing_m && rotationAngle(offset) < config_.keyframe_spacing_rad &&
        PlaceEncoder::dissimilarity(code, keyframe.code) < config_.min_novelty) {
      return false;
    }
  }
  keyframes_.push_back({T_W_C, std::move(code)});
  return true;
}

void PlaceMemory::add(Keyframe keyframe) {
  if (keyframe.code.size() != static_cast<size_t>(config_.descriptor.fern_count)) {
    throw std::invalid_argument("a keyframe of " + std::to_string(keyframe.code.size()) +
                                " ferns does not fit a place memory of " +
                                std::to_string(config_.descriptor.fern_count));
  }
  if (keyframes_.size() >= static_cast<size_t>(config_.max_keyframes)) {
    throw std::invalid_argument("the place memory is full (" + std::to_string(config_.max_keyframes) + " keyframes)");
  }
  keyframes_.push_back(std::move(keyframe));
}

std::vector<PlaceMemory::Match> PlaceMemory::mostAlike(const PlaceCode& code, size_t count) const {
  std::vector<Match> matches;
  matches.reserve(keyframes_.size());
  for (size_t k = 0; k < keyframes_.size(); ++k) {
    matches.push_back({k, PlaceEncoder::dissimilarity(code, keyframes_[k].code)});
  }
  const size_t n = std::min(count, matches.size());
  std::partial_sort(matches.begin(), matches.begin() + static_cast<std::ptrdiff_t>(n), matches.end(),
                    [](const Match& a, const Match& b) {
                      return a.dissimilarity < b.dissimilarity || (a.dissimilarity == b.dissimilarity && a.keyframe < b.keyframe);
                    });
  matches.resize(n);
  return matches;
}

void PlaceMemory::clear() {
  keyframes_.clear();
  checked_any_ = false;
}

}  // namespace sdf_tracker
