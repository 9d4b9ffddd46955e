#pragma once

#include <string>

#include "sdf_tracker/map/sparse_tsdf_map.h"

/// This package's own binary map (.sdfmap): every block of a sparse map, exactly, behind a header
/// with a format version and the map's geometry, and followed by a checksum. Little-endian:
///   "SDFTMAP\n", u32 version (1), u32 block side (8), f64 voxel size [m], f64 positive truncation
///   [m], f64 x3 origin [m], u64 block count; per block i32 x3 block index and kBlockSide^3 voxels
///   of f32 distance [m], f32 weight (x fastest); u64 FNV-1a hash of every byte before it.
namespace sdf_tracker::io {

void writeSparseMap(const std::string& path, const SparseTsdfMap& map);
/// Checks the header, the file's length against the block count (before allocating anything),
/// every block index (in reach, no repeats), every voxel (finite distance, finite weight >= 0)
/// and the checksum; the map is returned only when all of it holds.
SparseTsdfMap readSparseMap(const std::string& path);

}  // namespace sdf_tracker::io
