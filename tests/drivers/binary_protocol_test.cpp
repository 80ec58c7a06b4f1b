// SPDX-License-Identifier: MIT
// Tests for drivers/binary_protocol: known-answer bytes, round trips of every message type, every chunking,
// resynchronisation after garbage, corruption and truncation, and the decoder's counters.
#include "drivers/binary_protocol.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <random>
#include <string_view>

// Counts heap allocations made by the current thread (to check the decoder's hot path allocates nothing).
namespace {
thread_local long tAllocations = 0;
}
void* operator new(size_t size) {
  ++tAllocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// GCC cannot see that this operator new returns malloc()'s memory and would warn about the matching free().
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace imps::drivers {
namespace {

using Bytes = std::vector<uint8_t>;

Bytes bytesOf(std::string_view hex) {
  Bytes out;
  for (size_t i = 0; i < hex.size();) {
    if (hex[i] == ' ') {
      ++i;
      continue;
    }
    out.push_back(static_cast<uint8_t>(std::stoul(std::string(hex.substr(i, 2)), nullptr, 16)));
    i += 2;
  }
  return out;
}

Bytes encode(const Message& m) {
  Bytes out;
  auto ok = appendFrame(m, out);
  EXPECT_TRUE(ok.has_value()) << (ok ? "" : ok.error().str());
  return out;
}

// A frame with arbitrary header fields and payload, CRCs computed as docs/protocol.md says.
Bytes rawFrame(uint8_t version, uint8_t type, uint8_t flags, uint32_t sequence, const Bytes& payload,
               size_t claimedLength = SIZE_MAX) {
  const size_t length = claimedLength == SIZE_MAX ? payload.size() : claimedLength;
  Bytes f = {kSync0, kSync1, version, type, flags};
  for (int i = 0; i < 4; ++i) f.push_back(static_cast<uint8_t>(sequence >> (8 * i)));
  f.push_back(static_cast<uint8_t>(length));
  f.push_back(static_cast<uint8_t>(length >> 8));
  const uint16_t hc = crc16CcittFalse(std::span(f).subspan(2));
  f.push_back(static_cast<uint8_t>(hc));
  f.push_back(static_cast<uint8_t>(hc >> 8));
  f.insert(f.end(), payload.begin(), payload.end());
  const uint16_t fc = crc16CcittFalse(std::span(f).subspan(2));
  f.push_back(static_cast<uint8_t>(fc));
  f.push_back(static_cast<uint8_t>(fc >> 8));
  return f;
}

DeviceInfo testInfo(int channels = 3) {
  DeviceInfo info;
  info.name = "IMPS Monkey-test";
  info.serialNumber = "SN-0042";
  info.firmwareVersion = "1.2.3";
  info.channelCount = channels;
  info.bitsPerChannel = 14;
  info.hasDeviceTimestamp = true;
  for (int i = 0; i < channels; ++i) info.channelNames.push_back("joint:" + std::to_string(i));
  return info;
}

Sample testSample(uint32_t sequence, int channels, int bits, uint64_t salt = 0) {
  Sample s;
  s.sequence = sequence;
  s.channelCount = static_cast<uint16_t>(channels);
  const uint64_t mask = (uint64_t{1} << bits) - 1;
  for (int i = 0; i < channels; ++i) {
    s.counts[i] = static_cast<uint32_t>((sequence * 2654435761u + static_cast<uint64_t>(i) * 40503u + salt) & mask);
    s.flags[i] = static_cast<ChannelFlag>((i + sequence) % 3);
  }
  return s;
}

// One message of every type, plus samples in every option combination.
std::vector<Message> everyMessage() {
  std::vector<Message> all;
  all.push_back({0, 0, msg::Hello{kProtocolVersion, testInfo()}});
  all.push_back({11, kFlagReply, msg::Info{testInfo(64)}});
  for (int variant = 0; variant < 4; ++variant) {
    Sample s = testSample(100 + static_cast<uint32_t>(variant), 17 + variant, 12 + variant);
    const bool time = variant & 1, flags = variant & 2;
    if (time) s.deviceTimeNs = 123456789000;
    if (!flags) s.flags.fill(ChannelFlag::Valid);
    all.push_back(sampleMessage(s, static_cast<uint8_t>(12 + variant), time, flags));
  }
  all.push_back({12, kFlagReply, msg::Ack{MessageType::StartStream}});
  all.push_back({13, kFlagReply, msg::Error{MessageType::StartStream, ErrorCode::BadRate, "rate 9999 Hz too high"}});
  all.push_back({0, 0, msg::Error{MessageType{}, ErrorCode::DeviceFault, ""}});
  all.push_back({1, 0, msg::HostHello{1}});
  all.push_back({2, 0, msg::GetInfo{}});
  all.push_back({3, 0, msg::Poll{}});
  all.push_back({4, 0, msg::StartStream{1000}});
  all.push_back({5, 0, msg::StopStream{}});
  return all;
}

// Feeds `stream` in chunks whose sizes come from `nextChunk`, collecting every message and the frame bytes.
template <class ChunkFn>
std::vector<Message> decodeChunked(BinaryDecoder& d, const Bytes& stream, ChunkFn nextChunk) {
  std::vector<Message> out;
  size_t at = 0;
  while (at < stream.size()) {
    const size_t n = std::min(stream.size() - at, std::max<size_t>(1, nextChunk()));
    d.feed(std::span(stream).subspan(at, n));
    at += n;
    while (auto m = d.next()) out.push_back(std::move(*m));
  }
  return out;
}

std::vector<Message> decodeAll(BinaryDecoder& d, const Bytes& stream) {
  return decodeChunked(d, stream, [&] { return stream.size(); });
}

void expectStatsAddUp(const BinaryDecoder& d) {
  const auto& s = d.stats();
  EXPECT_EQ(s.bytesReceived, s.bytesInFrames + s.bytesSkipped + d.buffered());
}

TEST(Crc16CcittFalse, CheckValue) {
  const std::string_view check = "123456789";
  EXPECT_EQ(crc16CcittFalse(std::span(reinterpret_cast<const uint8_t*>(check.data()), check.size())), 0x29B1);
  EXPECT_EQ(crc16CcittFalse({}), 0xFFFF);
  // Continuing over a split gives the same result.
  const auto* p = reinterpret_cast<const uint8_t*>(check.data());
  EXPECT_EQ(crc16CcittFalse(std::span(p + 4, 5), crc16CcittFalse(std::span(p, 4))), 0x29B1);
}

// The two example frames of docs/protocol.md, computed by hand there (and independently in Python).
TEST(BinaryProtocol, KnownAnswerPoll) {
  const Bytes expected = bytesOf("A5 5A 01 83 00 07 00 00 00 00 00 E4 0E 1D A3");
  EXPECT_EQ(encode({7, 0, msg::Poll{}}), expected);
  BinaryDecoder d;
  const auto got = decodeAll(d, expected);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type(), MessageType::Poll);
  EXPECT_EQ(got[0].sequence, 7u);
}

TEST(BinaryProtocol, KnownAnswerSample) {
  const Bytes expected = bytesOf(
      "A5 5A 01 03 00 02 01 00 00 11 00 77 2A 03 0C 03 E8 03 00 00 00 00 00 00 23 61 45 89 07 24 1C 4B");
  Sample s;
  s.sequence = 0x0102;
  s.deviceTimeNs = 1000 * 1000;  // 1000 µs
  s.channelCount = 3;
  s.counts[0] = 0x123;
  s.counts[1] = 0x456;
  s.counts[2] = 0x789;
  s.flags[0] = ChannelFlag::Valid;
  s.flags[1] = ChannelFlag::NotConnected;
  s.flags[2] = ChannelFlag::Outlier;
  EXPECT_EQ(encode(sampleMessage(s, 12, true, true)), expected);

  BinaryDecoder d;
  d.feed(expected, 555);
  auto m = d.next();
  ASSERT_TRUE(m);
  const auto& f = std::get<msg::SampleFrame>(m->payload);
  s.arrivalTimeNs = 555;
  EXPECT_EQ(f.sample, s);
  EXPECT_EQ(f.bitsPerChannel, 12);
  EXPECT_TRUE(f.hasDeviceTime);
  EXPECT_TRUE(f.hasChannelFlags);
}

TEST(BinaryProtocol, KnownAnswerStartStream) {
  EXPECT_EQ(encode({1, 0, msg::StartStream{1000}}), bytesOf("A5 5A 01 84 00 01 00 00 00 02 00 7F 22 E8 03 5A F9"));
}

TEST(BinaryProtocol, EveryMessageTypeRoundTripsByteExactly) {
  for (const Message& m : everyMessage()) {
    SCOPED_TRACE(static_cast<int>(m.type()));
    const Bytes bytes = encode(m);
    EXPECT_EQ(encodedFrameSize(m).value(), bytes.size());
    BinaryDecoder d;
    d.feed(bytes);
    auto got = d.next();
    ASSERT_TRUE(got);
    EXPECT_EQ(*got, m);
    EXPECT_EQ(Bytes(d.lastFrame().begin(), d.lastFrame().end()), bytes);
    EXPECT_EQ(encode(*got), bytes);
    EXPECT_FALSE(d.next());
    EXPECT_EQ(d.stats().framesOk, 1u);
    EXPECT_EQ(d.stats().bytesInFrames, bytes.size());
    EXPECT_EQ(d.stats().bytesSkipped, 0u);
    expectStatsAddUp(d);
  }
}

TEST(BinaryProtocol, SamplesRoundTripForEveryBitDepthAndChannelCount) {
  BinaryDecoder d;
  Bytes stream;
  std::vector<Message> sent;
  uint32_t seq = 0;
  for (int bits = 1; bits <= 32; ++bits) {
    for (int channels : {1, 2, 3, 4, 5, 7, 8, 31, 63, 64}) {
      Sample s = testSample(seq, channels, bits, static_cast<uint64_t>(bits));
      if (channels == 64) s.counts[63] = static_cast<uint32_t>((uint64_t{1} << bits) - 1);  // largest count
      const bool time = (seq % 2) == 0, flags = (seq % 3) == 0;
      if (time) s.deviceTimeNs = static_cast<int64_t>(seq) * 1000 * 997;
      if (!flags) s.flags.fill(ChannelFlag::Valid);
      sent.push_back(sampleMessage(s, static_cast<uint8_t>(bits), time, flags));
      const Bytes f = encode(sent.back());
      stream.insert(stream.end(), f.begin(), f.end());
      ++seq;
    }
  }
  EXPECT_EQ(decodeAll(d, stream), sent);
  EXPECT_EQ(d.stats().samples, sent.size());
  EXPECT_EQ(d.stats().sequenceGaps, 0u);
  expectStatsAddUp(d);
}

TEST(BinaryProtocol, DefaultChannelNamesAreCanonicallyOmitted) {
  DeviceInfo info = testInfo(4);
  info.channelNames.clear();
  const Bytes noNames = encode({0, 0, msg::Info{info}});
  info.channelNames = {"ch0", "ch1", "ch2", "ch3"};
  EXPECT_EQ(encode({0, 0, msg::Info{info}}), noNames);
  BinaryDecoder d;
  d.feed(noNames);
  auto m = d.next();
  ASSERT_TRUE(m);
  EXPECT_EQ(std::get<msg::Info>(m->payload).info, info);  // the decoder fills in the default names
}

TEST(BinaryProtocol, EncoderRejectsWhatCannotBeEncoded) {
  auto rejects = [](const Message& m, std::string_view why) {
    Bytes out = {1, 2, 3};
    auto r = appendFrame(m, out);
    EXPECT_FALSE(r.has_value()) << why;
    EXPECT_EQ(out, (Bytes{1, 2, 3})) << why;
    EXPECT_FALSE(encodedFrameSize(m).has_value()) << why;
  };
  Sample s = testSample(5, 4, 10);
  auto sampleWith = [&](auto change, uint8_t bits = 10) {
    Sample t = s;
    change(t);
    return sampleMessage(t, bits, true, true);
  };
  rejects(sampleWith([](Sample& t) { t.channelCount = 0; }), "no channels");
  rejects(sampleWith([](Sample& t) { t.channelCount = kMaxChannels + 1; }), "too many channels");
  rejects(sampleWith([](Sample&) {}, 0), "0 bits");
  rejects(sampleWith([](Sample&) {}, 33), "33 bits");
  rejects(sampleWith([](Sample& t) { t.counts[2] = 1024; }), "count over 10 bits");
  rejects(sampleWith([](Sample& t) { t.flags[1] = static_cast<ChannelFlag>(3); }), "flag 3");
  rejects(sampleWith([](Sample& t) { t.deviceTimeNs = -1000; }), "negative time");
  Message mismatched = sampleWith([](Sample&) {});
  mismatched.sequence = 6;
  rejects(mismatched, "sequence mismatch");
  DeviceInfo info = testInfo(3);
  info.channelNames.pop_back();
  rejects({0, 0, msg::Info{info}}, "names count");
  info = testInfo(3);
  info.name = std::string(64, 'x');
  rejects({0, 0, msg::Hello{1, info}}, "long name");
  info = testInfo(3);
  info.channelNames[0] = std::string(24, 'x');
  rejects({0, 0, msg::Info{info}}, "long channel name");
  info = testInfo(3);
  info.bitsPerChannel = 0;
  rejects({0, 0, msg::Info{info}}, "info bits");
  rejects({0, 0, msg::StartStream{0}}, "rate 0");
  rejects({0, 0, msg::Error{MessageType::Poll, ErrorCode::Busy, std::string(256, 'e')}}, "long error text");

  // A span too small is refused, not overrun.
  std::array<uint8_t, 14> small{};
  EXPECT_FALSE(encodeFrame({0, 0, msg::Poll{}}, small).has_value());
  std::array<uint8_t, 15> exact{};
  EXPECT_EQ(encodeFrame({0, 0, msg::Poll{}}, exact).value(), 15u);
  // Device time is carried in whole microseconds.
  Sample fractional = testSample(1, 2, 8);
  fractional.deviceTimeNs = 1999;
  BinaryDecoder d;
  d.feed(encode(sampleMessage(fractional, 8, true, false)));
  EXPECT_EQ(std::get<msg::SampleFrame>(d.next()->payload).sample.deviceTimeNs, 1000);
}

Bytes streamOf(const std::vector<Message>& messages) {
  Bytes stream;
  for (const auto& m : messages) {
    const Bytes f = encode(m);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  return stream;
}

TEST(BinaryProtocol, EveryChunkingDecodesTheSame) {
  std::vector<Message> messages;
  for (int round = 0; round < 3; ++round)
    for (const auto& m : everyMessage()) messages.push_back(m);
  const Bytes stream = streamOf(messages);

  BinaryDecoder whole;
  ASSERT_EQ(decodeAll(whole, stream), messages);

  BinaryDecoder byByte;
  EXPECT_EQ(decodeChunked(byByte, stream, [] { return size_t{1}; }), messages);
  EXPECT_EQ(byByte.stats(), whole.stats());

  // Every split point of the stream into two chunks.
  for (size_t cut = 0; cut <= stream.size(); cut += 7) {
    BinaryDecoder d;
    bool first = true;
    EXPECT_EQ(decodeChunked(d, stream, [&] { return std::exchange(first, false) ? cut : stream.size(); }), messages)
        << "cut at " << cut;
  }
  for (unsigned seed = 1; seed <= 50; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<size_t> size(1, 200);
    BinaryDecoder d;
    EXPECT_EQ(decodeChunked(d, stream, [&] { return size(rng); }), messages) << "seed " << seed;
    EXPECT_EQ(d.stats(), whole.stats());
  }
}

TEST(BinaryProtocol, GarbageBeforeAndBetweenFramesIsSkippedAndCounted) {
  const auto messages = everyMessage();
  std::mt19937 rng(7);
  Bytes stream;
  size_t garbage = 0;
  for (const auto& m : messages) {
    // Random bytes rich in sync bytes, including false sync pairs.
    const size_t n = rng() % 40;
    for (size_t i = 0; i < n; ++i) {
      const unsigned r = rng() % 4;
      stream.push_back(r == 0 ? kSync0 : r == 1 ? kSync1 : static_cast<uint8_t>(rng()));
    }
    garbage += n;
    const Bytes f = encode(m);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  stream.push_back(kSync0);  // a trailing lone sync byte stays buffered
  ++garbage;
  for (size_t chunk : {size_t{1}, size_t{3}, size_t{64}, stream.size()}) {
    BinaryDecoder d;
    EXPECT_EQ(decodeChunked(d, stream, [&] { return chunk; }), messages);
    EXPECT_EQ(d.stats().bytesSkipped + d.buffered(), garbage);
    EXPECT_EQ(d.buffered(), 1u);
    expectStatsAddUp(d);
    d.reset();
    EXPECT_EQ(d.buffered(), 0u);
    EXPECT_EQ(d.stats().bytesSkipped, garbage);
    expectStatsAddUp(d);
  }
}

TEST(BinaryProtocol, EverySingleBitFlipIsRejectedAndTheNextFrameStillDecodes) {
  const Message before{1, 0, msg::Ack{MessageType::Poll}};
  const Message after{3, 0, msg::StopStream{}};
  Sample s = testSample(2, 5, 12);
  s.deviceTimeNs = 42000;
  const Message victim = sampleMessage(s, 12, true, true);
  const Bytes a = encode(before), b = encode(victim), c = encode(after);
  for (size_t byte = 0; byte < b.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      SCOPED_TRACE("byte " + std::to_string(byte) + " bit " + std::to_string(bit));
      Bytes corrupt = b;
      corrupt[byte] = static_cast<uint8_t>(corrupt[byte] ^ (1u << bit));
      BinaryDecoder d;
      Bytes first = a;
      first.insert(first.end(), corrupt.begin(), corrupt.end());
      auto got = decodeAll(d, first);
      // Nothing waits for bytes the corrupt frame claims: the good frame behind it decodes on arrival.
      auto rest = decodeAll(d, c);
      got.insert(got.end(), rest.begin(), rest.end());
      ASSERT_EQ(got.size(), 2u);
      EXPECT_EQ(got[0], before);
      EXPECT_EQ(got[1], after);
      EXPECT_EQ(d.stats().framesOk, 2u);
      EXPECT_EQ(d.stats().bytesInFrames, a.size() + c.size());
      EXPECT_EQ(d.stats().bytesSkipped, b.size());
      if (byte >= 2) {
        EXPECT_GE(d.stats().headerCrcErrors + d.stats().crcErrors, 1u);
      }
      if (byte >= 2 && byte < kFrameHeaderSize) {
        EXPECT_GE(d.stats().headerCrcErrors, 1u);
      }
      if (byte >= kFrameHeaderSize) {
        EXPECT_EQ(d.stats().crcErrors, 1u);
      }
      expectStatsAddUp(d);
    }
  }
}

TEST(BinaryProtocol, TruncatedFramesAreDroppedAndTheStreamResynchronises) {
  const Message first{1, 0, msg::Poll{}};
  Sample s1 = testSample(10, 8, 16), s2 = testSample(11, 8, 16);
  s1.flags.fill(ChannelFlag::Valid);  // sent without flags: decoded as Valid
  s2.flags.fill(ChannelFlag::Valid);
  const Bytes a = encode(first), b = encode(sampleMessage(s1, 16, false, false));
  const Bytes c = encode(sampleMessage(s2, 16, false, false));
  ASSERT_EQ(b.size(), c.size());
  for (size_t keep = 1; keep < b.size(); ++keep) {
    SCOPED_TRACE("kept " + std::to_string(keep));
    Bytes stream = a;
    stream.insert(stream.end(), b.begin(), b.begin() + static_cast<std::ptrdiff_t>(keep));
    stream.insert(stream.end(), c.begin(), c.end());
    BinaryDecoder d;
    const auto got = decodeChunked(d, stream, [] { return size_t{5}; });
    ASSERT_EQ(got.size(), 2u);
    EXPECT_EQ(got[0], first);
    EXPECT_EQ(std::get<msg::SampleFrame>(got[1].payload).sample, s2);
    EXPECT_EQ(d.stats().bytesSkipped, keep);
    // Sample 10 never arrived, so 11 is not a gap: nothing before it was seen.
    EXPECT_EQ(d.stats().sequenceGaps, 0u);
    expectStatsAddUp(d);
  }
  // A frame cut off at the end of input waits; reset() (after a timeout) drops it.
  BinaryDecoder d;
  d.feed(std::span(b).first(20));
  EXPECT_FALSE(d.next());
  EXPECT_EQ(d.buffered(), 20u);
  d.reset();
  EXPECT_EQ(d.stats().bytesSkipped, 20u);
  d.feed(std::span(b).subspan(20));  // the rest alone is garbage
  d.feed(c);
  auto m = d.next();
  ASSERT_TRUE(m);
  EXPECT_EQ(std::get<msg::SampleFrame>(m->payload).sample, s2);
  EXPECT_EQ(d.stats().bytesSkipped, b.size());
}

TEST(BinaryProtocol, OversizeLengthFieldsAreRejectedWithoutWaiting) {
  const Bytes good = encode({9, 0, msg::Poll{}});
  for (size_t claimed : {kMaxPayloadSize + 1, size_t{0xFFFF}}) {
    // Header CRC valid, length too large: rejected at once.
    Bytes stream = rawFrame(1, 0x83, 0, 1, {}, claimed);
    stream.resize(kFrameHeaderSize);
    stream.insert(stream.end(), good.begin(), good.end());
    BinaryDecoder d;
    const auto got = decodeAll(d, stream);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].sequence, 9u);
    EXPECT_EQ(d.stats().oversizeFrames, 1u);
    EXPECT_EQ(d.stats().bytesSkipped, kFrameHeaderSize);
  }
  // Exactly the maximum is legal framing (here an unknown type, skipped whole).
  Bytes stream = rawFrame(1, 0x7E, 0, 1, Bytes(kMaxPayloadSize, 0xA5));
  stream.insert(stream.end(), good.begin(), good.end());
  BinaryDecoder d;
  EXPECT_EQ(decodeChunked(d, stream, [] { return size_t{100}; }).size(), 1u);
  EXPECT_EQ(d.stats().unknownTypes, 1u);
  EXPECT_EQ(d.stats().bytesInFrames, stream.size());
  EXPECT_EQ(d.stats().bytesSkipped, 0u);
}

TEST(BinaryProtocol, UnknownTypesAndVersionsAndMalformedPayloadsAreSkippedWhole) {
  const Bytes good = encode({9, 0, msg::Poll{}});
  struct Case {
    Bytes frame;
    uint64_t BinaryDecoderStats::*counter;
  };
  const Bytes validSample = {2, 8, 0, 0x11, 0x22};  // 2 channels, 8 bits
  std::vector<Case> cases = {
      {rawFrame(1, 0x06, 0, 0, {}), &BinaryDecoderStats::unknownTypes},
      {rawFrame(1, 0x80, 0, 0, {1}), &BinaryDecoderStats::unknownTypes},
      {rawFrame(2, 0x83, 0, 0, {}), &BinaryDecoderStats::unsupportedVersions},
      {rawFrame(0, 0x03, 0, 0, validSample), &BinaryDecoderStats::unsupportedVersions},
      {rawFrame(1, 0x03, 0, 0, {2, 8, 0, 0x11}), &BinaryDecoderStats::malformedFrames},        // short
      {rawFrame(1, 0x03, 0, 0, {2, 8, 0, 0x11, 0x22, 0}), &BinaryDecoderStats::malformedFrames},  // long
      {rawFrame(1, 0x03, 0, 0, {0, 8, 0}), &BinaryDecoderStats::malformedFrames},              // 0 channels
      {rawFrame(1, 0x03, 0, 0, {65, 8, 0}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x03, 0, 0, {1, 33, 0, 0, 0, 0, 0, 0}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x03, 0, 0, {2, 8, 4, 0x11, 0x22}), &BinaryDecoderStats::malformedFrames},  // reserved bit
      {rawFrame(1, 0x03, 0, 0, {1, 4, 0, 0x1F}), &BinaryDecoderStats::malformedFrames},        // padding bits
      {rawFrame(1, 0x03, 0, 0, {1, 4, 2, 0x0F, 0x03}), &BinaryDecoderStats::malformedFrames},  // flag 3
      {rawFrame(1, 0x03, 0, 0, {1, 4, 2, 0x0F, 0x04}), &BinaryDecoderStats::malformedFrames},  // flag padding
      {rawFrame(1, 0x03, 0, 0, {1, 8, 1, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 7}),
       &BinaryDecoderStats::malformedFrames},  // device time overflows int64 ns
      {rawFrame(1, 0x82, 0, 0, {0}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x84, 0, 0, {0, 0}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x84, 0, 0, {1}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x04, 0, 0, {}), &BinaryDecoderStats::malformedFrames},
      {rawFrame(1, 0x05, 0, 0, {0x84, 3, 5, 'a'}), &BinaryDecoderStats::malformedFrames},  // string runs out
      {rawFrame(1, 0x02, 0, 0, {2, 12, 0, 0, 0, 0, 1, 0}), &BinaryDecoderStats::malformedFrames},  // 1 name of 2
      {rawFrame(1, 0x02, 0, 0, {2, 12, 0, 0, 0, 0, 0, 9}), &BinaryDecoderStats::malformedFrames},  // trailing byte
  };
  for (size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    Bytes stream = cases[i].frame;
    stream.insert(stream.end(), good.begin(), good.end());
    BinaryDecoder d;
    const auto got = decodeAll(d, stream);
    ASSERT_EQ(got.size(), 1u);
    EXPECT_EQ(got[0].sequence, 9u);
    EXPECT_EQ(d.stats().*cases[i].counter, 1u);
    EXPECT_EQ(d.stats().bytesInFrames, stream.size());  // framing was fine: nothing skipped
    EXPECT_EQ(d.stats().framesOk + d.stats().malformedFrames + d.stats().unknownTypes +
                  d.stats().unsupportedVersions,
              2u);
  }
  // The well-formed version of the sample payload above decodes (so the cases fail for the stated reason).
  BinaryDecoder d;
  d.feed(rawFrame(1, 0x03, 0, 0, validSample));
  auto m = d.next();
  ASSERT_TRUE(m);
  EXPECT_EQ(std::get<msg::SampleFrame>(m->payload).sample.counts[1], 0x22u);
}

TEST(BinaryProtocol, SequenceGapsWrapAndResetsAreCounted) {
  auto run = [](std::initializer_list<int64_t> sequences) {  // -1 stands for a Hello
    Bytes stream;
    for (int64_t q : sequences) {
      const Bytes f = q < 0 ? encode({0, 0, msg::Hello{1, testInfo()}})
                            : encode(sampleMessage(testSample(static_cast<uint32_t>(q), 2, 8), 8, false, false));
      stream.insert(stream.end(), f.begin(), f.end());
    }
    BinaryDecoder d;
    decodeAll(d, stream);
    return d.stats();
  };
  auto s = run({0, 1, 2, 5, 6, 10});
  EXPECT_EQ(s.sequenceGaps, 2u);
  EXPECT_EQ(s.samplesDropped, 5u);
  EXPECT_EQ(s.sequenceResets, 0u);
  s = run({0xFFFFFFFE, 0xFFFFFFFF, 0, 1});
  EXPECT_EQ(s.sequenceGaps, 0u);
  EXPECT_EQ(s.sequenceResets, 0u);
  s = run({0xFFFFFFFF, 1});
  EXPECT_EQ(s.sequenceGaps, 1u);
  EXPECT_EQ(s.samplesDropped, 1u);
  s = run({10, 11, 3, 4});
  EXPECT_EQ(s.sequenceResets, 1u);
  EXPECT_EQ(s.sequenceGaps, 0u);
  s = run({10, 11, -1, 0, 1});  // the device rebooted and said hello: not a reset
  EXPECT_EQ(s.sequenceResets, 0u);
  EXPECT_EQ(s.samples, 4u);
}

// Issue 14 item 4: a repeated frame is one sample, counted as a duplicate (it used to be returned twice).
TEST(BinaryProtocol, RepeatedSampleIsReturnedOnceAndCounted) {
  const Bytes a = encode(sampleMessage(testSample(4, 2, 8), 8, false, false));
  const Bytes b = encode(sampleMessage(testSample(5, 2, 8), 8, false, false));
  Bytes stream = a;
  stream.insert(stream.end(), a.begin(), a.end());
  stream.insert(stream.end(), b.begin(), b.end());
  BinaryDecoder d;
  const auto got = decodeAll(d, stream);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].sequence, 4u);
  EXPECT_EQ(got[1].sequence, 5u);
  const auto& s = d.stats();
  EXPECT_EQ(s.duplicateSamples, 1u);
  EXPECT_EQ(s.samples, 2u);
  EXPECT_EQ(s.sequenceResets, 0u);
  EXPECT_EQ(s.framesOk + s.malformedFrames + s.unknownTypes + s.unsupportedVersions + s.duplicateSamples, 3u);
}

