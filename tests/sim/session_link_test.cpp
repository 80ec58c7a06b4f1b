// SPDX-License-Identifier: MIT
// Tests for sim/session_link: outages, missing sequence numbers and restarts found in a recorded session, and a
// rate that does not average over the outages (issue 14 items 2 and 4).
#include "sim/session_link.h"

#include <gtest/gtest.h>

namespace imps::sim {
namespace {

constexpr int64_t kMs = 1'000'000;

// One device; samples every `spacingMs` with the given sequence numbers, and `pauseMs` more before sample
// `pauseAt`.
Session session(const std::vector<uint32_t>& sequences, int64_t spacingMs, size_t pauseAt = SIZE_MAX,
                int64_t pauseMs = 0) {
  Session s;
  DeviceInfo d;
  d.channelCount = 1;
  d.bitsPerChannel = 12;
  s.devices = {d};
  int64_t t = 5'000 * kMs;
  for (size_t i = 0; i < sequences.size(); ++i) {
    if (i == pauseAt) t += pauseMs * kMs;
    Sample x;
    x.channelCount = 1;
    x.sequence = sequences[i];
    x.arrivalTimeNs = t;
    s.samples.push_back(x);
    s.sampleDevice.push_back(0);
    t += spacingMs * kMs;
  }
  return s;
}

std::vector<uint32_t> range(uint32_t first, uint32_t end) {
  std::vector<uint32_t> out;
  for (uint32_t q = first; q < end; ++q) out.push_back(q);
  return out;
}

TEST(SessionLink, AnUnbrokenStreamHasNoOutageAndItsTrueRate) {
  const SessionLink link = analyzeSessionLink(session(range(0, 101), 10), 0);
  EXPECT_EQ(link.samples, 101u);
  EXPECT_EQ(link.spanNs, 1000 * kMs);
  EXPECT_TRUE(link.outages.empty());
  EXPECT_EQ(link.missing, 0u);
  EXPECT_EQ(link.restarts, 0u);
  EXPECT_DOUBLE_EQ(link.rateHz(), 100.0);
}

TEST(SessionLink, AnOutageIsLocatedAndLeftOutOfTheRate) {
  // 100 Hz, then 5 s of silence in which 500 samples were lost, then 100 Hz again.
  std::vector<uint32_t> q = range(0, 100);
  for (uint32_t x = 600; x < 700; ++x) q.push_back(x);
  const SessionLink link = analyzeSessionLink(session(q, 10, 100, 4990), 0);
  ASSERT_EQ(link.outages.size(), 1u);
  EXPECT_EQ(link.outages[0].afterSample, 99u);
  EXPECT_EQ(link.outages[0].startNs, 990 * kMs);
  EXPECT_EQ(link.outages[0].lengthNs, 5000 * kMs);
  EXPECT_EQ(link.outages[0].missing, 500u);
  EXPECT_EQ(link.missing, 500u);
  EXPECT_EQ(link.outageNs, 5000 * kMs);
  EXPECT_DOUBLE_EQ(link.rateHz(), 100.0);  // not 199 samples / 6.98 s
}

TEST(SessionLink, ARebootIsARestartNotMissingSamples) {
  std::vector<uint32_t> q = range(0, 50);
  for (uint32_t x = 0; x < 50; ++x) q.push_back(x);  // numbering starts again at 0
  const SessionLink link = analyzeSessionLink(session(q, 10, 50, 2000), 0);
  EXPECT_EQ(link.restarts, 1u);
  EXPECT_EQ(link.missing, 0u);
  ASSERT_EQ(link.outages.size(), 1u);
  EXPECT_EQ(link.outages[0].missing, 0u);
}

TEST(SessionLink, ShortHiccupsAreNotOutagesAndOtherDevicesDoNotCount) {
  Session s = session(range(0, 100), 1, 50, 60);  // 60 ms at 1 kHz: a hiccup, under 100 ms
  EXPECT_TRUE(analyzeSessionLink(s, 0).outages.empty());
  EXPECT_EQ(analyzeSessionLink(s, 1).samples, 0u);
  EXPECT_EQ(analyzeSessionLink(session({7}, 10), 0).rateHz(), 0.0);
}

}  // namespace
}  // namespace imps::sim
