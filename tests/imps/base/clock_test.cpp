// SPDX-License-Identifier: MIT
// The clock (imps/base/include/imps/clock.h): steadyNowNs is std::chrono::steady_clock in nanoseconds, SteadyClock
// reads it, ManualClock moves only when told and records every sleep.
#include "imps/clock.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

namespace imps {
namespace {

int64_t chronoNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

TEST(SteadyNowNs, IsTheSteadyClockInNanoseconds) {
  // Bracketed by steady_clock readings: same epoch, same unit (a unit or epoch error would miss by orders of
  // magnitude), and no sleep needed.
  for (int i = 0; i < 1000; ++i) {
    const int64_t before = chronoNowNs();
    const int64_t now = steadyNowNs();
    const int64_t after = chronoNowNs();
    ASSERT_LE(before, now);
    ASSERT_LE(now, after);
  }
}

TEST(SteadyNowNs, NeverDecreasesWithinAThread) {
  std::vector<std::thread> threads;
  std::vector<int> decreases(4, 0);
  for (size_t t = 0; t < decreases.size(); ++t)
    threads.emplace_back([&, t] {
      int64_t last = steadyNowNs();
      for (int i = 0; i < 100000; ++i) {
        const int64_t now = steadyNowNs();
        decreases[t] += now < last;
        last = now;
      }
    });
  for (std::thread& t : threads) t.join();
  for (int d : decreases) EXPECT_EQ(d, 0);
}

TEST(SteadyClock, ReadsSteadyNowNsAndSleepsUntilTheTargetHasPassed) {
  SteadyClock clock;
  Clock& c = clock;
  const int64_t before = steadyNowNs();
  const int64_t now = c.nowNs();
  EXPECT_LE(before, now);
  EXPECT_LE(now, steadyNowNs());
  const int64_t target = now + 2'000'000;  // 2 ms ahead
  c.sleepUntilNs(target);
  EXPECT_GE(c.nowNs(), target);
  c.sleepUntilNs(0);  // long past: returns
}

TEST(ManualClock, StartsWhereToldAndMovesOnlyByHand) {
  ManualClock clock(1000);
  EXPECT_EQ(clock.nowNs(), 1000);
  EXPECT_EQ(clock.nowNs(), 1000);
  clock.advance(250);
  EXPECT_EQ(clock.nowNs(), 1250);
  clock.set(5000);
  EXPECT_EQ(clock.nowNs(), 5000);
  EXPECT_EQ(ManualClock().nowNs(), 0);
  EXPECT_TRUE(clock.sleeps().empty());
}

TEST(ManualClock, SleepingJumpsForwardNeverBackAndIsRecorded) {
  ManualClock clock(100);
  Clock& c = clock;
  c.sleepUntilNs(400);
  EXPECT_EQ(c.nowNs(), 400);
  c.sleepUntilNs(300);  // already passed: time stays
  EXPECT_EQ(c.nowNs(), 400);
  c.sleepUntilNs(400);
  EXPECT_EQ(c.nowNs(), 400);
  c.sleepUntilNs(1000);
  EXPECT_EQ(c.nowNs(), 1000);
  EXPECT_EQ(clock.sleeps(), (std::vector<int64_t>{400, 300, 400, 1000}));
}

}  // namespace
}  // namespace imps
