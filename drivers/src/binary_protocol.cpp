// SPDX-License-Identifier: MIT
// The IMPS armature binary protocol: CRC, frame encoder and resynchronising decoder (format: docs/protocol.md).
#include "drivers/binary_protocol.h"

#include "imps/check.h"
#include "text.h"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <type_traits>

namespace imps::drivers {
namespace {

constexpr std::array<uint16_t, 256> makeCrcTable() {
  std::array<uint16_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned crc = i << 8;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 0x8000u) ? (crc << 1) ^ 0x1021u : crc << 1;
    table[i] = static_cast<uint16_t>(crc);
  }
  return table;
}
constexpr std::array<uint16_t, 256> kCrcTable = makeCrcTable();

// Header field offsets (docs/protocol.md, "Frame").
constexpr size_t kOffVersion = 2, kOffType = 3, kOffFlags = 4, kOffSequence = 5, kOffLength = 9, kOffHeaderCrc = 11;

// SAMPLE payload flag bits.
constexpr uint8_t kSampleHasTime = 0x01, kSampleHasFlags = 0x02, kSampleKnownBits = 0x03;
// DeviceInfo capability bits.
constexpr uint8_t kCapDeviceTime = 0x01;

constexpr int64_t kMaxDeviceTimeUs = std::numeric_limits<int64_t>::max() / 1000;

uint16_t get16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t get32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}
uint64_t get64(const uint8_t* p) { return get32(p) | (static_cast<uint64_t>(get32(p + 4)) << 32); }
void put16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void put64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

size_t packedCountBytes(int channels, int bits) { return (static_cast<size_t>(channels) * bits + 7) / 8; }
size_t packedFlagBytes(int channels) { return (static_cast<size_t>(channels) + 3) / 4; }

std::string defaultChannelName(int i) { return "ch" + std::to_string(i); }

bool hasDefaultNames(const DeviceInfo& info) {
  if (info.channelNames.empty()) return true;
  for (int i = 0; i < static_cast<int>(info.channelNames.size()); ++i)
    if (info.channelNames[i] != defaultChannelName(i)) return false;
  return true;
}

// ---- Payload sizes and validation (encoder side) ----

// A message that cannot be encoded: one diagnostic without a position (the values are not from a file).
std::unexpected<Diagnostics> invalid(std::string message) { return diagnosticError({}, std::move(message)); }

std::expected<size_t, Diagnostics> deviceInfoSize(const DeviceInfo& info) {
  if (info.channelCount < 1 || info.channelCount > kMaxChannels)
    return invalid("DeviceInfo.channelCount " + std::to_string(info.channelCount) + " is outside 1.." +
                   std::to_string(kMaxChannels));
  if (info.bitsPerChannel < 1 || info.bitsPerChannel > 32)
    return invalid("DeviceInfo.bitsPerChannel " + std::to_string(info.bitsPerChannel) + " is outside 1..32");
  if (info.name.size() > kMaxDeviceNameSize) return invalid("DeviceInfo.name is longer than 63 bytes");
  if (info.serialNumber.size() > kMaxSerialNumberSize)
    return invalid("DeviceInfo.serialNumber is longer than 63 bytes");
  if (info.firmwareVersion.size() > kMaxFirmwareVersionSize)
    return invalid("DeviceInfo.firmwareVersion is longer than 31 bytes");
  if (!info.channelNames.empty() && static_cast<int>(info.channelNames.size()) != info.channelCount)
    return invalid("DeviceInfo.channelNames has " + std::to_string(info.channelNames.size()) +
                   " entries; expected 0 or channelCount (" + std::to_string(info.channelCount) + ")");
  size_t size = 3 + 1 + info.name.size() + 1 + info.serialNumber.size() + 1 + info.firmwareVersion.size() + 1;
  if (!hasDefaultNames(info)) {
    for (const auto& n : info.channelNames) {
      if (n.size() > kMaxChannelNameSize) return invalid("channel name '" + n + "' is longer than 23 bytes");
      size += 1 + n.size();
    }
  }
  return size;
}

