// SPDX-License-Identifier: MIT
// Tests for drivers/line_protocol: line endings, separators, banner, timestamps, channel-count locking, overlong
// lines, junk, chunking, and the decoder's counters.
#include "drivers/line_protocol.h"

#include <gtest/gtest.h>

#include <random>
#include <string_view>

namespace imps::drivers {
namespace {

std::span<const uint8_t> bytes(std::string_view s) {
  return std::span(reinterpret_cast<const uint8_t*>(s.data()), s.size());
}

std::vector<Sample> decodeAll(LineDecoder& d, std::string_view text, size_t chunk = SIZE_MAX, int64_t t = 0) {
  std::vector<Sample> out;
  for (size_t at = 0; at < text.size(); at += chunk) {
    d.feed(bytes(text.substr(at, std::min(chunk, text.size() - at))), t);
    while (auto s = d.next()) out.push_back(*s);
  }
  return out;
}

std::vector<std::vector<uint32_t>> countsOf(const std::vector<Sample>& samples) {
  std::vector<std::vector<uint32_t>> out;
  for (const auto& s : samples) out.emplace_back(s.counts.begin(), s.counts.begin() + s.channelCount);
  return out;
}

void expectStatsAddUp(const LineDecoder& d) {
  const auto& s = d.stats();
  EXPECT_EQ(s.bytesReceived, s.bytesInLines + s.bytesSkipped + d.buffered());
  EXPECT_EQ(s.lines, s.samples + s.bannerLines + s.malformedLines + s.channelCountMismatches + s.overlongLines +
                         d.pendingLines());
}

// A decoder that takes the first well-formed line as the layout (tests of line parsing, not of settling).
LineDecoder lockingAtOnce() {
  LineDecoderOptions options;
  options.settleLines = 1;
  return LineDecoder(options);
}

using Rows = std::vector<std::vector<uint32_t>>;

TEST(LineProtocol, LineEndingsLfCrCrlfAndMixed) {
  for (std::string_view text : {"1,2,3\n4,5,6\n", "1,2,3\r4,5,6\r", "1,2,3\r\n4,5,6\r\n", "1,2,3\r\n4,5,6\n",
                                "1,2,3\n\r4,5,6\r", "\n\n1,2,3\r\n\r\n4,5,6\n"}) {
    LineDecoder d;
    EXPECT_EQ(countsOf(decodeAll(d, text)), (Rows{{1, 2, 3}, {4, 5, 6}})) << text;
    EXPECT_EQ(d.stats().lines, 2u);
    EXPECT_EQ(d.stats().errors(), 0u);
    expectStatsAddUp(d);
  }
}

TEST(LineProtocol, SeparatorsCommasSpacesTabs) {
  for (std::string_view text : {"10,20,30\n", "10 20 30\n", "10\t20\t30\n", "10, 20 ,30\n", "  10 \t 20   30  \n",
                                "10,20,30,\n", "10, 20, 30, \n", "\t10,\t20,\t30\n"}) {
    LineDecoder d = lockingAtOnce();
    EXPECT_EQ(countsOf(decodeAll(d, text)), (Rows{{10, 20, 30}})) << text;
  }
  // Largest count, and a 64-channel line.
  LineDecoder d = lockingAtOnce();
  std::string line;
  for (int i = 0; i < 64; ++i) line += std::to_string(4294967295u - static_cast<uint32_t>(i)) + " ";
  const auto got = decodeAll(d, line + "\n");
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].channelCount, 64);
  EXPECT_EQ(got[0].counts[0], 4294967295u);
  EXPECT_EQ(got[0].counts[63], 4294967295u - 63);
}

