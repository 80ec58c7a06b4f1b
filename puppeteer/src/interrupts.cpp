// SPDX-License-Identifier: MIT
// Ctrl-C and SIGTERM as a request to finish (see interrupts.h).
#include "interrupts.h"

#include <atomic>
#include <csignal>

namespace imps::app {
namespace {
std::atomic<bool> interrupted{false};
void onSignal(int) { interrupted.store(true); }
}  // namespace

void catchInterrupts() {
  interrupted.store(false);
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
}

bool interruptRequested() { return interrupted.load(); }

}  // namespace imps::app
