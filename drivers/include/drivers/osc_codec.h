// SPDX-License-Identifier: MIT
// The OSC pose stream's packets (docs/osc.md): one OSC bundle per pose frame — a frame header, one quaternion per
// joint, the root translation — or raw encoder channels from a DIY sender. The pure decoder the OSC receiver and
// its fuzz target use; knows nothing of characters (joints are names and numbers here).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <string_view>

#include "drivers/sample.h"
#include "imps/diagnostic.h"

namespace imps::drivers {

// Most joints one pose frame may carry, and the longest joint name (bytes, without the terminator).
inline constexpr int kMaxOscJoints = 128;
inline constexpr size_t kMaxOscJointName = 47;
// Largest datagram the receiver reads; larger ones are truncated by the socket and then fail to decode.
inline constexpr size_t kMaxOscPacket = 65507;

// One joint's absolute local rotation (relative to its parent), a unit quaternion. `name` is NUL-terminated.
struct OscJointRotation {
  std::array<char, kMaxOscJointName + 1> name{};
  float w = 1.0f, x = 0.0f, y = 0.0f, z = 0.0f;
  std::string_view nameView() const { return std::string_view(name.data()); }
};

// One pose frame as sent or received. Fixed size and trivially copyable (it travels through lock-free buffers).
struct OscPose {
  uint32_t frame = 0;         // the sender's frame counter: +1 per pose sent (wraps)
  int64_t sampleTimeNs = 0;   // the sample's arrival time, on the sending host's steady clock
  int64_t sentTimeNs = 0;     // when the sender thread sent the bundle, on the sending host's steady clock
  int64_t arrivalTimeNs = 0;  // receiver only: when the datagram was read, on the receiving host's steady clock
  bool hasRoot = false;
  std::array<float, 3> root{};  // the root joint's translation (scene units), when hasRoot
  uint16_t jointCount = 0;
  std::array<OscJointRotation, kMaxOscJoints> joints{};
};

// What one datagram held.
enum class OscPacketKind : uint8_t {
  Pose,      // a pose frame (into `pose`)
  Channels,  // raw encoder channels (into `channels`, a Sample)
  Ignored,   // well-formed OSC, but no /imps/ message (another program's traffic)
};

// What decodeOscPacket found besides the outputs.
struct OscDecoded {
  OscPacketKind kind = OscPacketKind::Ignored;
  bool hasFrame = false;  // the packet held /imps/frame (a pose always does; raw channels may)
};

// Decodes one UDP datagram: an OSC message or bundle (nested bundles up to depth 4) in the address space of
// docs/osc.md. A pose frame needs /imps/frame; joints come from /imps/joint/NAME (four numbers w x y z, not all 0)
// and the root from /imps/root (three numbers). Raw channels come from /imps/channels (1..kMaxChannels integers in
// 0..2^32-1, all flagged Valid); /imps/frame, when present with them, gives the Sample's sequence and deviceTimeNs.
// Integers may be sent as OSC int32 (i) or int64 (h), numbers as float32 (f) or float64 (d) too; other /imps/
// addresses and other programs' messages are skipped. On success fills `pose` or `channels` (arrivalTimeNs =
// `arrivalNs`; the other output is left untouched) and says what it was. On bad input returns one diagnostic
// whose file is "osc:byte N", N the 0-based offset into the datagram (printed "osc:byte N: error: what was
// expected"), and the outputs hold partial data. Never throws, never reads outside `packet`, allocates only for
// the error.
std::expected<OscDecoded, Diagnostics> decodeOscPacket(std::span<const uint8_t> packet, int64_t arrivalNs,
                                                       OscPose& pose, Sample& channels);

}  // namespace imps::drivers
