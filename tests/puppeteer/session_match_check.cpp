// SPDX-License-Identifier: MIT
// Checks a session recorded by the live app (`puppeteer live --record`) against the session the simulated armature
// played: the take is whole, has samples, and every recorded sample is, bit for bit, the source sample its sequence
// number names (the simulator sends source sample `sequence mod N`), with no sequence number missing.
// Usage: session_match_check TAKE.session SOURCE.session [MIN_SAMPLES]. Exit 0 when every check passes.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "sim/session_file.h"

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr, "usage: session_match_check TAKE.session SOURCE.session [MIN_SAMPLES]\n");
    return 2;
  }
  const size_t minSamples = argc == 4 ? std::strtoull(argv[3], nullptr, 10) : 1;
  auto take = imps::sim::readSession(argv[1]);
  auto source = imps::sim::readSession(argv[2]);
  if (!take || !source) {
    std::fputs((!take ? take.error() : source.error()).str().c_str(), stderr);
    return 1;
  }
  if (!take->recovery.closedCleanly) {
    std::printf("FAIL: %s was not closed cleanly\n", argv[1]);
    return 1;
  }
  if (take->samples.size() < minSamples || source->samples.empty()) {
    std::printf("FAIL: %zu samples recorded, expected at least %zu\n", take->samples.size(), minSamples);
    return 1;
  }
  const size_t n = source->samples.size();
  for (size_t i = 0; i < take->samples.size(); ++i) {
    const auto& got = take->samples[i];
    const auto& want = source->samples[got.sequence % n];
    if (i > 0 && got.sequence != take->samples[i - 1].sequence + 1) {
      std::printf("FAIL: sample %zu: sequence %u follows %u (a sample is missing)\n", i, got.sequence,
                  take->samples[i - 1].sequence);
      return 1;
    }
    for (int c = 0; c < got.channelCount; ++c) {
      if (got.counts[size_t(c)] != want.counts[size_t(c)]) {
        std::printf("FAIL: sample %zu (sequence %u) channel %d: recorded %u, the simulator sent %u\n", i,
                    got.sequence, c, got.counts[size_t(c)], want.counts[size_t(c)]);
        return 1;
      }
    }
  }
  std::printf("ok: %zu recorded samples equal the simulator's, bit for bit, none missing\n", take->samples.size());
  return 0;
}