// Issue 14 item 2: only an unsolicited HELLO (a reboot) restarts sequence tracking; the HELLO answering HOST_HELLO
// after a reconnect, a timeout's resync() and a reconnect's discard() keep it, so lost samples are counted.
TEST(BinaryProtocol, OnlyAnUnsolicitedHelloRestartsSequenceTracking) {
  auto sample = [](uint32_t q) { return encode(sampleMessage(testSample(q, 2, 8), 8, false, false)); };
  BinaryDecoder d;
  decodeAll(d, sample(10));
  decodeAll(d, encode({3, kFlagReply, msg::Hello{1, testInfo()}}));  // answer to HOST_HELLO: not a reboot
  decodeAll(d, sample(15));
  EXPECT_EQ(d.stats().samplesDropped, 4u);
  d.resync();
  d.discard();
  decodeAll(d, sample(20));
  EXPECT_EQ(d.stats().samplesDropped, 8u);
  decodeAll(d, encode({0, 0, msg::Hello{1, testInfo()}}));  // unasked: the device rebooted
  decodeAll(d, sample(0));
  EXPECT_EQ(d.stats().samplesDropped, 8u);
  EXPECT_EQ(d.stats().sequenceResets, 0u);
  d.reset();  // forgets the sequence too
  decodeAll(d, sample(7));
  EXPECT_EQ(d.stats().samplesDropped, 8u);
}

