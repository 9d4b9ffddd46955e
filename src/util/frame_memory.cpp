#include "sdf_tracker/util/frame_memory.h"

#if __has_include(<malloc.h>)
#include <malloc.h>
#endif

namespace sdf_tracker {

bool keepFrameMemoryResident() {
#if defined(M_MMAP_THRESHOLD) && defined(M_TRIM_THRESHOLD)  // glibc's mallopt()
  // 32 MiB is the largest threshold glibc accepts; the dense grid (128 MiB) is still mapped on its own.
  constexpr int kLargestHeapBuffer = 32 << 20;
  constexpr int kFreeHeapKept = 128 << 20;
  const bool mmap_set = mallopt(M_MMAP_THRESHOLD, kLargestHeapBuffer) == 1;
  const bool trim_set = mallopt(M_TRIM_THRESHOLD, kFreeHeapKept) == 1;
  return mmap_set && trim_set;
#else
  return false;
#endif
}

}  // namespace sdf_tracker
