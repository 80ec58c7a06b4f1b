// SPDX-License-Identifier: MIT
// The threading layer (imps/base/include/imps/parallel.h): every index once, worker numbers for per-worker scratch.
#include "imps/parallel.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <thread>
#include <vector>

namespace imps {
namespace {

TEST(Parallel, ParallelForVisitsEveryIndexOnce) {
  for (int threads : {1, 2, 0})
    for (size_t n : {size_t(0), size_t(1), size_t(1000)}) {
      std::vector<std::atomic<int>> visits(n);
      parallelFor(n, threads, [&](size_t i) { ++visits[i]; });
      for (size_t i = 0; i < n; ++i) ASSERT_EQ(visits[i], 1) << "index " << i << " threads " << threads;
    }
}

TEST(Parallel, ResolveThreadsHonoursARequestUpToTheCapAndElseTakesTheMachine) {
  const int machine = std::max(1, int(std::thread::hardware_concurrency()));
  EXPECT_EQ(resolveThreads(1), 1);
  EXPECT_EQ(resolveThreads(7), 7);
  EXPECT_EQ(resolveThreads(kMaxThreads), kMaxThreads);
  EXPECT_EQ(resolveThreads(kMaxThreads + 1), kMaxThreads);
  EXPECT_EQ(resolveThreads(1 << 30), kMaxThreads);
  EXPECT_EQ(resolveThreads(0), machine);
  EXPECT_EQ(resolveThreads(-3), machine);
}

TEST(Parallel, AGrainStillVisitsEveryIndexOnceAndPerIndexOutputsMatchOneThread) {
  const size_t n = 4099;  // not a multiple of the grain
  std::vector<double> one(n), many(n);
  auto f = [](size_t i) { return double(i) * 0.5 + double(i % 13); };
  parallelFor(n, 1, [&](size_t i) { one[i] = f(i); }, 64);
  std::vector<std::atomic<int>> visits(n);
  parallelFor(n, 4, [&](size_t i) {
    ++visits[i];
    many[i] = f(i);
  }, 64);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(visits[i], 1) << "index " << i;
  EXPECT_EQ(one, many);
}

TEST(Parallel, WorkersAreNumberedBelowTheThreadCountAndNeverShared) {
  for (int threads : {1, 2, 3, 0}) {
    const int workers = resolveThreads(threads);
    const size_t n = 20000;
    std::vector<std::atomic<int>> visits(n);
    auto busy = std::make_unique<std::atomic<int>[]>(size_t(workers));
    std::atomic<int> badNumber{0}, shared{0};
    parallelForWorkers(n, threads, [&](size_t i, int worker) {
      if (worker < 0 || worker >= workers) {
        ++badNumber;
        return;
      }
      // A worker's scratch is used by one call at a time: nobody else may hold this number now.
      if (busy[size_t(worker)].exchange(1) != 0) ++shared;
      volatile double x = 0.0;
      for (int k = 0; k < 200; ++k) x = x + double(i * size_t(k));
      ++visits[i];
      busy[size_t(worker)] = 0;
    });
    EXPECT_EQ(badNumber, 0) << threads;
    EXPECT_EQ(shared, 0) << threads;
    for (size_t i = 0; i < n; ++i) ASSERT_EQ(visits[i], 1) << "index " << i;
  }
}

}  // namespace
}  // namespace imps