// Issue 14 item 3: in poll mode nothing follows a header that claims more bytes than will ever come. After the
// timeout, resync() drops its sync byte and the intact sample behind it is found.
TEST(BinaryProtocol, ResyncRescansBytesBehindAHeaderThatNeverCompletes) {
  const Bytes forged = rawFrame(1, 0x03, kFlagReply, 9, Bytes(2000, 0x11));
  Bytes stream(forged.begin(), forged.begin() + kFrameHeaderSize);  // a valid header claiming 2000 bytes
  const Sample intact = testSample(9, 4, 12);
  const Bytes good = encode(sampleMessage(intact, 12, false, true, kFlagReply));
  stream.insert(stream.end(), good.begin(), good.end());
  BinaryDecoder d;
  d.feed(stream, 5);
  EXPECT_FALSE(d.next());  // waiting for the 2000 bytes
  d.resync();
  auto m = d.next();
  ASSERT_TRUE(m);
  Sample got = std::get<msg::SampleFrame>(m->payload).sample;
  EXPECT_EQ(got.arrivalTimeNs, 5);
  got.arrivalTimeNs = intact.arrivalTimeNs;
  EXPECT_EQ(got, intact);
  EXPECT_EQ(d.stats().truncatedFrames, 1u);
  EXPECT_EQ(d.stats().bytesSkipped, kFrameHeaderSize);
  EXPECT_EQ(d.buffered(), 0u);
  d.resync();  // nothing buffered: nothing to abandon
  EXPECT_EQ(d.stats().truncatedFrames, 1u);
}

