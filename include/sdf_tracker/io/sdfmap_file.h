#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/places/place_memory.h"

/// This package's own binary map (.sdfmap): every block of a sparse map, exactly, the place
/// memory it was built with and the frame it was shown in, behind a header with a format version
/// and the map's geometry, and followed by a checksum. Little-endian:
///   "SDFTMAP\n", u32 version (4), u32 block side (8), f64 voxel size [m], f64 positive truncation
///   [m], f64 x3 origin [m], u64 block count; (version 2 on) u64 keyframe count, i32 descriptor
///   grid width, height, fern count, tests per fern, u64 seed, f64 min and max test depth [m];
///   (version 3) u64 1 when a map frame follows (else 0), its f64 x3 position [m] and f64 x4
///   orientation (qx qy qz qw); (version 4) u64 1 when the map holds colour (else 0); per block
///   i32 x3 block index and kBlockSide^3 voxels of f32 distance [m], f32 weight (x fastest), and
///   with colour kBlockSide^3 colours of u8 red, green, blue, weight; (version 2 on) per keyframe
///   f64 x3 position [m], f64 x4 orientation and one u8 code per fern; u64 FNV-1a hash of every
///   byte before it.
/// Versions 1 (no place memory), 2 (no map frame) and 3 (no colour) are still read.
namespace sdf_tracker::io {

/// The place memory as a map file keeps it.
struct SavedPlaces {
  PlaceDescriptorConfig descriptor;
  std::vector<Keyframe> keyframes;
};

/// Writes version 4 (with the map's colour when it holds colour) with `places`' keyframes (none: an empty place memory) and the map frame
/// `T_map_W` (the pose of the map's world in the frame a node published it in, levelled with
/// gravity: a second session publishes in the same frame), when there is one.
void writeSparseMap(const std::string& path, const SparseTsdfMap& map, const PlaceMemory* places = nullptr,
                    const std::optional<Eigen::Isometry3d>& T_map_W = std::nullopt);
/// Checks the header, the file's length against the block and keyframe counts (before allocating
/// anything), every block index (in reach, no repeats), every voxel (finite distance, finite
/// weight >= 0), every keyframe (finite position, unit quaternion, codes of the fern's bits) and
/// the map frame (a unit quaternion, a finite position) and the checksum; the map is returned
/// only when all of it holds. `places`, when given, receives the saved place memory, and nothing
/// for a version 1 file (which has none); `T_map_W` the saved map frame, and nothing when none was
/// saved (a version 1 or 2 file, or a map no node published).
SparseTsdfMap readSparseMap(const std::string& path, std::optional<SavedPlaces>* places = nullptr,
                            std::optional<Eigen::Isometry3d>* T_map_W = nullptr);

}  // namespace sdf_tracker::io
