#pragma once

#include <memory>
#include <string>

#include "sdf_tracker/map/tsdf_map.h"
#include "sdf_tracker/places/place_memory.h"

namespace sdf_tracker::io {

/// A map file chosen by its extension: .sdfmap (writeSparseMap, with the place memory; a dense
/// grid is stored as its observed blocks, and read back sparse) or .vti (writeVti; a sparse map
/// as the box around its blocks, read back dense; no place memory). Other extensions are refused,
/// naming the path.
void writeMap(const std::string& path, const TsdfMap& map, const PlaceMemory* places = nullptr);
/// `places`, when given, receives the file's place memory (its descriptor as saved, the rest of
/// its settings from `places_config`), or nullptr when the file holds none (a .vti, a version 1
/// .sdfmap).
std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels = false,
                                 std::unique_ptr<PlaceMemory>* places = nullptr,
                                 const PlaceMemoryConfig& places_config = PlaceMemoryConfig());

}  // namespace sdf_tracker::io
