// Fuzz target: PLY meshes (io::readPlyMesh), binary and ASCII.
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/mesh_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sdf_tracker::fuzz::writeInput(data, size, "mesh.ply");
  try {
    sdf_tracker::io::readPlyMesh(path);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
