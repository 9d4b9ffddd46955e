#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/places/place_memory.h"

/// This package's own binary map (.sdfmap): every block of a sparse map, exactly, and the place
/// memory it was built with, behind a header with a format version and the map's geometry, and
/// followed by a checksum. Little-endian:
///   "SDFTMAP\n", u32 version (2), u32 block side (8), f64 voxel size [m], f64 positive truncation
///   [m], f64 x3 origin [m], u64 block count; (version 2) u64 keyframe count, i32 descriptor grid
///   width, height, fern count, tests per fern, u64 seed, f64 min and max test depth [m];
///   per block i32 x3 block index and kBlockSide^3 voxels of f32 distance [m], f32 weight
///   (x fastest); (version 2) per keyframe f64 x3 position [m], f64 x4 orientation (qx qy qz qw)
///   and one u8 code per fern; u64 FNV-1a hash of every byte before it.
/// Version 1 (no place memory) is still read.
namespace sdf_tracker::io {

/// The place memory as a map file keeps it.
struct SavedPlaces {
  PlaceDescriptorConfig descriptor;
  std::vector<Keyframe> keyframes;
};

/// Writes version 2 with `places`' keyframes (none: an empty place memory).
void writeSparseMap(const std::string& path, const SparseTsdfMap& map, const PlaceMemory* places = nullptr);
/// Checks the header, the file's length against the block and keyframe counts (before allocating
/// anything), every block index (in reach, no repeats), every voxel (finite distance, finite
/// weight >= 0), every keyframe (finite position, unit quaternion, codes of the fern's bits) and
/// the checksum; the map is returned only when all of it holds. `places`, when given, receives
/// the saved place memory, and nothing for a version 1 file (which has none).
SparseTsdfMap readSparseMap(const std::string& path, std::optional<SavedPlaces>* places = nullptr);

}  // namespace sdf_tracker::io
