// Fuzz target: VTK ImageData volumes (io::readVti), into both voxel formats.
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/vti_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sdf_tracker::fuzz::writeInput(data, size, "volume.vti");
  try {
    sdf_tracker::io::readVti(path, size % 2 == 1);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
