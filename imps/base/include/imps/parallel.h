// SPDX-License-Identifier: MIT
// The one threading layer: every parallel loop in the project goes through here (oneTBB underneath).
//
// Determinism contract: parallelFor calls body(i) exactly once for every i in [0, n), in an unspecified order and
// on unspecified threads. Algorithms that write per-index outputs and merge them in index order therefore produce
// identical results for 1 thread and for N threads.
#pragma once

#include <cstddef>
#include <functional>

namespace imps {

// The most worker threads any loop runs on (the command line's --threads and a scene's numThreads are bounded by
// it too): a larger request is a mistake, and oneTBB fails on arenas of millions of threads.
inline constexpr int kMaxThreads = 1024;

// Number of worker threads for a requested count: `requested` (at most kMaxThreads) if > 0, else the machine's
// hardware concurrency.
int resolveThreads(int requested);

// Runs body(i) for i in [0, n) on up to `threads` threads (0 = all cores). Returns when every call has returned.
// `grain` is the smallest number of consecutive indices given to one task.
void parallelFor(size_t n, int threads, const std::function<void(size_t)>& body, size_t grain = 1);

// parallelFor that also tells the body which worker runs it: body(i, worker) with worker in
// [0, resolveThreads(threads)), and no two calls running at the same time share a worker number. For scratch memory
// owned by the caller, one slot per worker (instead of thread_local storage that lives as long as the process).
void parallelForWorkers(size_t n, int threads, const std::function<void(size_t, int)>& body, size_t grain = 1);

}  // namespace imps
