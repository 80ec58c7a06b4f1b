// SPDX-License-Identifier: MIT
// What a recorded session's samples say about the device link: outages (pauses), sequence numbers missing, and
// restarts of the device's numbering (reboots). `puppeteer info` prints it; the rate excludes the outages.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/session_file.h"

namespace imps::sim {

// A pause in the arrival of one device's samples.
struct SessionOutage {
  size_t afterSample = 0;  // index among that device's samples of the last sample before the pause
  int64_t startNs = 0;     // its arrival time, from the device's first sample
  int64_t lengthNs = 0;    // arrival of the next sample minus startNs' sample's arrival
  uint64_t missing = 0;    // sequence numbers skipped across the pause (0 after a restart)
  bool operator==(const SessionOutage&) const = default;
};

struct SessionLink {
  size_t samples = 0;
  int64_t spanNs = 0;    // first to last arrival (saturated to int64)
  double spanSeconds = 0.0;  // the same in seconds, exact for any two timestamps
  int64_t outageNs = 0;  // of which in outages
  uint64_t missing = 0;  // sequence numbers skipped anywhere (modulo 2^32, as the drivers count drops)
  uint64_t restarts = 0; // the sequence repeated or went backwards: the device restarted its numbering
  std::vector<SessionOutage> outages;
  // Samples per second while the device was sending: intervals between samples, outages excluded, over the time
  // they span. 0 with fewer than two such intervals.
  double rateHz() const;
};

// The link of device `device` of `session` (an index into session.devices). A pause is an outage when it is longer
// than both 100 ms and 20 times the median spacing of that device's samples (a scheduler or USB hiccup is not).
SessionLink analyzeSessionLink(const Session& session, size_t device);

}  // namespace imps::sim
