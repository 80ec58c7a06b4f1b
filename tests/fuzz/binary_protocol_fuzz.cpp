// SPDX-License-Identifier: MIT
// libFuzzer target for the binary protocol decoder (drivers/binary_protocol): arbitrary bytes in arbitrary chunks
// must never crash, and must keep the decoder's invariants (docs/protocol.md).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "drivers/binary_protocol.h"

#include "fuzz_check.h"

using namespace imps::drivers;

namespace {

void checkStats(const BinaryDecoder& d) {
  const auto& s = d.stats();
  FUZZ_CHECK(s.bytesReceived == s.bytesInFrames + s.bytesSkipped + d.buffered());
  FUZZ_CHECK(s.samples <= s.framesOk);
  FUZZ_CHECK(s.samplesDropped >= s.sequenceGaps);
}

void checkMessage(const Message& m, std::span<const uint8_t> frame) {
  if (const auto* f = std::get_if<msg::SampleFrame>(&m.payload)) {
    const Sample& s = f->sample;
    FUZZ_CHECK(s.channelCount >= 1 && s.channelCount <= kMaxChannels);
    FUZZ_CHECK(f->bitsPerChannel >= 1 && f->bitsPerChannel <= 32);
    FUZZ_CHECK(s.sequence == m.sequence);
    FUZZ_CHECK(s.deviceTimeNs >= 0);
    for (int i = 0; i < kMaxChannels; ++i) {
      if (i < s.channelCount) {
        FUZZ_CHECK(static_cast<uint64_t>(s.counts[i]) < (uint64_t{1} << f->bitsPerChannel));
        FUZZ_CHECK(static_cast<uint8_t>(s.flags[i]) <= 2);
      } else {
        FUZZ_CHECK(s.counts[i] == 0 && s.flags[i] == ChannelFlag::Valid);
      }
    }
  }
  const DeviceInfo* info = nullptr;
  if (const auto* h = std::get_if<msg::Hello>(&m.payload)) info = &h->info;
  if (const auto* i = std::get_if<msg::Info>(&m.payload)) info = &i->info;
  if (info) {
    FUZZ_CHECK(info->channelCount >= 1 && info->channelCount <= kMaxChannels);
    FUZZ_CHECK(static_cast<int>(info->channelNames.size()) == info->channelCount);
  }
  // Whatever decodes re-encodes, and decodes back to the same message (arrival time is not on the wire).
  std::vector<uint8_t> again;
  FUZZ_CHECK(appendFrame(m, again).has_value());
  FUZZ_CHECK(again.size() <= kMaxFrameSize);
  // Byte-exact except where the format allows two spellings (explicit default channel names, ignored
  // capability bits in DeviceInfo).
  if (!info) FUZZ_CHECK(std::equal(again.begin(), again.end(), frame.begin(), frame.end()));
  BinaryDecoder d;
  d.feed(again, std::holds_alternative<msg::SampleFrame>(m.payload)
                    ? std::get<msg::SampleFrame>(m.payload).sample.arrivalTimeNs
                    : 0);
  auto back = d.next();
  FUZZ_CHECK(back.has_value());
  FUZZ_CHECK(*back == m);
  FUZZ_CHECK(!d.next());
}

// Random bytes almost never carry valid CRCs, so the payload parsers are reached mostly through this second view
// of the input: records [type][flags][length u16][payload] wrapped into frames with correct CRCs. Every such
// frame must be consumed whole (never resynchronised over) and be accepted or counted.
void fuzzPayloads(std::span<const uint8_t> in) {
  std::vector<uint8_t> stream;
  size_t frames = 0;
  while (in.size() >= 4) {
    const uint8_t type = in[0], flags = in[1];
    const size_t length = std::min<size_t>({static_cast<size_t>(in[2] | (in[3] << 8)), in.size() - 4,
                                            kMaxPayloadSize});
    const uint8_t version = (flags & 0x80) && (flags & 0x40) ? 2 : kProtocolVersion;
    std::vector<uint8_t> f = {kSync0, kSync1, version, type, flags, static_cast<uint8_t>(frames), 0, 0, 0,
                              static_cast<uint8_t>(length), static_cast<uint8_t>(length >> 8)};
    const uint16_t hc = crc16CcittFalse(std::span(f).subspan(2));
    f.push_back(static_cast<uint8_t>(hc));
    f.push_back(static_cast<uint8_t>(hc >> 8));
    f.insert(f.end(), in.begin() + 4, in.begin() + 4 + static_cast<std::ptrdiff_t>(length));
    const uint16_t fc = crc16CcittFalse(std::span(f).subspan(2));
    f.push_back(static_cast<uint8_t>(fc));
    f.push_back(static_cast<uint8_t>(fc >> 8));
    stream.insert(stream.end(), f.begin(), f.end());
    ++frames;
    in = in.subspan(4 + length);
  }
  BinaryDecoder d;
  d.feed(stream);
  size_t ok = 0;
  while (auto m = d.next()) {
    checkMessage(*m, d.lastFrame());
    ++ok;
  }
  const auto& s = d.stats();
  checkStats(d);
  FUZZ_CHECK(s.framesOk == ok);
  FUZZ_CHECK(s.bytesSkipped == 0 && d.buffered() == 0 && s.bytesInFrames == stream.size());
  FUZZ_CHECK(s.framesOk + s.malformedFrames + s.unknownTypes + s.unsupportedVersions + s.duplicateSamples == frames);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  fuzzPayloads(std::span(data + 1, size - 1));
  // The first byte seeds the chunking; the rest is the stream.
  uint32_t rng = data[0] * 2654435761u + 1;
  std::span<const uint8_t> stream(data + 1, size - 1);

  BinaryDecoder whole;
  whole.feed(stream, 1);
  std::vector<Message> expected;
  while (auto m = whole.next()) {
    checkMessage(*m, whole.lastFrame());
    expected.push_back(std::move(*m));
  }
  checkStats(whole);
  FUZZ_CHECK(whole.stats().framesOk == expected.size());
  FUZZ_CHECK(whole.buffered() < kMaxFrameSize);

  // The same bytes in random chunks decode to the same messages and the same counters.
  BinaryDecoder chunked;
  size_t at = 0, got = 0;
  while (at < stream.size()) {
    rng = rng * 1103515245u + 12345u;
    const size_t n = std::min<size_t>(stream.size() - at, 1 + (rng >> 16) % 64);
    chunked.feed(stream.subspan(at, n), 1);
    at += n;
    while (auto m = chunked.next()) {
      FUZZ_CHECK(got < expected.size() && *m == expected[got]);
      ++got;
    }
    checkStats(chunked);
    FUZZ_CHECK(chunked.buffered() < kMaxFrameSize);
  }
  FUZZ_CHECK(got == expected.size());
  FUZZ_CHECK(chunked.stats() == whole.stats());

  chunked.reset();
  checkStats(chunked);
  FUZZ_CHECK(chunked.buffered() == 0);
  return 0;
}
