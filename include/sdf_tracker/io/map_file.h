#pragma once

#include <memory>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/pipeline/pipeline.h"
#include "sdf_tracker/pipeline/submaps.h"
#include "sdf_tracker/places/place_memory.h"

namespace sdf_tracker::io {

/// A map file chosen by its extension: .sdfmap (writeSparseMap, with the place memory; a dense
/// grid is stored as its observed blocks, and read back sparse) or .vti (writeVti; a sparse map
/// as the box around its blocks, read back dense; no place memory). Other extensions are refused,
/// naming the path. `T_map_W`, the frame the map is published in (writeSparseMap), is kept by a
/// .sdfmap only.
void writeMap(const std::string& path, const TsdfMap& map, const PlaceMemory* places = nullptr,
              const std::optional<Eigen::Isometry3d>& T_map_W = std::nullopt);
/// writeMap() of a session's submaps and graph (SdfPipeline::copySubmaps): a .sdfmap keeps them
/// (writeSubmaps), with `places`' keyframes in their submaps' frames; a .vti holds them merged
/// where the graph placed them.
void writeMap(const std::string& path, const SubmapGraph& saved, const PlaceMemory* places = nullptr,
              const std::optional<Eigen::Isometry3d>& T_map_W = std::nullopt);

/// A map file as a session takes it up (SdfPipeline::setSubmaps).
struct LoadedMap {
  /// A .sdfmap's submaps and graph (one submap before format version 5); a .vti's grid as the one
  /// submap.
  SubmapGraph submaps;
  /// The place memory, each keyframe in its submap's frame: its descriptor as saved, the rest of
  /// its settings as given; nullptr when the file holds none (a .vti, a version 1 .sdfmap).
  std::unique_ptr<PlaceMemory> places;
  /// The saved map frame, or nothing (a .vti, a .sdfmap before version 3, one saved without).
  std::optional<Eigen::Isometry3d> T_map_W;
};
/// Reads a .sdfmap or a .vti, refusing an empty map; other extensions are refused, naming the
/// path.
LoadedMap loadMap(const std::string& path, bool compact_voxels = false,
                  const PlaceMemoryConfig& places_config = PlaceMemoryConfig());

/// loadMap() as one map: the submaps merged where the graph placed them.
/// `places`, when given, receives the file's place memory (its descriptor as saved, the rest of
/// its settings from `places_config`), or nullptr when the file holds none (a .vti, a version 1
/// .sdfmap), its keyframes in the map frame; `T_map_W` the saved map frame, or nothing (a .vti, a .sdfmap before version 3, one
/// saved without).
std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels = false,
                                 std::unique_ptr<PlaceMemory>* places = nullptr,
                                 const PlaceMemoryConfig& places_config = PlaceMemoryConfig(),
                                 std::optional<Eigen::Isometry3d>* T_map_W = nullptr);

/// Whether readMap() reads `path` as a dense grid (a .vti), which holds no submaps: what the
/// settings must know before the map is loaded.
bool readsAsDenseGrid(const std::string& path);

/// What a loaded map's place memory (readMap's `places`: none, or with its keyframes) brings for
/// finding the camera in it, said after the file's name: "holds 12 keyframes in its place memory:
/// the camera is searched for in it, ...", or that it holds none and why, and what Relocalise
/// then does.
std::string describeLoadedPlaces(const PlaceMemory* places, bool relocalise);

/// What becomes of a loaded map's submaps (SdfPipeline::keepsSubmaps), said after the file's
/// name: "" for one; "holds 40 submaps joined by 41 edges (1 loop): kept as submaps, ..." or why
/// they are merged into one map.
std::string describeLoadedSubmaps(const SubmapGraph& saved, const PipelineConfig& config);

/// With Colour on, what a loaded map without colour (a .sdfmap before version 4, a map saved
/// without colour, a .vti without the colour array) means, said once after the file's name:
/// "holds no colour ...: what it holds shows grey until the camera sees it in colour"; "" when
/// the map holds colour or Colour is off.
std::string describeLoadedColour(const TsdfMap& map, bool colour_on);

}  // namespace sdf_tracker::io
