// SPDX-License-Identifier: MIT
// Time, in one place: the monotonic host clock every module stamps samples and measures timeouts on
// (std::chrono::steady_clock, in nanoseconds), and the Clock interface through which replays, simulated devices,
// the session writer's periodic flush and the drivers' arrival stamps read time, so tests can drive them by hand.
#pragma once

#include <cstdint>
#include <vector>

namespace imps {

// Nanoseconds on std::chrono::steady_clock. Thread-safe.
int64_t steadyNowNs();

// A source of time in nanoseconds on a monotonic timeline, and a way to wait for a point on it.
class Clock {
 public:
  virtual ~Clock() = default;
  // Current time in nanoseconds. Must never decrease.
  virtual int64_t nowNs() = 0;
  // Returns once nowNs() >= timeNs (at once if that time has passed).
  virtual void sleepUntilNs(int64_t timeNs) = 0;
};

// std::chrono::steady_clock (steadyNowNs). Thread-safe; stateless, so one instance may serve everything.
class SteadyClock final : public Clock {
 public:
  int64_t nowNs() override { return steadyNowNs(); }
  void sleepUntilNs(int64_t timeNs) override;
};

// A clock that moves only when told to: sleepUntilNs() jumps straight to the requested time (never backwards),
// advance() and set() move it by hand. Every sleep is recorded so tests can check the schedule. Not thread-safe.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(int64_t startNs = 0) : now_(startNs) {}
  int64_t nowNs() override { return now_; }
  void sleepUntilNs(int64_t timeNs) override;
  void advance(int64_t ns) { now_ += ns; }
  void set(int64_t timeNs) { now_ = timeNs; }
  const std::vector<int64_t>& sleeps() const { return sleeps_; }  // every target passed to sleepUntilNs

 private:
  int64_t now_;
  std::vector<int64_t> sleeps_;
};

}  // namespace imps
