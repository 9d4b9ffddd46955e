// Fuzz target: sdf_tracker binary maps (io::readSubmaps): submaps, graph, place memory.
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/sdfmap_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sdf_tracker::fuzz::writeInput(data, size, "map.sdfmap");
  try {
    sdf_tracker::io::readSubmaps(path);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
