#pragma once

#include <atomic>
#include <memory>

#include <omp.h>

namespace sdf_tracker {

/// Runs work(stretch) once for every stretch in [0, count) on the OpenMP threads. Each thread
/// first takes the stretches of its own share, in order: the same share on every call, so that
/// a loop run again and again (the tracker's iterations) finds what its share read still in that
/// core's cache, as a static split would. A thread that has finished its share then takes the
/// stretches the others have not begun, from the far end of their shares: when the system gives
/// a thread's core to other work (a loop search, a merge, rosbag, rviz), the call is late by a
/// stretch, not by that thread's whole share.
template <typename Work>
void forEachStretch(int count, const Work& work) {
  // A cache line per flag: the threads' claims do not contend for one line.
  struct alignas(64) Claim {
    std::atomic<bool> taken{false};
  };
  const std::unique_ptr<Claim[]> claims(new Claim[static_cast<size_t>(count)]);
#pragma omp parallel
  {
    const int threads = omp_get_num_threads(), thread = omp_get_thread_num();
    const int end = count * (thread + 1) / threads;
    for (int stretch = count * thread / threads; stretch < end; ++stretch) {
      if (!claims[stretch].taken.exchange(true)) work(stretch);
    }
    for (int stretch = count - 1; stretch >= 0; --stretch) {
      if (!claims[stretch].taken.exchange(true)) work(stretch);
    }
  }
}

}  // namespace sdf_tracker
