// Fuzz target: 16-bit depth PNGs (io::readDepthPng). Any input must give a depth image or a
// std::runtime_error, never a crash, a sanitizer report or an allocation beyond the size cap.
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/depth_png.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = sdf_tracker::fuzz::writeInput(data, size, "depth.png");
  try {
    sdf_tracker::io::readDepthPng(path, 5000.0);
  } catch (const std::runtime_error&) {
  }
  return 0;
}
