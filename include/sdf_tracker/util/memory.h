#pragma once

#include <cstdint>
#include <string>

namespace sdf_tracker {

/// How many bytes this process can still allocate: the least of the memory the system has
/// available (MemAvailable), what is left under the process's address-space limit (ulimit -v)
/// and what is left under its cgroup's memory limit. The first is always known on Linux; a limit
/// that is not set does not count.
uint64_t availableMemoryBytes();

/// Throws std::runtime_error("<what> needs <n> MiB of memory, but <m> MiB are available") when
/// `bytes` exceed `available_bytes`: asked before a large allocation, so that a file or a request
/// that claims too much is refused by name instead of ending the process with std::bad_alloc.
void requireMemory(uint64_t bytes, const std::string& what, uint64_t available_bytes = availableMemoryBytes());

}  // namespace sdf_tracker
