// SPDX-License-Identifier: MIT
// Tests for sim/sample_table: exact round trips of every field, and a take in memory about its size on disk.
#include "sim/sample_table.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "sim/session_file.h"

namespace imps::sim {
namespace {

using drivers::ChannelFlag;
using drivers::Sample;

Sample randomSample(std::mt19937& rng) {
  Sample s;
  s.sequence = uint32_t(rng());
  s.deviceTimeNs = int64_t(uint64_t(rng()) << 32 | rng());
  s.arrivalTimeNs = -int64_t(rng());
  s.channelCount = uint16_t(rng() % (drivers::kMaxChannels + 1));  // 0..64, both ends included
  for (int c = 0; c < s.channelCount; ++c) {
    s.counts[c] = uint32_t(rng());
    s.flags[c] = ChannelFlag(rng() % 3);
  }
  return s;
}

TEST(SampleTable, EverySampleReadsBackBitExact) {
  std::mt19937 rng(7);
  std::vector<Sample> expected;
  SampleTable table;
  for (int i = 0; i < 2000; ++i) {
    expected.push_back(randomSample(rng));
    table.push_back(expected.back());
  }
  ASSERT_EQ(table.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(table[i], expected[i]) << i;
    EXPECT_EQ(table.arrivalTimeNs(i), expected[i].arrivalTimeNs);
    EXPECT_EQ(table.deviceTimeNs(i), expected[i].deviceTimeNs);
    EXPECT_EQ(table.sequence(i), expected[i].sequence);
  }
  EXPECT_EQ(table.front(), expected.front());
  EXPECT_EQ(table.back(), expected.back());
  size_t i = 0;
  for (const Sample& s : table) EXPECT_EQ(s, expected[i++]);
  EXPECT_EQ(i, expected.size());
  EXPECT_EQ(table.end() - table.begin(), std::ptrdiff_t(expected.size()));
}

TEST(SampleTable, EqualityComparesContents) {
  std::mt19937 rng(3);
  SampleTable a, b;
  const Sample s = randomSample(rng);
  a.push_back(s);
  EXPECT_NE(a, b);
  b.push_back(s);
  EXPECT_EQ(a, b);
  Sample t = s;
  t.counts[0] ^= 1;
  t.channelCount = std::max<uint16_t>(t.channelCount, 1);
  SampleTable c;
  c.push_back(t);
  EXPECT_NE(a, c);
}

// The issue-14 finding: a 100 MB session took 1.7 GB in `info` (350 bytes per sample whatever its channel count).
// Held in a SampleTable, a read session of 3-channel samples takes at most 1.5x its file's bytes.
TEST(SampleTable, ReadSessionTakesAboutItsFileSize) {
  const auto path = std::filesystem::temp_directory_path() / ("imps_sample_table_" + std::to_string(::getpid()));
  DeviceInfo d;
  d.name = "three";
  d.channelCount = 3;
  d.bitsPerChannel = 12;
  d.channelNames = {"a", "b", "c"};
  {
    auto writer = SessionWriter::create(path, d);
    ASSERT_TRUE(writer.has_value()) << writer.error().firstError();
    Sample s;
    s.channelCount = 3;
    for (uint32_t i = 0; i < 100000; ++i) {
      s.sequence = i;
      s.arrivalTimeNs = int64_t(i) * 1'000'000;
      s.counts = {i & 4095, (i * 7) & 4095, (i * 13) & 4095};
      ASSERT_TRUE(writer->append(s).has_value());
    }
    ASSERT_TRUE(writer->close().has_value());
  }
  const auto fileBytes = std::filesystem::file_size(path);
  auto session = readSession(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(session.has_value()) << session.error().firstError();
  ASSERT_EQ(session->samples.size(), 100000u);
  EXPECT_EQ(session->samples[99999].counts[2], (99999u * 13) & 4095);
  EXPECT_LE(session->samples.bytes(), fileBytes * 3 / 2)
      << "bytes per sample: " << double(session->samples.bytes()) / 1e5;
  EXPECT_LT(session->samples.bytes() * 5, 100000 * sizeof(Sample));  // what a vector<Sample> took, 5x over
}

}  // namespace
}  // namespace imps::sim
