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
void refuseEmpty(const std::string& path, bool observes_nothing) {
  if (observes_nothing) throwFileError(path, "an empty map: no voxel holds an observation, nothing to track against");
}

constexpr char kNothingMappedYet[] = "not written: nothing is mapped yet (no voxel holds an observation)";

}  // namespace

void writeMap(const std::string& path, const TsdfMap& map, const PlaceMemory* places,
              const std::optional<Eigen::Isometry3d>& T_map_W) {
  if (map.observesNothing()) throwFileError(path, kNothingMappedYet);
  if (hasExtension(path, ".sdfmap")) {
    if (map.type() == MapType::kSparse) writeSparseMap(path, static_cast<const SparseTsdfMap&>(map), places, T_map_W);
    else writeSparseMap(path, toSparseMap(map), places, T_map_W);
  } else if (hasExtension(path, ".vti")) {
    writeVti(path, toDenseVolume(map));
  } else {
    failUnknownMapExtension(path);
  }
}

void writeMap(const std::string& path, const SubmapGraph& saved, const PlaceMemory* places,
              const std::optional<Eigen::Isometry3d>& T_map_W) {
  if (saved.observesNothing()) throwFileError(path, kNothingMappedYet);
  if (hasExtension(path, ".sdfmap")) {
    writeSubmaps(path, saved, places, T_map_W);
  } else if (hasExtension(path, ".vti")) {
    if (saved.submaps.size() == 1) return writeVti(path, toDenseVolume(*saved.submaps.front().map));
    writeVti(path, toDenseVolume(mergeSubmaps(saved.submaps)));
  } else {
    failUnknownMapExtension(path);
  }
}

bool readsAsDenseGrid(const std::string& path) { return hasExtension(path, ".vti"); }

LoadedMap loadMap(const std::string& path, bool compact_voxels, const PlaceMemoryConfig& places_config) {
  LoadedMap loaded;
  if (hasExtension(path, ".sdfmap")) {
    SavedMap saved = readSubmaps(path);
    refuseEmpty(path, saved.submaps.observesNothing());
    if (saved.places) {
      PlaceMemoryConfig config = places_config;
      config.descriptor = saved.places->descriptor;
      config.max_keyframes = std::max<int>(config.max_keyframes, static_cast<int>(saved.places->keyframes.size()));
      loaded.places = std::make_unique<PlaceMemory>(config);
      for (Keyframe& keyframe : saved.places->keyframes) loaded.places->add(std::move(keyframe));
    }
    loaded.submaps = std::move(saved.submaps);
    loaded.T_map_W = saved.T_map_W;
    return loaded;
  }
  if (readsAsDenseGrid(path)) {
    auto map = std::make_unique<TsdfVolume>(readVti(path, compact_voxels));
    refuseEmpty(path, map->observesNothing());
    loaded.submaps.submaps.push_back(Submap{std::move(map), SubmapPlace()});
    return loaded;
  }
  failUnknownMapExtension(path);
}

std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels, std::unique_ptr<PlaceMemory>* places,
                                 const PlaceMemoryConfig& places_config, std::optional<Eigen::Isometry3d>* T_map_W) {
  LoadedMap loaded = loadMap(path, compact_voxels, places_config);
  if (places) {
    places->reset();
    if (loaded.places) *places = loaded.submaps.placesInMapFrame(*loaded.places);
  }
  if (T_map_W) *T_map_W = loaded.T_map_W;
  return mergeSubmaps(std::move(loaded.submaps.submaps));
}

std::string describeLoadedColour(const TsdfMap& map, bool colour_on) {
  if (!colour_on || map.holdsColour()) return "";
  return "holds no colour (a .sdfmap before format version 4, or a map made without colour): what it holds shows "
         "grey until the camera sees it in colour";
}

std::string describeLoadedSubmaps(const SubmapGraph& saved, const PipelineConfig& config) {
  if (saved.submaps.size() <= 1) return "";
  const auto loops = std::count_if(saved.edges.begin(), saved.edges.end(),
                                   [](const PoseEdge& edge) { return edge.kind == PoseEdgeKind::kLoop; });
  const std::string held = "holds " + std::to_string(saved.submaps.size()) + " submaps joined by " +
                           std::to_string(saved.edges.size()) + " edges (" + std::to_string(loops) +
                           " of them places found again: loops, and where later sessions joined)";
  if (SdfPipeline::keepsSubmaps(config, saved)) {
    return held + ": kept as submaps; the submap where the camera is found joins their pose graph";
  }
  return held + ": merged into one map, as " +
         (config.submaps.enabled() ? std::string("Relocalise=false (no search to find the camera in them)")
                                   : std::string("SubmapSize=0 (one map)")) +
         " makes it";
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
