// SPDX-License-Identifier: MIT
// Outages, missing sequence numbers and restarts in a recorded session (see session_link.h).
#include "sim/session_link.h"

#include <algorithm>

namespace imps::sim {

namespace {
// b - a and a + b saturated to int64: timestamps read from a file may be anything.
int64_t difference(int64_t a, int64_t b) {
  int64_t d;
  return __builtin_sub_overflow(b, a, &d) ? (b > a ? INT64_MAX : INT64_MIN) : d;
}
int64_t sum(int64_t a, int64_t b) {
  int64_t d;
  return __builtin_add_overflow(a, b, &d) ? (b > 0 ? INT64_MAX : INT64_MIN) : d;
}
}  // namespace

double SessionLink::rateHz() const {
  const int64_t active = difference(outageNs, spanNs);
  const size_t intervals = samples > 1 ? samples - 1 - outages.size() : 0;
  return active > 0 && intervals > 0 ? double(intervals) / (double(active) * 1e-9) : 0.0;
}

SessionLink analyzeSessionLink(const Session& session, size_t device) {
  std::vector<size_t> samples;  // the device's samples, as indices into session.samples
  for (size_t i = 0; i < session.samples.size() && i < session.sampleDevice.size(); ++i)
    if (session.sampleDevice[i] == device) samples.push_back(i);
  auto arrival = [&](size_t k) { return session.samples.arrivalTimeNs(samples[k]); };
  SessionLink link;
  link.samples = samples.size();
  if (samples.size() < 2) return link;
  std::vector<int64_t> spacing;
  spacing.reserve(samples.size() - 1);
  for (size_t i = 1; i < samples.size(); ++i)
    spacing.push_back(difference(arrival(i - 1), arrival(i)));
  std::vector<int64_t> sorted = spacing;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const int64_t median = std::max<int64_t>(sorted[sorted.size() / 2], 0);
  const int64_t threshold = std::max<int64_t>(median > INT64_MAX / 20 ? INT64_MAX : 20 * median, 100'000'000);
  const int64_t first = arrival(0);
  link.spanNs = difference(first, arrival(samples.size() - 1));
  link.spanSeconds = (double(arrival(samples.size() - 1)) - double(first)) * 1e-9;  // exact for any two
  for (size_t i = 1; i < samples.size(); ++i) {
    const uint32_t delta =
        session.samples.sequence(samples[i]) - session.samples.sequence(samples[i - 1]);  // wrapping is not a gap
    uint64_t missing = 0;
    if (delta == 0 || delta > 0x80000000u)
      ++link.restarts;
    else
      missing = delta - 1;
    link.missing += missing;
    if (spacing[i - 1] > threshold) {
      link.outages.push_back({i - 1, difference(first, arrival(i - 1)), spacing[i - 1], missing});
      link.outageNs = sum(link.outageNs, spacing[i - 1]);
    }
  }
  return link;
}

}  // namespace imps::sim