TEST(LineProtocol, BannerLinesBeforeTheFirstSampleAreRecorded) {
  LineDecoder d;
  const auto got = decodeAll(d,
                             "\xff\xfe garbage at reset\r\n"
                             "IMPS DIY armature v0.3\r\n"
                             "channels: 3, 10-bit\r\n"
                             "\r\n"
                             "1.5 2.5 3.5\r\n"
                             "100,200,300\r\n"
                             "hello again\r\n"
                             "101,201,301\r\n");
  EXPECT_EQ(countsOf(got), (Rows{{100, 200, 300}, {101, 201, 301}}));
  ASSERT_EQ(d.banner().size(), 4u);
  EXPECT_EQ(d.banner()[1], "IMPS DIY armature v0.3");
  EXPECT_EQ(d.banner()[3], "1.5 2.5 3.5");
  EXPECT_EQ(d.stats().bannerLines, 4u);
  EXPECT_EQ(d.stats().malformedLines, 1u);  // junk after the first sample is an error, not banner
  EXPECT_EQ(got[0].sequence, 0u);
  EXPECT_EQ(got[1].sequence, 1u);
  expectStatsAddUp(d);

  // reset() (the Arduino rebooted) accepts a new banner and restarts the sequence.
  d.reset();
  const auto again = decodeAll(d, "booting\n7 8\n9 10\n");
  EXPECT_EQ(countsOf(again), (Rows{{7, 8}, {9, 10}}));
  EXPECT_EQ(again[0].sequence, 0u);
  EXPECT_EQ(d.banner(), std::vector<std::string>{"booting"});
  EXPECT_EQ(d.channelCount(), 2);

  LineDecoderOptions few;
  few.maxBannerLines = 2;
  LineDecoder capped(few);
  decodeAll(capped, "a\nb\nc\nd\n1\n2\n");
  EXPECT_EQ(capped.banner().size(), 2u);
  EXPECT_EQ(capped.stats().bannerLines, 4u);
}

TEST(LineProtocol, Timestamps) {
  LineDecoder d;
  const auto got =
      decodeAll(d, "t=1500,1,2\nt=2000us 1 2\nT=3ms,1,2\nt=4ms\t1\t2\nt=18446744073709551615,1,2\n5,6\n", SIZE_MAX, 77);
  ASSERT_EQ(got.size(), 5u);
  EXPECT_EQ(got[0].deviceTimeNs, 1500000);
  EXPECT_EQ(got[1].deviceTimeNs, 2000000);
  EXPECT_EQ(got[2].deviceTimeNs, 3000000);
  EXPECT_EQ(got[3].deviceTimeNs, 4000000);
  EXPECT_EQ(got[4].deviceTimeNs, 0);  // no timestamp
  EXPECT_EQ(got[4].counts[0], 5u);
  EXPECT_EQ(got[0].arrivalTimeNs, 77);
  EXPECT_EQ(d.stats().malformedLines, 1u);  // the timestamp that overflows int64 nanoseconds
  for (std::string_view bad : {"t=,1,2\n", "t=5\n", "t5,1,2\n", "t=5s,1,2\n", "t=5 ms,1,2\n", "t=-5,1,2\n"}) {
    LineDecoder e;
    decodeAll(e, "1,2\n1,2\n");
    EXPECT_TRUE(decodeAll(e, bad).empty()) << bad;
    EXPECT_EQ(e.stats().malformedLines, 1u) << bad;
  }
}

TEST(LineProtocol, NonNumericJunkIsCountedAndSkipped) {
  for (std::string_view bad : {"1,2,x\n", "1,,2\n", ",1,2\n", "1;2\n", "12a,3\n", "-1,2\n", "+1,2\n",
                               "1.0,2\n", "4294967296,1\n", "0x10,1\n", "OK\n", "1 2 3 4 5 6 7 8 9 10 "
                               "11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33 34 35 36 37 "
                               "38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59 60 61 62 63 64 "
                               "65\n"}) {
    LineDecoder d;
    decodeAll(d, "1,2\n1,2\n");
    EXPECT_TRUE(decodeAll(d, bad).empty()) << bad;
    const auto ok = decodeAll(d, "3,4\n");
    EXPECT_EQ(countsOf(ok), (Rows{{3, 4}})) << bad;
    EXPECT_EQ(d.stats().malformedLines + d.stats().channelCountMismatches, 1u) << bad;
    expectStatsAddUp(d);
  }
  // An embedded NUL makes the line junk.
  LineDecoder d;
  decodeAll(d, "1,2\n1,2\n");
  decodeAll(d, std::string_view("1,\0002\n", 5));
  EXPECT_EQ(d.stats().malformedLines, 1u);
}

