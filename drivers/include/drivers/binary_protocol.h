// SPDX-License-Identifier: MIT
// The IMPS armature binary protocol (wire format in docs/protocol.md): messages, the frame encoder used by both
// ends (host commands, device replies and samples) and the incremental, resynchronising frame decoder.
#pragma once

#include <cstddef>
#include <cstdint>
#include <expected>
#include <optional>
#include <span>
#include <string>
#include <variant>
#include <vector>

#include "drivers/receive_buffer.h"
#include "imps/diagnostic.h"

#include "drivers/sample.h"

namespace imps::drivers {

// ---- Framing constants (docs/protocol.md, "Frame") -----------------------------------------------------------

inline constexpr uint8_t kSync0 = 0xA5;
inline constexpr uint8_t kSync1 = 0x5A;
// The protocol version this code speaks, written in every frame header and in HELLO.
inline constexpr uint8_t kProtocolVersion = 1;
// sync(2) version(1) type(1) flags(1) sequence(4) length(2) headerCrc(2)
inline constexpr size_t kFrameHeaderSize = 13;
inline constexpr size_t kFrameCrcSize = 2;
// Largest payload a v1 frame may carry; a header claiming more is rejected.
inline constexpr size_t kMaxPayloadSize = 2048;
inline constexpr size_t kMaxFrameSize = kFrameHeaderSize + kMaxPayloadSize + kFrameCrcSize;

// Header flag bits. Bits not named here are reserved: senders write 0, receivers pass them through untouched.
inline constexpr uint8_t kFlagReply = 0x01;  // the message answers the host command with the same sequence

// String limits in DeviceInfo (bytes of UTF-8, no terminator).
inline constexpr size_t kMaxDeviceNameSize = 63;
inline constexpr size_t kMaxSerialNumberSize = 63;
inline constexpr size_t kMaxFirmwareVersionSize = 31;
inline constexpr size_t kMaxChannelNameSize = 23;
inline constexpr size_t kMaxErrorTextSize = 255;

// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, not reflected, no final xor; check("123456789") == 0x29B1).
// Pass a previous result as `crc` to continue over more bytes.
uint16_t crc16CcittFalse(std::span<const uint8_t> bytes, uint16_t crc = 0xFFFF);

// ---- Messages ------------------------------------------------------------------------------------------------

// Message type codes: device → host below 0x80, host → device from 0x81. Any other value is an unknown type.
enum class MessageType : uint8_t {
  Hello = 0x01,   // device: boot announcement or answer to HostHello
  Info = 0x02,    // device: answer to GetInfo
  Sample = 0x03,  // device: one reading (streamed, or the answer to Poll with kFlagReply)
  Ack = 0x04,     // device: command accepted
  Error = 0x05,   // device: command refused, or a device fault
  HostHello = 0x81,
  GetInfo = 0x82,
  Poll = 0x83,
  StartStream = 0x84,
  StopStream = 0x85,
};

// Codes carried by an Error message.
enum class ErrorCode : uint8_t {
  UnknownCommand = 1,
  BadPayload = 2,
  BadRate = 3,  // StartStream rate the device cannot honour
  Busy = 4,
  UnsupportedVersion = 5,
  DeviceFault = 6,  // e.g. an encoder bus failure; not tied to a command
};

// Payloads, one struct per message type. The header sequence number lives in Message, not here.
namespace msg {
struct HostHello {
  uint8_t protocolVersion = kProtocolVersion;  // the highest version the host speaks
  bool operator==(const HostHello&) const = default;
};
struct GetInfo {
  bool operator==(const GetInfo&) const = default;
};
struct Poll {
  bool operator==(const Poll&) const = default;
};
struct StartStream {
  uint16_t rateHz = 0;  // 1..65535 samples per second; 0 is malformed
  bool operator==(const StartStream&) const = default;
};
struct StopStream {
  bool operator==(const StopStream&) const = default;
};
struct Hello {
  uint8_t protocolVersion = kProtocolVersion;  // the highest version the device speaks
  DeviceInfo info;
  bool operator==(const Hello&) const = default;
};
struct Info {
  DeviceInfo info;
  bool operator==(const Info&) const = default;
};
// One reading. sample.sequence must equal the enclosing Message::sequence (the encoder checks).
struct SampleFrame {
  Sample sample;               // arrivalTimeNs is never on the wire: the decoder sets it from feed()
  uint8_t bitsPerChannel = 16; // 1..32; every count must be < 2^bitsPerChannel
  bool hasDeviceTime = false;  // carry sample.deviceTimeNs (as whole microseconds, >= 0)
  bool hasChannelFlags = false;  // carry sample.flags; when false the decoder reports every channel Valid
  bool operator==(const SampleFrame&) const = default;
};
struct Ack {
  MessageType command{};  // the type of the command acknowledged; its sequence is the Message's
  bool operator==(const Ack&) const = default;
};
struct Error {
  MessageType command{};  // the refused command's type, or 0 for a fault not tied to a command
  ErrorCode code = ErrorCode::DeviceFault;
  std::string text;  // human-readable detail, <= kMaxErrorTextSize bytes
  bool operator==(const Error&) const = default;
};
}  // namespace msg

using Payload = std::variant<msg::Hello, msg::Info, msg::SampleFrame, msg::Ack, msg::Error, msg::HostHello,
                             msg::GetInfo, msg::Poll, msg::StartStream, msg::StopStream>;

// One decoded (or to-be-encoded) frame.
// sequence: for Sample, the sample sequence; for a device reply, the sequence of the command it answers; for a
// host command, the host's own running command number.
struct Message {
  uint32_t sequence = 0;
  uint8_t flags = 0;  // kFlag* bits (reserved bits preserved)
  Payload payload;

