#include "sdf_tracker/util/memory.h"

#include <sys/resource.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace sdf_tracker {

namespace {

constexpr uint64_t kUnlimited = std::numeric_limits<uint64_t>::max();

/// The value of a "Name: <n> kB" line of a /proc file, in bytes, or kUnlimited.
uint64_t procValueBytes(const char* file, const std::string& name) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, name.size() + 1, name + ":") != 0) continue;
    std::istringstream words(line.substr(name.size() + 1));
    uint64_t kib = 0;
    if (words >> kib) return kib * 1024;
  }
  return kUnlimited;
}

/// The first number in a file, or kUnlimited (no file, "max").
uint64_t fileNumber(const char* file) {
  std::ifstream in(file);
  uint64_t value = 0;
  return in >> value ? value : kUnlimited;
}

}  // namespace

uint64_t availableMemoryBytes() {
  uint64_t available = procValueBytes("/proc/meminfo", "MemAvailable");
  struct rlimit limit;
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
    const uint64_t used = procValueBytes("/proc/self/status", "VmSize");
    const uint64_t cap = static_cast<uint64_t>(limit.rlim_cur);
    available = std::min(available, used != kUnlimited && used < cap ? cap - used : 0);
  }
  const uint64_t cgroup_max = fileNumber("/sys/fs/cgroup/memory.max");
  const uint64_t cgroup_used = fileNumber("/sys/fs/cgroup/memory.current");
  if (cgroup_max != kUnlimited && cgroup_used != kUnlimited) {
    available = std::min(available, cgroup_used < cgroup_max ? cgroup_max - cgroup_used : 0);
  }
  return available;
}

void requireMemory(uint64_t bytes, const std::string& what, uint64_t available_bytes) {
  if (bytes <= available_bytes) return;
  std::ostringstream s;
  s << what << " needs " << (bytes >> 20) << " MiB of memory, but " << (available_bytes >> 20) << " MiB are available";
  throw std::runtime_error(s.str());
}

}  // namespace sdf_tracker
