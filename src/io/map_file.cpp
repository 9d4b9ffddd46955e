#include "sdf_tracker/io/map_file.h"

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

void writeMap(const std::string& path, const TsdfMap& map) {
  if (hasExtension(path, ".sdfmap")) {
    if (map.type() == MapType::kSparse) writeSparseMap(path, static_cast<const SparseTsdfMap&>(map));
    else writeSparseMap(path, toSparseMap(map));
  } else if (hasExtension(path, ".vti")) {
    writeVti(path, toDenseVolume(map));
  } else {
    failUnknownMapExtension(path);
  }
}

std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels) {
  if (hasExtension(path, ".sdfmap")) return std::make_unique<SparseTsdfMap>(readSparseMap(path));
  if (hasExtension(path, ".vti")) return std::make_unique<TsdfVolume>(readVti(path, compact_voxels));
  failUnknownMapExtension(path);
}

}  // namespace sdf_tracker::io