  MessageType type() const;
  bool operator==(const Message&) const = default;
};

// Builds a Sample message whose header sequence is sample.sequence.
Message sampleMessage(const Sample& sample, uint8_t bitsPerChannel, bool hasDeviceTime, bool hasChannelFlags,
                      uint8_t flags = 0);

// ---- Encoder -------------------------------------------------------------------------------------------------

// Bytes the whole frame of `message` takes, or what makes it unencodable (channel count outside 1..kMaxChannels,
// bits outside 1..32, a count that does not fit its bits, a flag value > 2, a string over its limit, channel names
// neither empty nor channelCount long, StartStream rate 0, negative device time, mismatched sample sequence), as
// one diagnostic without a position (printed "error: …"; the values come from the program, not a file).
std::expected<size_t, Diagnostics> encodedFrameSize(const Message& message);

// Writes one frame into `out` (which must hold at least encodedFrameSize bytes) and returns the bytes written.
// Never allocates for Sample messages. Deterministic: equal messages give equal bytes.
std::expected<size_t, Diagnostics> encodeFrame(const Message& message, std::span<uint8_t> out);

// Appends one frame to `out`; `out` is unchanged on error.
std::expected<void, Diagnostics> appendFrame(const Message& message, std::vector<uint8_t>& out);

// The DeviceInfo block alone (the payload of INFO, docs/protocol.md): what a USB armature returns for its vendor
// GET_INFO control request. Errors as encodedFrameSize() gives them for an invalid description.
std::expected<std::vector<uint8_t>, Diagnostics> encodeDeviceInfo(const DeviceInfo& info);
// Parses a DeviceInfo block that fills `bytes` exactly (the layout and limits of INFO's payload); the error (one
// diagnostic without a position) says that the block is malformed. Never throws.
std::expected<DeviceInfo, Diagnostics> decodeDeviceInfo(std::span<const uint8_t> bytes);

// ---- Decoder -------------------------------------------------------------------------------------------------

// Every byte fed ends up in exactly one of bytesInFrames, bytesSkipped or BinaryDecoder::buffered():
//   bytesReceived == bytesInFrames + bytesSkipped + buffered()
// and every frame whose CRCs check out is exactly one of:
//   framesOk + malformedFrames + unknownTypes + unsupportedVersions + duplicateSamples.
struct BinaryDecoderStats {
  uint64_t bytesReceived = 0;
  uint64_t bytesInFrames = 0;  // bytes of frames whose header and frame CRC matched (decoded or not)
  uint64_t bytesSkipped = 0;   // bytes discarded while hunting for the next frame (garbage, corrupt frames, reset)
  uint64_t framesOk = 0;       // messages returned by next()
  uint64_t samples = 0;        // of which Sample messages
  uint64_t headerCrcErrors = 0;  // a sync pair whose header CRC did not match
  uint64_t crcErrors = 0;        // a header that checked out but whose frame CRC did not match
  uint64_t oversizeFrames = 0;   // a header that checked out but claimed more than kMaxPayloadSize
  uint64_t malformedFrames = 0;  // CRC good, payload invalid for its type (wrong length, bad field value)
  uint64_t unknownTypes = 0;     // CRC good, type unknown to this version: skipped
  uint64_t unsupportedVersions = 0;  // CRC good, header version != kProtocolVersion: skipped
  uint64_t sequenceGaps = 0;     // Sample messages whose sequence was not previous + 1 (forward jumps)
  uint64_t samplesDropped = 0;   // sequence numbers missing across those gaps
  uint64_t sequenceResets = 0;   // a Sample sequence that went backwards without a HELLO (e.g. a missed reboot)
  uint64_t duplicateSamples = 0;  // a Sample repeating the previous one's sequence: skipped, not returned
  uint64_t truncatedFrames = 0;   // a frame that never completed: abandoned by resync() (a timeout)
  bool operator==(const BinaryDecoderStats&) const = default;
};

// Incremental decoder for a byte stream of frames, arriving in chunks of any size split anywhere.
//
// Usage (one thread; not thread-safe, not shared):  decoder.feed(chunk, nowNs); while (auto m = decoder.next()) …
// feed() copies the chunk into an internal buffer that keeps its capacity (no allocation per byte or per frame
// once warmed up); memory is bounded by the largest chunk fed plus one frame. next() returns each valid frame
// once, in order, and returns nullopt when the buffered bytes hold no further complete frame.
// Bad input never throws or crashes: garbage, corrupt, truncated, oversize, unknown-type and unsupported-version
// frames are counted in stats() and skipped; after a bad header or CRC the decoder rescans from the byte after
// the rejected sync byte, so a good frame right behind a bad one is still found.
// Sequence tracking: only an unsolicited Hello (no REPLY flag: the device rebooted) restarts it; a Hello answering
// HOST_HELLO, a timeout (resync()) or a reconnect (discard()) do not, so samples lost across them are counted.
class BinaryDecoder {
 public:
  BinaryDecoder();

