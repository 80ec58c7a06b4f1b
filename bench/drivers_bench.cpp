// SPDX-License-Identifier: MIT
// Benchmarks for the drivers' pure path: decode + hand-off cost per 64-channel sample (issue 4's goal: <= 2 µs),
// decoder throughput in MB/s, and the pieces on their own (encode, line decode, mailbox).
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "drivers/binary_protocol.h"
#include "drivers/line_protocol.h"
#include "drivers/pose_mailbox.h"

namespace {

using namespace imps::drivers;

Sample benchSample(uint32_t sequence, int channels, int bits) {
  Sample s;
  s.sequence = sequence;
  s.deviceTimeNs = static_cast<int64_t>(sequence) * 1000000;
  s.channelCount = static_cast<uint16_t>(channels);
  for (int i = 0; i < channels; ++i) {
    s.counts[i] = static_cast<uint32_t>((sequence * 2654435761u + static_cast<uint32_t>(i) * 40503u) &
                                        ((uint64_t{1} << bits) - 1));
    s.flags[i] = i % 17 == 0 ? ChannelFlag::Outlier : ChannelFlag::Valid;
  }
  return s;
}

// A stream of `frames` SAMPLE frames (with device time and per-channel flags) and each frame's end offset.
struct Stream {
  std::vector<uint8_t> bytes;
  std::vector<size_t> ends;
};
Stream sampleStream(int frames, int channels, int bits) {
  Stream s;
  for (int q = 0; q < frames; ++q) {
    if (!appendFrame(sampleMessage(benchSample(static_cast<uint32_t>(q), channels, bits),
                                   static_cast<uint8_t>(bits), true, true),
                     s.bytes))
      std::abort();
    s.ends.push_back(s.bytes.size());
  }
  return s;
}

// The I/O thread's whole job per sample, one frame per read (the worst case for per-call overhead): feed the
// bytes, decode, publish; plus the frame loop's take of the newest sample.
void BM_DecodeAndHandOffPerSample(benchmark::State& state) {
  const int channels = static_cast<int>(state.range(0)), bits = static_cast<int>(state.range(1));
  const Stream stream = sampleStream(1024, channels, bits);
  BinaryDecoder decoder;
  PoseMailbox mailbox;
  Sample newest;
  size_t frame = 0, begin = 0;
  int64_t fakeNow = 0;
  for (auto _ : state) {
    const size_t end = stream.ends[frame];
    decoder.feed(std::span(stream.bytes).subspan(begin, end - begin), ++fakeNow);
    while (auto m = decoder.next()) mailbox.publish(std::get<msg::SampleFrame>(m->payload).sample);
    benchmark::DoNotOptimize(mailbox.latest(newest));
    begin = end;
    if (++frame == stream.ends.size()) frame = begin = 0;
  }
  if (decoder.stats().malformedFrames + decoder.stats().crcErrors != 0) state.SkipWithError("decode errors");
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) *
                          static_cast<int64_t>(stream.bytes.size() / stream.ends.size()));
}
BENCHMARK(BM_DecodeAndHandOffPerSample)->Args({64, 16})->Args({64, 12})->Args({32, 12});

// Decoder throughput on 4 KiB reads (a transport's typical chunk).
void BM_BinaryDecodeThroughput(benchmark::State& state) {
  const Stream stream = sampleStream(4096, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  BinaryDecoder decoder;
  constexpr size_t kChunk = 4096;
  uint64_t frames = 0;
  for (auto _ : state) {
    for (size_t at = 0; at < stream.bytes.size(); at += kChunk) {
      decoder.feed(std::span(stream.bytes).subspan(at, std::min(kChunk, stream.bytes.size() - at)));
      while (auto m = decoder.next()) {
        benchmark::DoNotOptimize(m->sequence);
        ++frames;
      }
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.bytes.size()));
  state.SetItemsProcessed(static_cast<int64_t>(frames));
}
BENCHMARK(BM_BinaryDecodeThroughput)->Args({64, 16})->Args({32, 12});

void BM_EncodeSample(benchmark::State& state) {
  const Message m = sampleMessage(benchSample(1, 64, 16), 16, true, true);
  std::array<uint8_t, kMaxFrameSize> out{};
  for (auto _ : state) benchmark::DoNotOptimize(encodeFrame(m, out));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EncodeSample);

// The DIY text format: a 64-channel line of counts up to 4095 with a timestamp.
void BM_LineDecodeThroughput(benchmark::State& state) {
  std::string text;
  for (int q = 0; q < 1024; ++q) {
    text += "t=";  // appended piecewise: GCC 12 -O3 warns (-Wrestrict, a false positive) on "t=" + to_string()
    text += std::to_string(q * 1000);
    const Sample s = benchSample(static_cast<uint32_t>(q), 64, 12);
    for (int i = 0; i < 64; ++i) {
      text += ',';
      text += std::to_string(s.counts[i]);
    }
    text += "\r\n";
  }
  const auto bytes = std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size());
  LineDecoder decoder;
  uint64_t samples = 0;
  for (auto _ : state) {
    for (size_t at = 0; at < bytes.size(); at += 4096) {
      decoder.feed(bytes.subspan(at, std::min<size_t>(4096, bytes.size() - at)));
      while (auto s = decoder.next()) {
        benchmark::DoNotOptimize(s->counts[0]);
        ++samples;
      }
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
  state.SetItemsProcessed(static_cast<int64_t>(samples));
}
BENCHMARK(BM_LineDecodeThroughput);

// The mailbox alone, single-threaded: publish (with the in-order queue on) + take newest + drain.
void BM_MailboxPublishTakeDrain(benchmark::State& state) {
  PoseMailboxOptions options;
  options.queueCapacity = 1024;
  PoseMailbox mailbox(options);
  const Sample s = benchSample(1, 64, 16);
  Sample out;
  std::vector<Sample> drained;
  drained.reserve(64);
  for (auto _ : state) {
    mailbox.publish(s);
    benchmark::DoNotOptimize(mailbox.latest(out));
    if (mailbox.stats().queued - mailbox.stats().drained >= 64) {
      drained.clear();
      mailbox.drain(drained);
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MailboxPublishTakeDrain);

}  // namespace