std::expected<size_t, Diagnostics> sampleSize(const msg::SampleFrame& f, uint32_t headerSequence) {
  const Sample& s = f.sample;
  if (s.channelCount < 1 || s.channelCount > kMaxChannels)
    return invalid("Sample.channelCount " + std::to_string(s.channelCount) + " is outside 1.." +
                   std::to_string(kMaxChannels));
  if (f.bitsPerChannel < 1 || f.bitsPerChannel > 32)
    return invalid("bitsPerChannel " + std::to_string(f.bitsPerChannel) + " is outside 1..32");
  if (s.sequence != headerSequence)
    return invalid("Sample.sequence " + std::to_string(s.sequence) + " differs from Message.sequence " +
                   std::to_string(headerSequence));
  const uint64_t limit = f.bitsPerChannel == 32 ? (uint64_t{1} << 32) : (uint64_t{1} << f.bitsPerChannel);
  for (int i = 0; i < s.channelCount; ++i) {
    if (s.counts[i] >= limit)
      return invalid("channel " + std::to_string(i) + " count " + std::to_string(s.counts[i]) + " does not fit in " +
                     std::to_string(f.bitsPerChannel) + " bits");
    if (f.hasChannelFlags && static_cast<uint8_t>(s.flags[i]) > 2)
      return invalid("channel " + std::to_string(i) + " has flag value " +
                     std::to_string(static_cast<int>(s.flags[i])) + " (expected 0..2)");
  }
  if (f.hasDeviceTime && s.deviceTimeNs < 0) return invalid("Sample.deviceTimeNs is negative");
  return 3 + (f.hasDeviceTime ? 8 : 0) + packedCountBytes(s.channelCount, f.bitsPerChannel) +
         (f.hasChannelFlags ? packedFlagBytes(s.channelCount) : 0);
}

std::expected<size_t, Diagnostics> payloadSize(const Message& m) {
  struct Visitor {
    uint32_t sequence;
    std::expected<size_t, Diagnostics> operator()(const msg::Hello& h) const {
      auto s = deviceInfoSize(h.info);
      if (!s) return s;
      return *s + 1;
    }
    std::expected<size_t, Diagnostics> operator()(const msg::Info& i) const { return deviceInfoSize(i.info); }
    std::expected<size_t, Diagnostics> operator()(const msg::SampleFrame& f) const { return sampleSize(f, sequence); }
    std::expected<size_t, Diagnostics> operator()(const msg::Ack&) const { return size_t{1}; }
    std::expected<size_t, Diagnostics> operator()(const msg::Error& e) const {
      if (e.text.size() > kMaxErrorTextSize) return invalid("Error.text is longer than 255 bytes");
      return 3 + e.text.size();
    }
    std::expected<size_t, Diagnostics> operator()(const msg::HostHello&) const { return size_t{1}; }
    std::expected<size_t, Diagnostics> operator()(const msg::GetInfo&) const { return size_t{0}; }
    std::expected<size_t, Diagnostics> operator()(const msg::Poll&) const { return size_t{0}; }
    std::expected<size_t, Diagnostics> operator()(const msg::StartStream& s) const {
      if (s.rateHz == 0) return invalid("StartStream.rateHz is 0");
      return size_t{2};
    }
    std::expected<size_t, Diagnostics> operator()(const msg::StopStream&) const { return size_t{0}; }
  };
  return std::visit(Visitor{m.sequence}, m.payload);
}

// ---- Payload writers (sizes already validated) ----

uint8_t* putString(uint8_t* p, const std::string& s) {
  *p++ = static_cast<uint8_t>(s.size());
  if (!s.empty()) std::memcpy(p, s.data(), s.size());
  return p + s.size();
}

uint8_t* putDeviceInfo(uint8_t* p, const DeviceInfo& info) {
  *p++ = static_cast<uint8_t>(info.channelCount);
  *p++ = static_cast<uint8_t>(info.bitsPerChannel);
  *p++ = info.hasDeviceTimestamp ? kCapDeviceTime : 0;
  p = putString(p, info.name);
  p = putString(p, info.serialNumber);
  p = putString(p, info.firmwareVersion);
  // Default names ("ch0", "ch1", …) are never sent: the canonical form of "no names" is a count of 0.
  if (hasDefaultNames(info)) {
    *p++ = 0;
  } else {
    *p++ = static_cast<uint8_t>(info.channelNames.size());
    for (const auto& n : info.channelNames) p = putString(p, n);
  }
  return p;
}

