// SPDX-License-Identifier: MIT
// The DIY line protocol decoder: banner, sample lines, timestamps, channel-count locking (docs/protocol.md).
#include "drivers/line_protocol.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace imps::drivers {
namespace {

bool isBlank(char c) { return c == ' ' || c == '\t'; }
bool isDigit(char c) { return c >= '0' && c <= '9'; }
bool isTerminator(uint8_t c) { return c == '\n' || c == '\r'; }

// Parses an unsigned decimal of at most `limit`; advances p past the digits. False on no digits or overflow.
bool parseUnsigned(const char*& p, const char* end, uint64_t limit, uint64_t& value) {
  if (p == end || !isDigit(*p)) return false;
  uint64_t v = 0;
  while (p != end && isDigit(*p)) {
    const auto d = static_cast<uint64_t>(*p - '0');
    if (v > (limit - d) / 10) return false;
    v = v * 10 + d;
    ++p;
  }
  value = v;
  return true;
}

// Consumes a field separator: blanks, at most one comma, blanks. Returns false when none was present.
bool skipSeparator(const char*& p, const char* end) {
  const char* start = p;
  while (p != end && isBlank(*p)) ++p;
  if (p != end && *p == ',') {
    ++p;
    while (p != end && isBlank(*p)) ++p;
  }
  return p != start;
}

}  // namespace

LineDecoder::LineDecoder(LineDecoderOptions options) : options_(options) {
  if (options_.maxLineLength == 0) options_.maxLineLength = 1;
  if (options_.expectedChannelCount < 0 || options_.expectedChannelCount > kMaxChannels)
    options_.expectedChannelCount = 0;
  channelCount_ = options_.expectedChannelCount;
  in_.reserve(options_.maxLineLength + 4096);
  const auto waiting = static_cast<size_t>(std::max({options_.settleLines, options_.relockAfter, 1}));
  pending_.reserve(waiting);
  ready_.reserve(waiting);
}

void LineDecoder::feed(std::span<const uint8_t> bytes, int64_t arrivalTimeNs) {
  stats_.bytesReceived += bytes.size();
  arrivalTimeNs_ = arrivalTimeNs;
  in_.append(bytes);  // after next() ran dry, at most one partial line (<= maxLineLength bytes) is left
}

void LineDecoder::skip(size_t n) {
  in_.consume(n);
  stats_.bytesSkipped += n;
}

void LineDecoder::reset() {
  skip(in_.size());
  in_.clear();
  discarding_ = false;
  if (seenSample_)
    dropPending();
  else
    pendingToBanner();
  ready_.clear();
  readyAt_ = 0;
  channelCount_ = options_.expectedChannelCount;
  seenSample_ = false;
  nextSequence_ = 0;
  banner_.clear();
}

bool LineDecoder::parseLine(const char* p, const char* end, Sample& out) const {
  while (p != end && isBlank(*p)) ++p;
  // Optional timestamp: `t=<digits>` with an optional unit, `us` (the default) or `ms`.
  if (p != end && (*p == 't' || *p == 'T')) {
    ++p;
    if (p == end || *p != '=') return false;
    ++p;
    uint64_t value = 0;
    if (!parseUnsigned(p, end, std::numeric_limits<uint64_t>::max(), value)) return false;
    uint64_t nsPerUnit = 1000;
    if (end - p >= 2 && p[0] == 'u' && p[1] == 's') {
      p += 2;
    } else if (end - p >= 2 && p[0] == 'm' && p[1] == 's') {
      p += 2;
      nsPerUnit = 1000000;
    }
    if (value > static_cast<uint64_t>(std::numeric_limits<int64_t>::max()) / nsPerUnit) return false;
    out.deviceTimeNs = static_cast<int64_t>(value * nsPerUnit);
    if (!skipSeparator(p, end)) return false;
  }
  int n = 0;
  while (p != end) {
    uint64_t value = 0;
    if (n == kMaxChannels || !parseUnsigned(p, end, std::numeric_limits<uint32_t>::max(), value)) return false;
    out.counts[n++] = static_cast<uint32_t>(value);
    // A number ends at a separator or the line end ("12a" is junk); after the last field, trailing blanks and
    // one trailing comma are allowed (Arduino sketches often print "v," in a loop).
    if (p != end && !skipSeparator(p, end)) return false;
  }
  if (n == 0) return false;
  out.channelCount = static_cast<uint16_t>(n);
  return true;
}

void LineDecoder::addBanner(const char* begin, const char* end) {
  ++stats_.bannerLines;
  if (banner_.size() < options_.maxBannerLines) banner_.emplace_back(begin, end);
}

