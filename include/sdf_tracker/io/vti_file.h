#pragma once

#include <string>

#include "sdf_tracker/map/tsdf_volume.h"

/// A dense grid as VTK XML ImageData (.vti), which ParaView opens.
namespace sdf_tracker::io {

/// Point arrays "distance" and "weight" (Float32), and when the grid holds colour "colour" (UInt8,
/// three components: red, green, blue) and "colour_weight" (UInt8); raw appended data.
void writeVti(const std::string& path, const TsdfVolume& volume);
/// Validates dimensions, spacing, origin, array sizes and values before building the volume,
/// stored compactly when asked; the colour arrays when the file has them.
TsdfVolume readVti(const std::string& path, bool compact_voxels = false);

}  // namespace sdf_tracker::io