uint8_t* putSample(uint8_t* p, const msg::SampleFrame& f) {
  const Sample& s = f.sample;
  const int bits = f.bitsPerChannel;
  *p++ = static_cast<uint8_t>(s.channelCount);
  *p++ = static_cast<uint8_t>(bits);
  *p++ = static_cast<uint8_t>((f.hasDeviceTime ? kSampleHasTime : 0) | (f.hasChannelFlags ? kSampleHasFlags : 0));
  if (f.hasDeviceTime) {
    put64(p, static_cast<uint64_t>(s.deviceTimeNs / 1000));
    p += 8;
  }
  // Counts: an LSB-first bit stream, channel 0 first, zero-padded to a whole byte.
  uint64_t acc = 0;
  int accBits = 0;
  for (int i = 0; i < s.channelCount; ++i) {
    acc |= static_cast<uint64_t>(s.counts[i]) << accBits;
    accBits += bits;
    while (accBits >= 8) {
      *p++ = static_cast<uint8_t>(acc);
      acc >>= 8;
      accBits -= 8;
    }
  }
  if (accBits > 0) *p++ = static_cast<uint8_t>(acc);
  if (f.hasChannelFlags) {
    for (int i = 0; i < s.channelCount; i += 4) {
      uint8_t byte = 0;
      for (int k = 0; k < 4 && i + k < s.channelCount; ++k)
        byte = static_cast<uint8_t>(byte | (static_cast<uint8_t>(s.flags[i + k]) << (2 * k)));
      *p++ = byte;
    }
  }
  return p;
}

uint8_t* putPayload(uint8_t* p, const Message& m) {
  struct Visitor {
    uint8_t* p;
    uint8_t* operator()(const msg::Hello& h) const {
      *p = h.protocolVersion;
      return putDeviceInfo(p + 1, h.info);
    }
    uint8_t* operator()(const msg::Info& i) const { return putDeviceInfo(p, i.info); }
    uint8_t* operator()(const msg::SampleFrame& f) const { return putSample(p, f); }
    uint8_t* operator()(const msg::Ack& a) const {
      *p = static_cast<uint8_t>(a.command);
      return p + 1;
    }
    uint8_t* operator()(const msg::Error& e) const {
      p[0] = static_cast<uint8_t>(e.command);
      p[1] = static_cast<uint8_t>(e.code);
      return putString(p + 2, e.text);
    }
    uint8_t* operator()(const msg::HostHello& h) const {
      *p = h.protocolVersion;
      return p + 1;
    }
    uint8_t* operator()(const msg::GetInfo&) const { return p; }
    uint8_t* operator()(const msg::Poll&) const { return p; }
    uint8_t* operator()(const msg::StartStream& s) const {
      put16(p, s.rateHz);
      return p + 2;
    }
    uint8_t* operator()(const msg::StopStream&) const { return p; }
  };
  return std::visit(Visitor{p}, m.payload);
}

// ---- Payload readers (decoder side). Each returns false when the payload is malformed. ----

// A bounds-checked cursor over one payload.
struct Reader {
  const uint8_t* p;
  const uint8_t* end;
  size_t left() const { return static_cast<size_t>(end - p); }
  bool u8(uint8_t& v) {
    if (left() < 1) return false;
    v = *p++;
    return true;
  }
  bool str(std::string& s, size_t maxSize) {
    uint8_t n = 0;
    if (!u8(n) || n > maxSize || left() < n) return false;
    s.assign(reinterpret_cast<const char*>(p), n);
    p += n;
    return true;
  }
};

bool readDeviceInfo(Reader& r, DeviceInfo& info) {
  uint8_t channels = 0, bits = 0, caps = 0, names = 0;
  if (!r.u8(channels) || !r.u8(bits) || !r.u8(caps)) return false;
  if (channels < 1 || channels > kMaxChannels || bits < 1 || bits > 32) return false;
  info.channelCount = channels;
  info.bitsPerChannel = bits;
  info.hasDeviceTimestamp = (caps & kCapDeviceTime) != 0;  // other capability bits: reserved, ignored
  if (!r.str(info.name, kMaxDeviceNameSize) || !r.str(info.serialNumber, kMaxSerialNumberSize) ||
      !r.str(info.firmwareVersion, kMaxFirmwareVersionSize) || !r.u8(names))
    return false;
  if (names != 0 && names != channels) return false;
  info.channelNames.assign(channels, std::string());
  for (int i = 0; i < channels; ++i) {
    if (names == 0) {
      info.channelNames[i] = defaultChannelName(i);
    } else if (!r.str(info.channelNames[i], kMaxChannelNameSize)) {
      return false;
    }
  }
  return r.left() == 0;
}