TEST(LineProtocol, ChannelCountIsSettledByAgreeingLines) {
  LineDecoder d;
  const auto got = decodeAll(d, "1 2 3\n4 5 6\n4 5\n6 7 8 9\n10 11 12\n");
  EXPECT_EQ(countsOf(got), (Rows{{1, 2, 3}, {4, 5, 6}, {10, 11, 12}}));
  EXPECT_EQ(d.channelCount(), 3);
  EXPECT_EQ(d.stats().channelCountMismatches, 2u);
  EXPECT_EQ(d.stats().errors(), 2u);
  expectStatsAddUp(d);

  // Lines that disagree before the layout settled are banner, not samples of another layout.
  LineDecoder e;
  EXPECT_EQ(countsOf(decodeAll(e, "1 2 3\n4 5\n6 7 8 9\n10 11 12\n13 14 15\n")), (Rows{{10, 11, 12}, {13, 14, 15}}));
  EXPECT_EQ(e.stats().bannerLines, 3u);
  EXPECT_EQ(e.stats().errors(), 0u);
  expectStatsAddUp(e);

  // A single line waits for the next one to agree.
  LineDecoder f;
  EXPECT_TRUE(decodeAll(f, "1 2\n").empty());
  EXPECT_EQ(f.pendingLines(), 1u);
  expectStatsAddUp(f);
  EXPECT_EQ(countsOf(decodeAll(f, "3 4\n")), (Rows{{1, 2}, {3, 4}}));

  // An expected count makes other counts banner before the first sample and mismatches after.
  LineDecoderOptions options;
  options.expectedChannelCount = 2;
  LineDecoder fixed(options);
  EXPECT_EQ(countsOf(decodeAll(fixed, "115200\n1 2\n3 4 5\n6 7\n")), (Rows{{1, 2}, {6, 7}}));
  EXPECT_EQ(fixed.stats().bannerLines, 1u);
  EXPECT_EQ(fixed.stats().channelCountMismatches, 1u);
}

// Issue 14 item 1: the docs' own banner (a baud rate on a line of its own) must not become a 1-channel layout.
TEST(LineProtocol, NumericBannerLineIsBannerNotTheFirstSample) {
  LineDecoder d;
  std::string text = "115200\n";
  for (int i = 0; i < 20; ++i) text += std::to_string(i) + " 2 3 4 5 6 7 8\n";
  const auto got = decodeAll(d, text, 5, 42);
  ASSERT_EQ(got.size(), 20u);
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].channelCount, 8);
    EXPECT_EQ(got[i].counts[0], i);
    EXPECT_EQ(got[i].sequence, i);
    EXPECT_EQ(got[i].arrivalTimeNs, 42);
  }
  EXPECT_EQ(d.banner(), std::vector<std::string>{"115200"});
  EXPECT_EQ(d.stats().errors(), 0u);
  EXPECT_EQ(d.stats().channelCountChanges, 0u);
  expectStatsAddUp(d);
}

TEST(LineProtocol, ConsistentNewChannelCountReLocksWithoutLosingItsLines) {
  LineDecoderOptions options;
  options.relockAfter = 3;
  LineDecoder d(options);
  // Two numeric banner lines agree and settle a 1-channel layout; three 2-channel lines re-lock to 2 and are
  // samples of the new layout, in order.
  const auto got = decodeAll(d, "2024\n2025\n1 2\n3 4\n5 6\n7 8\n9 10\n");
  EXPECT_EQ(countsOf(got), (Rows{{2024}, {2025}, {1, 2}, {3, 4}, {5, 6}, {7, 8}, {9, 10}}));
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].sequence, i);
  EXPECT_EQ(d.channelCount(), 2);
  EXPECT_EQ(d.stats().channelCountChanges, 1u);
  EXPECT_EQ(d.stats().channelCountMismatches, 0u);
  expectStatsAddUp(d);

  // Interleaved different counts do not re-lock; an accepted sample breaks the run.
  LineDecoder e(options);
  decodeAll(e, "1 2\n1 2\n1 2 3\n1 2 3 4\n1 2 3\n1 2\n1 2 3\n1 2 3\n1 2\n");
  EXPECT_EQ(e.channelCount(), 2);
  EXPECT_EQ(e.stats().channelCountChanges, 0u);
  EXPECT_EQ(e.stats().samples, 4u);
  EXPECT_EQ(e.stats().channelCountMismatches, 5u);
  expectStatsAddUp(e);

  options.relockAfter = 0;
  LineDecoder never(options);
  decodeAll(never, "1\n1\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n");
  EXPECT_EQ(never.channelCount(), 1);
  EXPECT_EQ(never.stats().channelCountMismatches, 10u);
}

