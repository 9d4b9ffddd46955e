#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/map/sparse_tsdf_map.h"
#include "sdf_tracker/pipeline/submaps.h"
#include "sdf_tracker/places/place_memory.h"

/// This package's own binary map (.sdfmap): every block of every submap, exactly, their places and
/// pose graph, the place memory they were built with and the frame they were shown in, behind a
/// header with a format version and the map's geometry, and followed by a checksum.
/// Little-endian:
///   "SDFTMAP\n", u32 version (5), u32 block side (8), f64 voxel size [m], f64 positive truncation
///   [m], f64 x3 origin [m], u64 block count (all submaps'); (version 2 on) u64 keyframe count,
///   i32 descriptor grid width, height, fern count, tests per fern, u64 seed, f64 min and max
///   test depth [m]; (version 3 on) u64 1 when a map frame follows (else 0), its f64 x3 position
///   [m] and f64 x4 orientation (qx qy qz qw); (version 4 on) u64 1 when the map holds colour
///   (else 0); (version 5) u64 submap count, u64 edge count, per submap its anchor T_W_anchor and
///   place T_map_W (each f64 x3 position, f64 x4 orientation), u64 its block count, i64 frames
///   fused, f64 path [m]; per edge i32 from, i32 to, u32 kind (0 odometry, 1 loop), u32 0, the
///   relative pose T_from_to and f64 x36 information (row-major); per block (submap after submap)
///   i32 x3 block index and kBlockSide^3 voxels of f32 distance [m], f32 weight (x fastest), and
///   with colour kBlockSide^3 colours of u8 red, green, blue, weight; (version 2 on) per keyframe
///   its pose in its submap's frame (f64 x3 position [m], f64 x4 orientation), one u8 code per
///   fern and (version 5) i32 its submap; u64 FNV-1a hash of every byte before it.
/// Versions 1 (no place memory), 2 (no map frame), 3 (no colour) and 4 (one map, no submaps)
/// are still read, as one submap.
namespace sdf_tracker::io {

/// The place memory as a map file keeps it.
struct SavedPlaces {
  PlaceDescriptorConfig descriptor;
  std::vector<Keyframe> keyframes;
};

/// Everything a .sdfmap holds.
struct SavedMap {
  /// The submaps and their graph: one submap and no edge for a map saved without submaps (and
  /// for every file before version 5); each keyframe's submap (0 before version 5).
  SubmapGraph submaps;
  /// The place memory, each keyframe in its submap's frame; none in a version 1 file.
  std::optional<SavedPlaces> places;
  /// The map frame (the pose of the map's frame in the one a node published it in, levelled with
  /// gravity: a second session publishes in the same frame); none when none was saved (a version
  /// 1 or 2 file, a map no node published).
  std::optional<Eigen::Isometry3d> T_map_W;
};

/// Writes version 5: `saved`'s submaps (a dense grid, alone, as its observed blocks), places and
/// edges, `places`' keyframes (in their submaps' frames, saved.keyframe_submaps; none: an empty
/// place memory) and the map frame `T_map_W`, when there is one. Throws std::runtime_error naming
/// the path for submaps that cannot be a map's (SubmapGraph::problem), or of different lattices.
void writeSubmaps(const std::string& path, const SubmapGraph& saved, const PlaceMemory* places = nullptr,
                  const std::optional<Eigen::Isometry3d>& T_map_W = std::nullopt);
/// writeSubmaps() of `map` as the one submap.
void writeSparseMap(const std::string& path, const SparseTsdfMap& map, const PlaceMemory* places = nullptr,
                    const std::optional<Eigen::Isometry3d>& T_map_W = std::nullopt);
/// Checks the header, the file's length against the block, submap, edge and keyframe counts
/// (before allocating anything), every submap (a place of unit quaternions and finite positions,
/// its share of the blocks), every edge (a pose, a symmetric positive definite information,
/// between submaps that exist; every submap joined to the first), every block index (in reach,
/// no repeats within its submap), every voxel (finite distance, finite weight >= 0), every
/// keyframe (finite position, unit quaternion, codes of the fern's bits, a submap that exists)
/// and the map frame (a unit quaternion, a finite position) and the checksum; the map is
/// returned only when all of it holds. Throws std::runtime_error naming the path and what is
/// wrong.
SavedMap readSubmaps(const std::string& path);
/// readSubmaps()' blocks as one map: the submaps merged where their graph placed them
/// (mergeSubmaps).
SparseTsdfMap readSparseMap(const std::string& path);

}  // namespace sdf_tracker::io