bool readSample(const uint8_t* p, size_t size, msg::SampleFrame& f) {
  if (size < 3) return false;
  const int channels = p[0], bits = p[1];
  const uint8_t sflags = p[2];
  if (channels < 1 || channels > kMaxChannels || bits < 1 || bits > 32 || (sflags & ~kSampleKnownBits) != 0)
    return false;
  f.bitsPerChannel = static_cast<uint8_t>(bits);
  f.hasDeviceTime = (sflags & kSampleHasTime) != 0;
  f.hasChannelFlags = (sflags & kSampleHasFlags) != 0;
  const size_t expected = 3 + (f.hasDeviceTime ? 8 : 0) + packedCountBytes(channels, bits) +
                          (f.hasChannelFlags ? packedFlagBytes(channels) : 0);
  if (size != expected) return false;
  p += 3;
  Sample& s = f.sample;
  s.channelCount = static_cast<uint16_t>(channels);
  if (f.hasDeviceTime) {
    const uint64_t us = get64(p);
    if (us > static_cast<uint64_t>(kMaxDeviceTimeUs)) return false;
    s.deviceTimeNs = static_cast<int64_t>(us) * 1000;
    p += 8;
  }
  const uint64_t mask = (uint64_t{1} << bits) - 1;
  uint64_t acc = 0;
  int accBits = 0;
  for (int i = 0; i < channels; ++i) {
    while (accBits < bits) {
      acc |= static_cast<uint64_t>(*p++) << accBits;
      accBits += 8;
    }
    s.counts[i] = static_cast<uint32_t>(acc & mask);
    acc >>= bits;
    accBits -= bits;
  }
  if (acc != 0) return false;  // padding bits must be zero (one canonical encoding per sample)
  if (f.hasChannelFlags) {
    for (int i = 0; i < channels; ++i) {
      const unsigned v = (p[i / 4] >> (2 * (i % 4))) & 3u;
      if (v > 2) return false;  // 3 is reserved
      s.flags[i] = static_cast<ChannelFlag>(v);
    }
    const int used = channels % 4;
    if (used != 0 && (p[channels / 4] >> (2 * used)) != 0) return false;
  }
  return true;
}

// Decodes a CRC-checked payload of a known type into `m.payload`; false when malformed.
bool readPayload(MessageType type, const uint8_t* p, size_t size, Message& m) {
  Reader r{p, p + size};
  switch (type) {
    case MessageType::Hello: {
      msg::Hello h;
      if (!r.u8(h.protocolVersion) || !readDeviceInfo(r, h.info)) return false;
      m.payload = std::move(h);
      return true;
    }
    case MessageType::Info: {
      msg::Info i;
      if (!readDeviceInfo(r, i.info)) return false;
      m.payload = std::move(i);
      return true;
    }
    case MessageType::Sample: {
      auto& f = m.payload.emplace<msg::SampleFrame>();
      f.sample.sequence = m.sequence;
      return readSample(p, size, f);
    }
    case MessageType::Ack:
      if (size != 1) return false;
      m.payload = msg::Ack{static_cast<MessageType>(p[0])};
      return true;
    case MessageType::Error: {
      msg::Error e;
      uint8_t command = 0, code = 0;
      if (!r.u8(command) || !r.u8(code) || !r.str(e.text, kMaxErrorTextSize) || r.left() != 0) return false;
      e.command = static_cast<MessageType>(command);
      e.code = static_cast<ErrorCode>(code);  // unknown codes are passed through
      m.payload = std::move(e);
      return true;
    }
    case MessageType::HostHello:
      if (size != 1) return false;
      m.payload = msg::HostHello{p[0]};
      return true;
    case MessageType::GetInfo:
      m.payload = msg::GetInfo{};
      return size == 0;
    case MessageType::Poll:
      m.payload = msg::Poll{};
      return size == 0;
    case MessageType::StartStream:
      if (size != 2 || get16(p) == 0) return false;
      m.payload = msg::StartStream{get16(p)};
      return true;
    case MessageType::StopStream:
      m.payload = msg::StopStream{};
      return size == 0;
  }
  return false;
}

