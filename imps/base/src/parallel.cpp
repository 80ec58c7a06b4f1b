// SPDX-License-Identifier: MIT
// parallelFor on oneTBB, with an arena per thread count so callers can pin 1 vs N threads.
#include "imps/parallel.h"

#include "imps/check.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

namespace imps {

int resolveThreads(int requested) {
  if (requested > 0) return std::min(requested, kMaxThreads);
  const unsigned hw = std::thread::hardware_concurrency();
  return hw > 0 ? static_cast<int>(hw) : 1;
}

namespace {

// One arena per thread count, created once (creating one costs more than meshing a small character).
tbb::task_arena& arenaFor(int threads) {
  static std::mutex mutex;
  static std::map<int, std::unique_ptr<tbb::task_arena>> arenas;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = arenas[threads];
  if (!slot) {
    // An arena of t threads asks oneTBB for t - 1 workers. Its default limit is one fewer than the cores, and a
    // request above it is cut with a warning on stderr ("The number of workers is currently limited to …") that
    // no caller can act on. Raise the limit to the largest arena asked for (replacing the control: with several,
    // the lowest wins), so a requested thread count is honoured, silently.
    static std::unique_ptr<tbb::global_control> limit;
    const size_t wanted = std::max<size_t>(size_t(threads), std::thread::hardware_concurrency());
    if (!limit || tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) < wanted) {
      limit.reset();
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, wanted);
    }
    slot = std::make_unique<tbb::task_arena>(threads);
  }
  return *slot;
}

}  // namespace

void parallelFor(size_t n, int threads, const std::function<void(size_t)>& body, size_t grain) {
  const int t = resolveThreads(threads);
  if (t == 1 || n <= 1) {
    for (size_t i = 0; i < n; ++i) body(i);
    return;
  }
  arenaFor(t).execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) body(i);
    });
  });
}

void parallelForWorkers(size_t n, int threads, const std::function<void(size_t, int)>& body, size_t grain) {
  const int t = resolveThreads(threads);
  if (t == 1 || n <= 1) {
    for (size_t i = 0; i < n; ++i) body(i, 0);
    return;
  }
  // Inside the arena every thread holds one of its t slots, numbered from 0, for as long as it runs tasks there.
  arenaFor(t).execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, grain), [&](const tbb::blocked_range<size_t>& r) {
      const int worker = tbb::this_task_arena::current_thread_index();
      IMPS_CHECK(worker >= 0 && worker < t);
      for (size_t i = r.begin(); i != r.end(); ++i) body(i, worker);
    });
  });
}

}  // namespace imps
