// SPDX-License-Identifier: MIT
// libFuzzer target for the line protocol decoder (drivers/line_protocol): arbitrary text in arbitrary chunks must
// never crash, and must keep the decoder's invariants (docs/protocol.md).
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "drivers/line_protocol.h"

#include "fuzz_check.h"

using namespace imps::drivers;

namespace {

void checkStats(const LineDecoder& d) {
  const auto& s = d.stats();
  FUZZ_CHECK(s.bytesReceived == s.bytesInLines + s.bytesSkipped + d.buffered());
  FUZZ_CHECK(s.lines == s.samples + s.bannerLines + s.malformedLines + s.channelCountMismatches + s.overlongLines +
                            d.pendingLines());
  FUZZ_CHECK(d.banner().size() <= d.options().maxBannerLines);
  FUZZ_CHECK(d.channelCount() >= 0 && d.channelCount() <= kMaxChannels);
}

void checkSample(const LineDecoder& d, const Sample& s, uint32_t expectedSequence) {
  FUZZ_CHECK(s.channelCount >= 1 && s.channelCount <= kMaxChannels);
  FUZZ_CHECK(s.channelCount == d.channelCount());
  FUZZ_CHECK(s.sequence == expectedSequence);
  FUZZ_CHECK(s.deviceTimeNs >= 0);
  for (int i = s.channelCount; i < kMaxChannels; ++i) FUZZ_CHECK(s.counts[i] == 0);
  for (auto f : s.flags) FUZZ_CHECK(f == ChannelFlag::Valid);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 2) return 0;
  // Byte 0 picks the options and seeds the chunking; the rest is the stream.
  LineDecoderOptions options;
  options.maxLineLength = 8 + (data[0] & 0x3F) * 16;
  options.relockAfter = (data[0] >> 6) & 3;
  options.expectedChannelCount = (data[1] & 0x80) ? (data[1] & 7) : 0;
  uint32_t rng = data[1] * 2654435761u + 1;
  std::span<const uint8_t> stream(data + 2, size - 2);

  LineDecoder whole(options);
  whole.feed(stream, 5);
  std::vector<Sample> expected;
  while (auto s = whole.next()) {
    checkSample(whole, *s, static_cast<uint32_t>(expected.size()));
    expected.push_back(*s);
  }
  checkStats(whole);
  FUZZ_CHECK(whole.stats().samples == expected.size());
  FUZZ_CHECK(whole.buffered() <= options.maxLineLength);

  LineDecoder chunked(options);
  size_t at = 0, got = 0;
  while (at < stream.size()) {
    rng = rng * 1103515245u + 12345u;
    const size_t n = std::min<size_t>(stream.size() - at, 1 + (rng >> 16) % 32);
    chunked.feed(stream.subspan(at, n), 5);
    at += n;
    while (auto s = chunked.next()) {
      FUZZ_CHECK(got < expected.size() && *s == expected[got]);
      ++got;
    }
    checkStats(chunked);
    FUZZ_CHECK(chunked.buffered() <= options.maxLineLength);
  }
  FUZZ_CHECK(got == expected.size());
  FUZZ_CHECK(chunked.stats() == whole.stats());
  FUZZ_CHECK(chunked.banner() == whole.banner());
  return 0;
}
