#pragma once

#include <string>

#include "sdf_tracker/surface/surface.h"

/// Surfaces as files: binary PLY (clouds and meshes, with normals, and vertex colours when they
/// have them) and Wavefront OBJ (vertex colours as three more numbers on each vertex).
namespace sdf_tracker::io {

/// Binary little-endian PLY with normals.
void writePly(const std::string& path, const SurfaceCloud& cloud);
void writePly(const std::string& path, const TriangleMesh& mesh);
/// Wavefront OBJ, as the reference release's triangles.obj.
void writeObj(const std::string& path, const TriangleMesh& mesh);
/// A mesh file chosen by its extension: Wavefront OBJ for .obj, binary PLY for .ply; any other
/// extension is refused, naming the path (a PLY under another name would fool the next program).
void writeMesh(const std::string& path, const TriangleMesh& mesh);
/// Reads a PLY written by writePly(mesh) (binary or ASCII vertices x y z, optional uchar red green
/// blue, and triangle faces).
TriangleMesh readPlyMesh(const std::string& path);

}  // namespace sdf_tracker::io