TEST(LineProtocol, OverlongLinesAreSkippedWithoutUnboundedBuffering) {
  LineDecoderOptions options;
  options.maxLineLength = 16;
  for (size_t chunk : {size_t{1}, size_t{5}, size_t{1000}}) {
    LineDecoder d(options);
    const std::string longLine(1000, '7');
    const std::string text = "1,2\n" + longLine + "\r\n3,4\n" + std::string(16, ' ') + "\n" + "5,6" +
                             std::string(13, ' ') + "\n";
    size_t maxBuffered = 0;
    std::vector<Sample> got;
    for (size_t at = 0; at < text.size(); at += chunk) {
      d.feed(bytes(std::string_view(text).substr(at, std::min(chunk, text.size() - at))));
      while (auto s = d.next()) got.push_back(*s);
      maxBuffered = std::max(maxBuffered, d.buffered());
    }
    EXPECT_EQ(countsOf(got), (Rows{{1, 2}, {3, 4}, {5, 6}})) << chunk;  // 16 bytes exactly is accepted
    EXPECT_EQ(d.stats().overlongLines, 1u);
    EXPECT_EQ(d.stats().bytesSkipped, longLine.size() + 1);  // the line and its CR
    EXPECT_LE(maxBuffered, std::max<size_t>(chunk, 16));
    expectStatsAddUp(d);
  }
  // A line that never ends is dropped as it arrives.
  LineDecoder d(options);
  for (int i = 0; i < 1000; ++i) {
    d.feed(bytes("123456789 "));
    EXPECT_FALSE(d.next());
    EXPECT_LE(d.buffered(), 16u);
  }
  EXPECT_EQ(d.stats().overlongLines, 1u);
  d.feed(bytes("\n9 9\n9 9\n"));
  EXPECT_TRUE(d.next());
  expectStatsAddUp(d);
}

TEST(LineProtocol, EveryChunkingDecodesTheSame) {
  std::string text = "Monkey DIY\r\nready\r\n";
  for (int i = 0; i < 200; ++i) {
    text += (i % 3 == 0 ? "t=" + std::to_string(i * 1000) + "," : std::string());
    for (int c = 0; c < 8; ++c) text += std::to_string(i * 8 + c) + (c % 2 ? ", " : "\t");
    text += i % 4 == 0 ? "\r\n" : i % 4 == 1 ? "\n" : i % 4 == 2 ? "\r" : " \t\n";
    if (i % 50 == 7) text += "oops\n";
  }
  LineDecoder whole;
  const auto expected = decodeAll(whole, text);
  ASSERT_EQ(expected.size(), 200u);
  EXPECT_EQ(whole.stats().malformedLines, 4u);
  for (size_t chunk : {size_t{1}, size_t{2}, size_t{3}, size_t{7}, size_t{64}}) {
    LineDecoder d;
    EXPECT_EQ(decodeAll(d, text, chunk), expected) << chunk;
    EXPECT_EQ(d.stats(), whole.stats());
    EXPECT_EQ(d.banner(), whole.banner());
  }
  std::mt19937 rng(11);
  LineDecoder d;
  std::vector<Sample> got;
  for (size_t at = 0; at < text.size();) {
    const size_t n = std::min<size_t>(text.size() - at, 1 + rng() % 100);
    d.feed(bytes(std::string_view(text).substr(at, n)));
    at += n;
    while (auto s = d.next()) got.push_back(*s);
  }
  EXPECT_EQ(got, expected);
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].sequence, i);
    EXPECT_EQ(got[i].counts[7], i * 8 + 7);
  }
}

}  // namespace
}  // namespace imps::drivers
