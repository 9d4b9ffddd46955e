#include "sdf_tracker/io/map_file.h"

#include <algorithm>
#include <optional>

#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/sdfmap_file.h"
#include "sdf_tracker/io/vti_file.h"
#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/map/tsdf_volume.h"

namespace sdf_tracker::io {

namespace {

[[noreturn]] void failUnknownMapExtension(const std::string& path) {
  throwFileError(path, "unknown map file extension (known: .sdfmap, .vti)");
}

/// A map in which nothing was ever observed cannot be tracked against: the camera would never be
/// found in it.
void refuseEmpty(const std::string& path, const TsdfMap& map) {
  if (map.observesNothing()) throwFileError(path, "an empty map: no voxel holds an observation, nothing to track against");
}

}  // namespace

void writeMap(const std::string& path, const TsdfMap& map, const PlaceMemory* places,
              const std::optional<Eigen::Isometry3d>& T_map_W) {
  if (map.observesNothing()) throwFileError(path, "not written: nothing is mapped yet (no voxel holds an observation)");
  if (hasExtension(path, ".sdfmap")) {
    if (map.type() == MapType::kSparse) writeSparseMap(path, static_cast<const SparseTsdfMap&>(map), places, T_map_W);
    else writeSparseMap(path, toSparseMap(map), places, T_map_W);
  } else if (hasExtension(path, ".vti")) {
    writeVti(path, toDenseVolume(map));
  } else {
    failUnknownMapExtension(path);
  }
}

bool readsAsDenseGrid(const std::string& path) { return hasExtension(path, ".vti"); }

std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels, std::unique_ptr<PlaceMemory>* places,
                                 const PlaceMemoryConfig& places_config, std::optional<Eigen::Isometry3d>* T_map_W) {
  if (places) places->reset();
  if (T_map_W) T_map_W->reset();
  if (hasExtension(path, ".sdfmap")) {
    std::optional<SavedPlaces> saved;
    auto map = std::make_unique<SparseTsdfMap>(readSparseMap(path, places ? &saved : nullptr, T_map_W));
    refuseEmpty(path, *map);
    if (places && saved) {
      PlaceMemoryConfig config = places_config;
      config.descriptor = saved->descriptor;
      config.max_keyframes = std::max<int>(config.max_keyframes, static_cast<int>(saved->keyframes.size()));
      *places = std::make_unique<PlaceMemory>(config);
      for (Keyframe& keyframe : saved->keyframes) (*places)->add(std::move(keyframe));
    }
    return map;
  }
  if (readsAsDenseGrid(path)) {
    auto map = std::make_unique<TsdfVolume>(readVti(path, compact_voxels));
    refuseEmpty(path, *map);
    return map;
  }
  failUnknownMapExtension(path);
}

std::string describeLoadedColour(const TsdfMap& map, bool colour_on) {
  if (!colour_on || map.holdsColour()) return "";
  return "holds no colour (a .sdfmap before format version 4, or a map made without colour): what it holds shows "
         "grey until the camera sees it in colour";
}

std::string describeLoadedPlaces(const PlaceMemory* places, bool relocalise) {
  std::string held;
  if (!places) held = "holds no place memory (a .vti, or a .sdfmap of format version 1)";
  else if (places->empty()) held = "holds a place memory without keyframes (its first session stored none)";
  else held = "holds " + std::to_string(places->keyframes().size()) + " keyframes in its place memory";
  if (!relocalise) return held + "; Relocalise is off: tracking starts at the map's start pose";
  if (!places || places->empty()) return held + ": the camera is searched for from the map's start pose only";
  return held + ": the camera is searched for in it, and nothing is fused until it is found";
}

}  // namespace sdf_tracker::io
