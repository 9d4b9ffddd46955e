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

}  // namespace

void writeMap(const std::string& path, const TsdfMap& map, const PlaceMemory* places) {
  if (hasExtension(path, ".sdfmap")) {
    if (map.type() == MapType::kSparse) writeSparseMap(path, static_cast<const SparseTsdfMap&>(map), places);
    else writeSparseMap(path, toSparseMap(map), places);
  } else if (hasExtension(path, ".vti")) {
    writeVti(path, toDenseVolume(map));
  } else {
    failUnknownMapExtension(path);
  }
}

std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels, std::unique_ptr<PlaceMemory>* places,
                                 const PlaceMemoryConfig& places_config) {
  if (places) places->reset();
  if (hasExtension(path, ".sdfmap")) {
    std::optional<SavedPlaces> saved;
    auto map = std::make_unique<SparseTsdfMap>(readSparseMap(path, places ? &saved : nullptr));
    if (places && saved) {
      PlaceMemoryConfig config = places_config;
      config.descriptor = saved->descriptor;
      config.max_keyframes = std::max<int>(config.max_keyframes, static_cast<int>(saved->keyframes.size()));
      *places = std::make_unique<PlaceMemory>(config);
      for (Keyframe& keyframe : saved->keyframes) (*places)->add(std::move(keyframe));
    }
    return map;
  }
  if (hasExtension(path, ".vti")) return std::make_unique<TsdfVolume>(readVti(path, compact_voxels));
  failUnknownMapExtension(path);
}

}  // namespace sdf_tracker::io
