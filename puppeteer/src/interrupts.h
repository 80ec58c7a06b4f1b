// SPDX-License-Identifier: MIT
// Ctrl-C and SIGTERM as a request to finish: long-running commands (record, sim, the live app) poll the flag and
// close what they have open (a take gets its END record) instead of being killed mid-write.
#pragma once

namespace imps::app {

// Installs handlers for SIGINT and SIGTERM that only set the flag, and clears it. Call from the main thread before
// the loop that polls interruptRequested().
void catchInterrupts();
// True once SIGINT or SIGTERM arrived after catchInterrupts(). Async-signal-safe to set, cheap to read.
bool interruptRequested();

}  // namespace imps::app