bool isKnownType(uint8_t t) {
  return (t >= 0x01 && t <= 0x05) || (t >= 0x81 && t <= 0x85);
}

}  // namespace

uint16_t crc16CcittFalse(std::span<const uint8_t> bytes, uint16_t crc) {
  for (uint8_t b : bytes) crc = static_cast<uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ b) & 0xFFu]);
  return crc;
}

MessageType Message::type() const {
  static constexpr MessageType kTypes[] = {MessageType::Hello,     MessageType::Info,    MessageType::Sample,
                                           MessageType::Ack,       MessageType::Error,   MessageType::HostHello,
                                           MessageType::GetInfo,   MessageType::Poll,    MessageType::StartStream,
                                           MessageType::StopStream};
  static_assert(std::size(kTypes) == std::variant_size_v<Payload>);
  return kTypes[payload.index()];
}

Message sampleMessage(const Sample& sample, uint8_t bitsPerChannel, bool hasDeviceTime, bool hasChannelFlags,
                      uint8_t flags) {
  return Message{sample.sequence, flags, msg::SampleFrame{sample, bitsPerChannel, hasDeviceTime, hasChannelFlags}};
}

// ---- Encoder ----

std::expected<size_t, Diagnostics> encodedFrameSize(const Message& message) {
  auto payload = payloadSize(message);
  if (!payload) return std::unexpected(payload.error());
  if (*payload > kMaxPayloadSize) return invalid("payload exceeds kMaxPayloadSize");
  return kFrameHeaderSize + *payload + kFrameCrcSize;
}

std::expected<size_t, Diagnostics> encodeFrame(const Message& message, std::span<uint8_t> out) {
  auto size = encodedFrameSize(message);
  if (!size) return size;
  if (out.size() < *size)
    return invalid("output span holds " + std::to_string(out.size()) + " bytes; the frame needs " +
                   std::to_string(*size));
  const size_t payload = *size - kFrameHeaderSize - kFrameCrcSize;
  uint8_t* p = out.data();
  p[0] = kSync0;
  p[1] = kSync1;
  p[kOffVersion] = kProtocolVersion;
  p[kOffType] = static_cast<uint8_t>(message.type());
  p[kOffFlags] = message.flags;
  put32(p + kOffSequence, message.sequence);
  put16(p + kOffLength, static_cast<uint16_t>(payload));
  put16(p + kOffHeaderCrc, crc16CcittFalse(std::span(p + kOffVersion, kOffHeaderCrc - kOffVersion)));
  uint8_t* end = putPayload(p + kFrameHeaderSize, message);
  // A bug when they differ: payloadSize() and putPayload() disagree.
  IMPS_CHECK_EQ(static_cast<size_t>(end - p), kFrameHeaderSize + payload);
  put16(end, crc16CcittFalse(std::span(p + kOffVersion, end)));
  return *size;
}

std::expected<void, Diagnostics> appendFrame(const Message& message, std::vector<uint8_t>& out) {
  auto size = encodedFrameSize(message);
  if (!size) return std::unexpected(size.error());
  const size_t old = out.size();
  out.resize(old + *size);
  auto written = encodeFrame(message, std::span(out).subspan(old));
  if (!written) {
    out.resize(old);
    return std::unexpected(written.error());
  }
  return {};
}

std::expected<std::vector<uint8_t>, Diagnostics> encodeDeviceInfo(const DeviceInfo& info) {
  auto size = deviceInfoSize(info);
  if (!size) return std::unexpected(size.error());
  std::vector<uint8_t> out(*size);
  putDeviceInfo(out.data(), info);
  return out;
}

std::expected<DeviceInfo, Diagnostics> decodeDeviceInfo(std::span<const uint8_t> bytes) {
  Reader r{bytes.data(), bytes.data() + bytes.size()};
  DeviceInfo info;
  if (!readDeviceInfo(r, info))
    return invalid("malformed DeviceInfo block (" + std::to_string(bytes.size()) + " bytes)");
  return info;
}

// ---- Decoder ----

BinaryDecoder::BinaryDecoder() { in_.reserve(4 * kMaxFrameSize); }

void BinaryDecoder::feed(std::span<const uint8_t> bytes, int64_t arrivalTimeNs) {
  stats_.bytesReceived += bytes.size();
  arrivalTimeNs_ = arrivalTimeNs;
  lastFrameSize_ = 0;
  in_.append(bytes);  // after next() ran dry, at most one partial frame is left to move to the front
}

