#include "sdf_tracker/pipeline/submaps.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "sdf_tracker/util/se3.h"
#include "sdf_tracker/util/validation.h"

namespace sdf_tracker {

std::vector<std::string> SubmapConfig::validate() const {
  Violations v;
  v.requireNonNegative("max_distance_m", max_distance_m);
  v.requireInRange("max_rotation_deg", max_rotation_deg, 0.1, 180.0);
  v.requireInRange("handover_frames", handover_frames, 1, 1000);
  v.requireNonNegative("track_recent_m", track_recent_m);
  v.requirePositive("recent_settled_weight", recent_settled_weight);
  return v.list();
}

std::string SubmapGraph::problem(size_t keyframes) const {
  if (submaps.empty()) return "no submap";
  const int count = static_cast<int>(submaps.size());
  for (int i = 0; i < count; ++i) {
    const std::string name = "submap " + std::to_string(i);
    if (!submaps[i].map) return name + " has no map";
    if (count > 1 && submaps[i].map->type() != MapType::kSparse) return name + " is a dense grid (submaps are sparse maps)";
    if (submaps[i].place.node != i) return name + " is node " + std::to_string(submaps[i].place.node) + " of the graph";
  }
  // Joined to node 0 through the edges, every one: a union of the parts they join.
  std::vector<int> part(count);
  std::iota(part.begin(), part.end(), 0);
  auto root = [&part](int node) {
    while (part[node] != node) node = part[node] = part[part[node]];
    return node;
  };
  for (size_t e = 0; e < edges.size(); ++e) {
    const PoseEdge& edge = edges[e];
    const std::string name = "edge " + std::to_string(e) + " (" + std::to_string(edge.from) + " to " + std::to_string(edge.to) + ")";
    if (edge.from < 0 || edge.from >= count || edge.to < 0 || edge.to >= count) {
      return name + " names a submap that is none of the " + std::to_string(count) + " there are";
    }
    if (edge.from == edge.to) return name + " joins a submap to itself";
    part[root(edge.from)] = root(edge.to);
  }
  for (int i = 1; i < count; ++i) {
    if (root(i) != root(0)) return "submap " + std::to_string(i) + " is joined to the first by no edge: the graph cannot place it";
  }
  if (keyframe_submaps.size() != keyframes) {
    return std::to_string(keyframe_submaps.size()) + " keyframes' submaps for " + std::to_string(keyframes) + " keyframes";
  }
  for (size_t k = 0; k < keyframe_submaps.size(); ++k) {
    if (keyframe_submaps[k] < 0 || keyframe_submaps[k] >= count) {
      return "keyframe " + std::to_string(k) + " is of submap " + std::to_string(keyframe_submaps[k]) +
             ", none of the " + std::to_string(count) + " there are";
    }
  }
  return "";
}

PlacedMap placedSubmap(const TsdfMap& submap, const Eigen::Isometry3d& T_target_W) {
  if (submap.type() != MapType::kSparse) throw std::invalid_argument("a dense grid cannot be merged as a submap");
  return {&static_cast<const SparseTsdfMap&>(submap), T_target_W};
}

SparseTsdfMap mergeSubmaps(const std::vector<Submap>& submaps) {
  std::vector<PlacedMap> parts;
  for (const Submap& submap : submaps) parts.push_back(placedSubmap(*submap.map, submap.place.T_map_W));
  return mergeMaps(parts);
}

std::unique_ptr<TsdfMap> mergeSubmaps(std::vector<Submap>&& submaps) {
  if (submaps.size() == 1 && submaps.front().place.T_map_W.isApprox(Eigen::Isometry3d::Identity(), 1e-12)) {
    return std::move(submaps.front().map);
  }
  return std::make_unique<SparseTsdfMap>(mergeSubmaps(static_cast<const std::vector<Submap>&>(submaps)));
}

bool SubmapGraph::observesNothing() const {
  return std::none_of(submaps.begin(), submaps.end(),
                      [](const Submap& submap) { return submap.map && !submap.map->observesNothing(); });
}

std::unique_ptr<PlaceMemory> placesInMapFrame(const PlaceMemory& places, const std::vector<int>& keyframe_submaps,
                                              const std::vector<Eigen::Isometry3d>& T_map_W) {
  auto moved = std::make_unique<PlaceMemory>(places.config());
  const std::vector<Keyframe>& keyframes = places.keyframes();
  for (size_t k = 0; k < keyframes.size(); ++k) {
    Keyframe keyframe = keyframes[k];
    keyframe.T_W_C = T_map_W.at(keyframe_submaps.at(k)) * keyframe.T_W_C;
    moved->add(std::move(keyframe));
  }
  return moved;
}

std::unique_ptr<PlaceMemory> SubmapGraph::placesInMapFrame(const PlaceMemory& places) const {
  std::vector<Eigen::Isometry3d> frames;
  for (const Submap& submap : submaps) frames.push_back(submap.place.T_map_W);
  return sdf_tracker::placesInMapFrame(places, keyframe_submaps, frames);
}

bool leavesSubmap(const SubmapConfig& config, const Eigen::Isometry3d& T_W_anchor, const Eigen::Isometry3d& T_W_C) {
  if (!config.enabled()) return false;
  const Eigen::Isometry3d motion = T_W_anchor.inverse() * T_W_C;
  return motion.translation().norm() > config.max_distance_m || rotationAngle(motion) > config.max_rotation_deg * M_PI / 180.0;
}

}  // namespace sdf_tracker