  // Appends bytes. arrivalTimeNs (host steady clock) becomes Sample::arrivalTimeNs of every Sample completed by
  // these bytes; call next() until it returns nullopt after each feed() so the stamps are accurate.
  void feed(std::span<const uint8_t> bytes, int64_t arrivalTimeNs = 0);

  // The next valid message, or nullopt when more bytes are needed.
  std::optional<Message> next();

  // The exact bytes of the frame last returned by next(); valid until the next feed(), next() or reset().
  std::span<const uint8_t> lastFrame() const;

  // Discards buffered bytes (counted as skipped) and sequence tracking; keeps stats.
  void reset();
  // A reconnect: discards buffered bytes (counted as skipped) so nothing from before joins bytes from after;
  // keeps sequence tracking.
  void discard();
  // A timeout: the frame whose header starts the buffer will not complete (its length may be forged or corrupt),
  // so its sync byte is dropped (counted in truncatedFrames and bytesSkipped) and the bytes behind it are scanned
  // again by next(). Keeps sequence tracking. No-op when nothing is buffered.
  void resync();

  // Bytes fed but not yet consumed as a frame or skipped.
  size_t buffered() const { return in_.size(); }
  const BinaryDecoderStats& stats() const { return stats_; }

 private:
  void skip(size_t n);
  bool trackSequence(uint32_t sequence);  // false: a duplicate

  ReceiveBuffer in_;
  size_t lastFrameBegin_ = 0, lastFrameSize_ = 0;
  int64_t arrivalTimeNs_ = 0;
  bool haveSequence_ = false;
  uint32_t lastSequence_ = 0;
  BinaryDecoderStats stats_;
};

}  // namespace imps::drivers
