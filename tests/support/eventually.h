// SPDX-License-Identifier: MIT
// Polling for a condition set by another thread (a device session, a simulated armature).
#pragma once

#include <chrono>
#include <thread>

namespace imps {

// Polls done() every 2 ms until it holds (true) or timeoutMs pass (false). The condition is the assertion; the time
// is only a bound, generous so that a loaded machine does not fail a correct program.
template <class Done>
bool eventually(Done&& done, int timeoutMs = 10'000) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeoutMs);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

}  // namespace imps
