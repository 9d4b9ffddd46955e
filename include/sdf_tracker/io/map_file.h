#pragma once

#include <memory>
#include <string>

#include "sdf_tracker/map/tsdf_map.h"

namespace sdf_tracker::io {

/// A map file chosen by its extension: .sdfmap (writeSparseMap; a dense grid is stored as its
/// observed blocks, and read back sparse) or .vti (writeVti; a sparse map as the box around its
/// blocks, read back dense). Other extensions are refused, naming the path.
void writeMap(const std::string& path, const TsdfMap& map);
std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels = false);

}  // namespace sdf_tracker::io
