// SPDX-License-Identifier: MIT
// The plain-text line protocol of DIY (Arduino) armatures: one line of unsigned integers per sample, with an
// optional `t=` timestamp, after an optional boot banner. Format: docs/protocol.md, "Line protocol".
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/receive_buffer.h"

#include "drivers/sample.h"

namespace imps::drivers {

struct LineDecoderOptions {
  // Longest line accepted, in bytes without its terminator. A longer line is discarded up to its terminator
  // (counted in overlongLines / bytesSkipped); nothing longer than this is ever buffered for one line.
  size_t maxLineLength = 1024;
  // Channels per sample; 0 infers it: the first layout is settled once settleLines consecutive well-formed lines
  // agree on a channel count (they become the first samples; lines before them are banner, so a numeric banner
  // line such as `115200` is not taken for a 1-channel sample).
  int expectedChannelCount = 0;
  // When inferring, consecutive agreeing lines that settle the first layout (1: the first well-formed line does).
  int settleLines = 2;
  // When inferring, this many consecutive lines that agree on another channel count make the decoder adopt that
  // count (a device reconfigured, or numeric banner lines were taken for the first samples); the agreeing lines
  // become samples of the new layout, none is lost. 0 never re-locks.
  int relockAfter = 8;
  // Banner lines kept for banner(); further banner lines are only counted.
  size_t maxBannerLines = 32;
};

// Every byte fed ends up in exactly one of bytesInLines, bytesSkipped or LineDecoder::buffered(), and every
// terminated non-blank line is exactly one of samples, bannerLines, malformedLines, channelCountMismatches,
// overlongLines, or LineDecoder::pendingLines() (well-formed lines waiting to settle or re-lock a layout):
//   bytesReceived == bytesInLines + bytesSkipped + buffered()
//   lines == samples + bannerLines + malformedLines + channelCountMismatches + overlongLines + pendingLines()
struct LineDecoderStats {
  uint64_t bytesReceived = 0;
  uint64_t bytesInLines = 0;  // bytes of accepted-length lines and of line terminators
  uint64_t bytesSkipped = 0;  // bytes of overlong lines (and their terminators), and bytes dropped by reset()
  uint64_t lines = 0;         // non-blank lines seen (blank lines are ignored, not counted)
  uint64_t samples = 0;       // lines accepted as a Sample (returned by next())
  uint64_t bannerLines = 0;   // lines before the first layout settled that are not among its first samples
  uint64_t malformedLines = 0;  // after the first sample: not a list of unsigned integers
  uint64_t channelCountMismatches = 0;  // after the first sample: well-formed, but a different channel count
  uint64_t overlongLines = 0;
  uint64_t channelCountChanges = 0;  // re-locks to a new channel count (see LineDecoderOptions::relockAfter)
  // Lines counted as parse errors and skipped.
  uint64_t errors() const { return malformedLines + channelCountMismatches + overlongLines; }
  bool operator==(const LineDecoderStats&) const = default;
};

// Incremental decoder for the line protocol, fed byte chunks of any size split anywhere.
//
// Usage (one thread; not thread-safe): decoder.feed(chunk, nowNs); while (auto s = decoder.next()) …
// Memory is bounded by the largest chunk fed plus one maximum-length line; no allocation per byte or per sample
// once warmed up (banner lines are copied into banner()). Bad input is counted in stats() and skipped, never
// thrown. Samples get sequence 0, 1, 2 … in acceptance order (the format has no sequence numbers, so the
// protocol cannot detect lost lines), deviceTimeNs from `t=` (0 without), flags all Valid, arrivalTimeNs of the
// chunk that completed their line. When inferring the channel count, up to max(settleLines, relockAfter) lines
// wait until their layout settles (see LineDecoderOptions) and then come out of next() together.
class LineDecoder {
 public:
  explicit LineDecoder(LineDecoderOptions options = {});

  // Appends bytes; arrivalTimeNs becomes Sample::arrivalTimeNs of the samples they complete.
  void feed(std::span<const uint8_t> bytes, int64_t arrivalTimeNs = 0);

  // The next sample line, or nullopt when more bytes are needed.
  std::optional<Sample> next();

  // Forgets buffered bytes (counted as skipped), the banner, the channel count and the sequence; keeps stats.
  // Call when the device resets (an Arduino reboots when its port opens) so a new banner is accepted.
  void reset();

  // Channels per sample: the expected or inferred count, 0 before the first layout settled when inferring. Every
  // sample next() returns has this count at the time it is returned.
  int channelCount() const { return channelCount_; }
  // Lines waiting for their layout to settle (first samples, and junk among them) or to re-lock (a new count).
  size_t pendingLines() const { return pending_.size() + pendingJunk_; }
  // Banner lines (without terminators) seen before the first sample, at most maxBannerLines of them.
  const std::vector<std::string>& banner() const { return banner_; }
  size_t buffered() const { return in_.size(); }
  const LineDecoderStats& stats() const { return stats_; }
  const LineDecoderOptions& options() const { return options_; }

 private:
  // Parses one line (no terminator). Returns false when it is not a well-formed sample line.
  bool parseLine(const char* begin, const char* end, Sample& out) const;
  std::optional<Sample> acceptLine(const char* begin, const char* end);
  std::optional<Sample> accept(Sample s);
  std::optional<Sample> hold(const Sample& s, const char* begin, const char* end);
  std::optional<Sample> releasePending();
  void pendingToBanner();
  void dropPending();
  void addBanner(const char* begin, const char* end);
  void skip(size_t n);

  LineDecoderOptions options_;
  ReceiveBuffer in_;
  bool discarding_ = false;  // inside an overlong line: drop bytes up to the next terminator
  int64_t arrivalTimeNs_ = 0;
  int channelCount_ = 0;
  bool seenSample_ = false;
  std::vector<Sample> pending_;            // lines of one channel count waiting to settle or re-lock a layout
  std::vector<std::string> pendingText_;  // before the first layout: their text, in case they are banner after all
  size_t pendingJunk_ = 0;                // malformed lines among them (before the first layout)
  std::vector<Sample> ready_;             // settled samples not yet returned by next()
  size_t readyAt_ = 0;
  uint32_t nextSequence_ = 0;
  std::vector<std::string> banner_;
  LineDecoderStats stats_;
};

}  // namespace imps::drivers
