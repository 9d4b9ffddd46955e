// Fuzz target: the text files of a TUM-layout folder (depth.txt, groundtruth.txt, intrinsics.txt)
// read by TumSequence::open and then the first frame. The first byte picks the file the rest of
// the input replaces; the other two files and one depth PNG are valid.
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <stdexcept>

#include "fuzz_input.h"
#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/files.h"
#include "sdf_tracker/io/tum_sequence.h"

namespace {

std::string folder() {
  static const std::string dir = [] {
    const std::string d = "/tmp/sdf_tracker_fuzz_" + std::to_string(::getpid()) + "_tum";
    sdf_tracker::io::makeDirectories(d + "/depth");
    sdf_tracker::io::writeDepthPng(d + "/depth/1.png", sdf_tracker::DepthImage(8, 6, 1.5f), 5000.0);
    return d;
  }();
  return dir;
}

void write(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::trunc) << text; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string dir = folder();
  write(dir + "/depth.txt", "# timestamp filename\n1.0 depth/1.png\n");
  write(dir + "/groundtruth.txt", "1.0 0 0 0 0 0 0 1\n");
  write(dir + "/intrinsics.txt", "# fx fy cx cy width height depth_factor\n10 10 4 3 8 6 5000\n");
  static const char* kFiles[] = {"depth.txt", "groundtruth.txt", "intrinsics.txt"};
  write(dir + "/" + kFiles[data[0] % 3], std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    const sdf_tracker::TumSequence sequence = sdf_tracker::TumSequence::open(dir);
    if (sequence.size() > 0) sequence.depth(0);
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
