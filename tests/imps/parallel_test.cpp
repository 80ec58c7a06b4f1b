// The threading layer (imps/include/imps/parallel.h): every index once, worker numbers for per-worker scratch.
#include "imps/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <memory>
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