// The lines that waited to settle the first layout disagree with what follows: they were banner after all.
void LineDecoder::pendingToBanner() {
  for (const std::string& text : pendingText_) addBanner(text.data(), text.data() + text.size());
  pending_.clear();
  pendingText_.clear();
  pendingJunk_ = 0;
}

// A run of lines of another channel count ended before it re-locked: they were mismatches.
void LineDecoder::dropPending() {
  stats_.channelCountMismatches += pending_.size();
  pending_.clear();
}

// Numbers a sample and counts it.
std::optional<Sample> LineDecoder::accept(Sample s) {
  seenSample_ = true;
  s.sequence = nextSequence_++;
  ++stats_.samples;
  return s;
}

// Queues a well-formed line of a not-yet-adopted channel count (a new run drops the previous one).
std::optional<Sample> LineDecoder::hold(const Sample& s, const char* begin, const char* end) {
  if (!pending_.empty() && pending_.front().channelCount != s.channelCount) {
    if (seenSample_)
      dropPending();
    else
      pendingToBanner();
  }
  pending_.push_back(s);
  if (!seenSample_) pendingText_.emplace_back(begin, end);
  const int needed = seenSample_ ? options_.relockAfter : std::max(options_.settleLines, 1);
  if (static_cast<int>(pending_.size()) < needed) return std::nullopt;
  if (seenSample_) ++stats_.channelCountChanges;
  channelCount_ = s.channelCount;
  return releasePending();
}

// The waiting run settled its layout: its lines become samples, in order.
std::optional<Sample> LineDecoder::releasePending() {
  ready_.clear();
  readyAt_ = 0;
  for (const Sample& p : pending_) ready_.push_back(*accept(p));
  stats_.malformedLines += pendingJunk_;  // junk between the lines that settled the layout is junk in the data
  pendingJunk_ = 0;
  pending_.clear();
  pendingText_.clear();
  return ready_.empty() ? std::nullopt : std::optional<Sample>(ready_[readyAt_++]);
}

std::optional<Sample> LineDecoder::acceptLine(const char* begin, const char* end) {
  ++stats_.lines;
  Sample s;
  const bool wellFormed = parseLine(begin, end, s);
  s.arrivalTimeNs = arrivalTimeNs_;
  const bool inferring = options_.expectedChannelCount == 0;
  if (!seenSample_) {
    // Before the first layout, anything that is not an acceptable sample line is banner. Junk among lines waiting
    // to settle a layout waits with them: malformed if they settle it, banner with them if they do not.
    if (inferring && !wellFormed && !pending_.empty()) {
      pendingText_.emplace_back(begin, end);
      ++pendingJunk_;
      return std::nullopt;
    }
    if (!wellFormed || (!inferring && s.channelCount != channelCount_)) {
      addBanner(begin, end);
      return std::nullopt;
    }
    if (!inferring) return accept(s);
    return hold(s, begin, end);
  }
  if (!wellFormed) {
    ++stats_.malformedLines;
    return std::nullopt;
  }
  if (s.channelCount == channelCount_) {
    dropPending();
    return accept(s);
  }
  if (inferring && options_.relockAfter > 0) return hold(s, begin, end);
  ++stats_.channelCountMismatches;
  return std::nullopt;
}

std::optional<Sample> LineDecoder::next() {
  for (;;) {
    if (readyAt_ < ready_.size()) return ready_[readyAt_++];
    if (in_.size() == 0) return std::nullopt;
    const uint8_t* base = in_.data();
    if (discarding_) {
      size_t i = in_.begin();
      while (i != in_.end() && !isTerminator(base[i])) ++i;
      if (i == in_.end()) {
        skip(in_.size());
        return std::nullopt;
      }
      skip(i + 1 - in_.begin());
      discarding_ = false;
      continue;
    }
    // Look for a terminator no further than one byte past the longest acceptable line.
    const size_t window = std::min(in_.size(), options_.maxLineLength + 1);
    size_t i = in_.begin();
    while (i != in_.begin() + window && !isTerminator(base[i])) ++i;
    if (i == in_.begin() + window) {
      if (window <= options_.maxLineLength) return std::nullopt;  // a line still arriving
      // Overlong: count it once and drop it up to its terminator, however many chunks that takes.
      ++stats_.lines;
      ++stats_.overlongLines;
      discarding_ = true;
      skip(window);
      continue;
    }
    const char* begin = reinterpret_cast<const char*>(base + in_.begin());
    const char* end = reinterpret_cast<const char*>(base + i);
    stats_.bytesInLines += i + 1 - in_.begin();
    in_.consume(i + 1 - in_.begin());
    const char* q = begin;
    while (q != end && isBlank(*q)) ++q;
    if (q == end) continue;  // blank line, or the LF of a CRLF
    if (auto s = acceptLine(begin, end)) return s;
  }
}

}  // namespace imps::drivers
