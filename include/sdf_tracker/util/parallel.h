#pragma once

#include <atomic>
#include <cstdint>
#include <memory>

#include <omp.h>

namespace sdf_tracker {

/// Runs work(stretch) once for every stretch in [0, count) on the OpenMP threads. Each thread
/// first takes the stretches of its own share, in order: the same share on every call, so that a
/// loop run again and again (the tracker's iterations) may find what its share read still in
/// that core's cache, as with a static split. A thread that has finished its share then takes,
/// from the last stretch down, those no thread has begun: when the system gives a thread's core
/// to other work (a loop search, a merge, rosbag, rviz), the call is late by a stretch, not by
/// that thread's whole share. `work` must not throw (it runs in an OpenMP region).
template <typename Work>
void forEachStretch(int count, const Work& work) {
  if (count <= 0) return;
  // A cache line per flag: the threads' claims do not contend for one line.
  struct alignas(64) Claim {
    std::atomic<bool> taken{false};
  };
  const std::unique_ptr<Claim[]> claims(new Claim[static_cast<size_t>(count)]);
  const auto claim = [&claims](int stretch) {
    std::atomic<bool>& taken = claims[stretch].taken;
    return !taken.load(std::memory_order_relaxed) && !taken.exchange(true, std::memory_order_acq_rel);
  };
#pragma omp parallel
  {
    const int64_t threads = omp_get_num_threads(), thread = omp_get_thread_num();
    const int end = static_cast<int>(count * (thread + 1) / threads);
    for (int stretch = static_cast<int>(count * thread / threads); stretch < end; ++stretch) {
      if (claim(stretch)) work(stretch);
    }
    for (int stretch = count - 1; stretch >= 0; --stretch) {
      if (claim(stretch)) work(stretch);
    }
  }
}

}  // namespace sdf_tracker