TEST(BinaryProtocol, ArrivalTimeIsThatOfTheChunkCompletingTheFrame) {
  const Bytes f = encode(sampleMessage(testSample(1, 4, 12), 12, false, false));
  BinaryDecoder d;
  d.feed(std::span(f).first(10), 100);
  EXPECT_FALSE(d.next());
  d.feed(std::span(f).subspan(10), 200);
  auto m = d.next();
  ASSERT_TRUE(m);
  EXPECT_EQ(std::get<msg::SampleFrame>(m->payload).sample.arrivalTimeNs, 200);
}

TEST(BinaryProtocol, DecodingSamplesDoesNotAllocateOnceWarm) {
  std::vector<Message> messages;
  for (uint32_t q = 0; q < 1000; ++q) {
    Sample s = testSample(q, 64, 16);
    s.deviceTimeNs = q * 1000000;
    messages.push_back(sampleMessage(s, 16, true, true));
  }
  const Bytes stream = streamOf(messages);
  BinaryDecoder d;
  d.feed(std::span(stream).first(4096));  // warm up: the buffer reaches its working size
  while (d.next()) {
  }
  std::mt19937 rng(3);
  size_t at = 4096;
  uint64_t decoded = d.stats().framesOk;
  const long before = tAllocations;
  while (at < stream.size()) {
    const size_t n = std::min<size_t>(stream.size() - at, 1 + rng() % 4096);
    d.feed(std::span(stream).subspan(at, n));
    at += n;
    while (auto m = d.next()) ++decoded;
  }
  EXPECT_EQ(tAllocations - before, 0);
  EXPECT_EQ(decoded, messages.size());
}

