// SPDX-License-Identifier: MIT
#include "imps/clock.h"

#include <algorithm>
#include <chrono>
#include <thread>

namespace imps {

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

void SteadyClock::sleepUntilNs(int64_t timeNs) {
  std::this_thread::sleep_until(std::chrono::steady_clock::time_point(std::chrono::nanoseconds(timeNs)));
}

void ManualClock::sleepUntilNs(int64_t timeNs) {
  sleeps_.push_back(timeNs);
  now_ = std::max(now_, timeNs);
}

}  // namespace imps
