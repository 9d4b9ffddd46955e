#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/core/camera.h"
#include "sdf_tracker/core/depth_image.h"
#include "sdf_tracker/core/sparse_tsdf_map.h"
#include "sdf_tracker/core/surface.h"
#include "sdf_tracker/core/tsdf_volume.h"

/// File input and output of the core. Every function throws std::runtime_error naming the file
/// and what is wrong with it; writers write a temporary file and rename it into place, so a
/// failed write never leaves a half-written file under the final name.
namespace sdf_tracker::io {

/// What a PNG's header says, read without decoding the image.
struct PngHeader {
  int width = 0;
  int height = 0;
  int bit_depth = 0;
  int colour_type = 0;  ///< 0 grey, 2 RGB, 3 palette, 4 grey + alpha, 6 RGBA
  std::string describe() const;  ///< "16-bit RGB"
};
/// Reads the signature and IHDR chunk; throws std::runtime_error for anything else.
PngHeader readPngHeader(const std::string& path);

/// A 16-bit single-channel (greyscale) PNG; metres = value / depth_factor, 0 = no measurement.
/// The header is checked before anything is decoded: other formats (RGB, grey + alpha, 8-bit)
/// are refused, not converted, and so is a size other than expected_width x expected_height
/// (when given) or one beyond kMaxImagePixels.
DepthImage readDepthPng(const std::string& path, double depth_factor, int expected_width = 0,
                        int expected_height = 0);
/// No depth image larger than this is decoded (a 4096 x 4096 image, 32 MiB of 16-bit depth).
constexpr long long kMaxImagePixels = 4096LL * 4096LL;
void writeDepthPng(const std::string& path, const DepthImage& depth, double depth_factor);

/// Binary little-endian PLY with normals.
void writePly(const std::string& path, const SurfaceCloud& cloud);
void writePly(const std::string& path, const TriangleMesh& mesh);
/// Wavefront OBJ, as the reference release's triangles.obj.
void writeObj(const std::string& path, const TriangleMesh& mesh);
/// A mesh file chosen by its extension: Wavefront OBJ for a .obj path, binary PLY for any other.
void writeMesh(const std::string& path, const TriangleMesh& mesh);
/// Reads a PLY written by writePly(mesh) (binary or ASCII vertices x y z and triangle faces).
TriangleMesh readPlyMesh(const std::string& path);

/// VTK XML ImageData (.vti) with point arrays "distance" and "weight", which ParaView opens.
void writeVti(const std::string& path, const TsdfVolume& volume);
/// Validates dimensions, spacing, origin, array sizes and values before building the volume,
/// stored compactly when asked.
TsdfVolume readVti(const std::string& path, bool compact_voxels = false);

/// This package's own binary map (.sdfmap): every block of a sparse map, exactly, behind a header
/// with a format version and the map's geometry, and followed by a checksum. Little-endian:
///   "SDFTMAP\n", u32 version (1), u32 block side (8), f64 voxel size [m], f64 positive truncation
///   [m], f64 x3 origin [m], u64 block count; per block i32 x3 block index and kBlockSide^3 voxels
///   of f32 distance [m], f32 weight (x fastest); u64 FNV-1a hash of every byte before it.
void writeSparseMap(const std::string& path, const SparseTsdfMap& map);
/// Checks the header, the file's length against the block count (before allocating anything),
/// every block index (in reach, no repeats), every voxel (finite distance, finite weight >= 0)
/// and the checksum; the map is returned only when all of it holds.
SparseTsdfMap readSparseMap(const std::string& path);

/// A map file chosen by its extension: .sdfmap (writeSparseMap; a dense grid is stored as its
/// observed blocks, and read back sparse) or .vti (writeVti; a sparse map as the box around its
/// blocks, read back dense). Other extensions are refused, naming the path.
void writeMap(const std::string& path, const TsdfMap& map);
std::unique_ptr<TsdfMap> readMap(const std::string& path, bool compact_voxels = false);

/// A timestamped camera-to-world pose.
struct StampedPose {
  double timestamp_s;
  Eigen::Isometry3d T_W_C;
};

/// TUM trajectory format: "timestamp tx ty tz qx qy qz qw" per line, '#' comments.
void writeTrajectory(const std::string& path, const std::vector<StampedPose>& poses);
std::vector<StampedPose> readTrajectory(const std::string& path);

/// Creates a directory and any missing parents (like mkdir -p).
void makeDirectories(const std::string& path);

/// Writes text atomically (temporary file + rename).
void writeTextFile(const std::string& path, const std::string& text);

/// Removes the temporary file a writer of `path` left when its process was killed mid-write;
/// true when there was one.
bool removeStaleTemporary(const std::string& path);

}  // namespace sdf_tracker::io