TEST(BinaryProtocol, MessageTypeMatchesPayload) {
  EXPECT_EQ((Message{0, 0, msg::Hello{}}).type(), MessageType::Hello);
  EXPECT_EQ((Message{0, 0, msg::SampleFrame{}}).type(), MessageType::Sample);
  EXPECT_EQ((Message{0, 0, msg::StopStream{}}).type(), MessageType::StopStream);
  EXPECT_EQ((Message{0, 0, msg::HostHello{}}).type(), MessageType::HostHello);
}

// The bare DeviceInfo block (a USB armature's INFO control request) is exactly INFO's payload.
TEST(BinaryProtocol, DeviceInfoBlockIsTheInfoPayload) {
  DeviceInfo info;
  info.name = "IMPS USB Monkey";
  info.serialNumber = "U1";
  info.firmwareVersion = "2.0";
  info.channelCount = 3;
  info.bitsPerChannel = 12;
  info.channelNames = {"hip", "knee", "ankle"};
  info.hasDeviceTimestamp = true;
  auto block = encodeDeviceInfo(info);
  ASSERT_TRUE(block) << block.error().str();
  std::vector<uint8_t> frame;
  ASSERT_TRUE(appendFrame(Message{0, kFlagReply, msg::Info{info}}, frame));
  ASSERT_EQ(frame.size(), kFrameHeaderSize + block->size() + kFrameCrcSize);
  EXPECT_TRUE(std::equal(block->begin(), block->end(), frame.begin() + kFrameHeaderSize));
  auto back = decodeDeviceInfo(*block);
  ASSERT_TRUE(back) << back.error().str();
  EXPECT_EQ(*back, info);

  std::vector<uint8_t> longer = *block;
  longer.push_back(0);  // a trailing byte is malformed, as in INFO
  EXPECT_FALSE(decodeDeviceInfo(longer));
  for (size_t n = 0; n < block->size(); ++n)  // so is every truncation
    EXPECT_FALSE(decodeDeviceInfo(std::span(block->data(), n))) << n;
  info.channelCount = 0;
  EXPECT_FALSE(encodeDeviceInfo(info));
}

}  // namespace
}  // namespace imps::drivers
