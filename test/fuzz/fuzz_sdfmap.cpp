// Fuzz target: sdf_tracker binary maps (io::readSparseMap), with their place memory.
#include <optional>
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/sdfmap_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sdf_tracker::fuzz::writeInput(data, size, "map.sdfmap");
  try {
    std::optional<sdf_tracker::io::SavedPlaces> places;
    sdf_tracker::io::readSparseMap(path, &places);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