void BinaryDecoder::skip(size_t n) {
  in_.consume(n);
  stats_.bytesSkipped += n;
}

void BinaryDecoder::reset() {
  discard();
  haveSequence_ = false;
}

void BinaryDecoder::discard() {
  skip(in_.size());
  in_.clear();
  lastFrameSize_ = 0;
}

void BinaryDecoder::resync() {
  lastFrameSize_ = 0;
  if (in_.size() == 0) return;
  ++stats_.truncatedFrames;
  skip(1);
}

std::span<const uint8_t> BinaryDecoder::lastFrame() const {
  return std::span<const uint8_t>(in_.data() + lastFrameBegin_, lastFrameSize_);
}

bool BinaryDecoder::trackSequence(uint32_t sequence) {
  if (haveSequence_) {
    const uint32_t delta = sequence - lastSequence_;  // modulo 2^32: wrapping is not a gap
    if (delta == 0) {
      ++stats_.duplicateSamples;
      return false;
    }
    if (delta > 0x80000000u) {
      ++stats_.sequenceResets;
    } else if (delta > 1) {
      ++stats_.sequenceGaps;
      stats_.samplesDropped += delta - 1;
    }
  }
  haveSequence_ = true;
  lastSequence_ = sequence;
  return true;
}

std::optional<Message> BinaryDecoder::next() {
  lastFrameSize_ = 0;
  for (;;) {
    // 1. Hunt for the sync pair.
    const size_t avail = in_.size();
    if (avail == 0) return std::nullopt;
    const uint8_t* here = in_.data() + in_.begin();
    const auto* sync = static_cast<const uint8_t*>(std::memchr(here, kSync0, avail));
    if (sync == nullptr) {
      skip(avail);
      return std::nullopt;
    }
    if (sync != here) {
      skip(static_cast<size_t>(sync - here));
      continue;
    }
    if (avail < 2) return std::nullopt;
    if (here[1] != kSync1) {
      skip(1);
      continue;
    }
    // 2. Header: its own CRC lets a corrupt length be rejected without waiting for the bytes it claims.
    if (avail < kFrameHeaderSize) return std::nullopt;
    if (crc16CcittFalse(std::span(here + kOffVersion, kOffHeaderCrc - kOffVersion)) != get16(here + kOffHeaderCrc)) {
      ++stats_.headerCrcErrors;
      skip(1);
      continue;
    }
    const size_t length = get16(here + kOffLength);
    if (length > kMaxPayloadSize) {
      ++stats_.oversizeFrames;
      skip(1);
      continue;
    }
    // 3. Whole frame and its CRC.
    const size_t total = kFrameHeaderSize + length + kFrameCrcSize;
    if (avail < total) return std::nullopt;
    const size_t crcAt = kFrameHeaderSize + length;
    if (crc16CcittFalse(std::span(here + kOffVersion, here + crcAt)) != get16(here + crcAt)) {
      ++stats_.crcErrors;
      skip(1);
      continue;
    }
    // 4. A genuine frame: consume it whole, then interpret it.
    const size_t begin = in_.begin();
    in_.consume(total);
    stats_.bytesInFrames += total;
    if (here[kOffVersion] != kProtocolVersion) {
      ++stats_.unsupportedVersions;
      continue;
    }
    const uint8_t type = here[kOffType];
    if (!isKnownType(type)) {
      ++stats_.unknownTypes;
      continue;
    }
    Message m;
    m.sequence = get32(here + kOffSequence);
    m.flags = here[kOffFlags];
    if (!readPayload(static_cast<MessageType>(type), here + kFrameHeaderSize, length, m)) {
      ++stats_.malformedFrames;
      continue;
    }
    if (auto* f = std::get_if<msg::SampleFrame>(&m.payload)) {
      if (!trackSequence(m.sequence)) continue;  // the same sample again (a retransmission): stored once
      f->sample.arrivalTimeNs = arrivalTimeNs_;
      ++stats_.samples;
    } else if (m.type() == MessageType::Hello && (m.flags & kFlagReply) == 0) {
      haveSequence_ = false;  // the device (re)booted: its sample sequence restarts
    }
    ++stats_.framesOk;
    lastFrameBegin_ = begin;
    lastFrameSize_ = total;
    return m;
  }
}

}  // namespace imps::drivers
