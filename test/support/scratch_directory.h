#pragma once

// Scratch folders for tests, removed when the test binary ends with every test passed.

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace sdf_tracker::test {

namespace scratch_detail {
struct Registry {
  std::mutex mutex;
  std::vector<std::string> directories;
};
inline Registry& registry() {
  static Registry made;
  return made;
}
}  // namespace scratch_detail

/// A fresh, unique scratch directory under the system temp folder ($TMPDIR, else /tmp), named
/// sdf_tracker_<name>_XXXXXX; removeScratchDirectories() removes it at the end of the run.
inline std::string scratchDirectory(const std::string& name) {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/sdf_tracker_" + name + "_XXXXXX";
  if (!mkdtemp(pattern.data())) throw std::runtime_error("cannot create a scratch directory like " + pattern);
  scratch_detail::Registry& made = scratch_detail::registry();
  std::lock_guard<std::mutex> lock(made.mutex);
  made.directories.push_back(pattern);
  return pattern;
}

/// At the end of a test binary (its main, after RUN_ALL_TESTS): every scratch directory it made
/// is removed when all its tests passed (a run leaves nothing behind), and kept for inspection,
/// with a line naming them, when one failed.
inline void removeScratchDirectories(bool all_passed) {
  scratch_detail::Registry& made = scratch_detail::registry();
  std::lock_guard<std::mutex> lock(made.mutex);
  if (!all_passed && !made.directories.empty()) {
    std::cout << "[ scratch  ] a test failed: its scratch directories are kept for inspection:";
    for (const std::string& directory : made.directories) std::cout << ' ' << directory;
    std::cout << '\n';
    return;
  }
  for (const std::string& directory : made.directories) {
    std::error_code error;
    std::filesystem::remove_all(directory, error);
    if (error) std::cout << "[ scratch  ] could not remove " << directory << ": " << error.message() << '\n';
  }
  made.directories.clear();
}

}  // namespace sdf_tracker::test
