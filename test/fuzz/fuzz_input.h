#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

namespace sdf_tracker::fuzz {

/// The readers take paths: each input is written to a file of this process's own. After a crash
/// the file still holds the input that caused it.
inline std::string writeInput(const uint8_t* data, size_t size, const std::string& name) {
  const std::string path = "/tmp/sdf_tracker_fuzz_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace sdf_tracker::fuzz
