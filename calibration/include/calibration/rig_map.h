// SPDX-License-Identifier: MIT
// The rig map: which armature channel drives which axis of which joint, and how counts become radians (sign, gain,
// offset, limits, deadband, smoothing, wrap-around). A calibration file is a rig map whose offsets are all set.
// The file format, the math and the technician's workflow are in docs/calibration.md.
#pragma once

#include <cstdint>
#include <expected>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/sample.h"
#include "imps/character.h"
#include "imps/diagnostic.h"

namespace imps::calibration {

// The file format version this program reads and writes. Newer files are refused, never half-read.
inline constexpr int kRigMapVersion = 1;

// An axis of a joint's local frame (the frame the character file's RigTransform defines).
enum class Axis : uint8_t { X = 0, Y = 1, Z = 2 };
// "x", "y" or "z".
const char* toString(Axis axis);

// Absolute encoders (the default) report a position on one turn: counts are modulo 2^bits, and an angle is the
// shortest signed difference from the offset. Linear sensors (potentiometers) never wrap.
enum class EncoderKind : uint8_t { Absolute, Linear };

// One channel → one joint axis: a rotation about it (axis "x"/"y"/"z"), or a translation along it (axis
// "tx"/"ty"/"tz"). Angles in radians, translations in metres, counts in encoder counts.
struct ChannelMap {
  int channel = -1;              // device channel index; -1 until a name is resolved against a DeviceInfo
  int device = 0;                // which device of a session (0 = the first; "device" in the file)
  SourceLoc deviceLoc;           // where the file gives "device" (line 0: not given, so a name may resolve anywhere)
  std::string channelName;       // the device channel name when the file named the channel, else ""
  std::string joint;             // joint name in the character
  Axis axis = Axis::X;           // rotation axis in the joint's local frame, or translation axis in its parent's
  bool translation = false;      // true: the channel moves the joint along `axis` (metres), not about it
  int sign = 1;                  // +1: counts grow with the angle; -1: the encoder is mounted reversed
  double gain = 0;               // counts per radian (translation: counts per metre), > 0
  std::optional<double> offset;  // counts at the calibration pose (unset in a rig map not yet calibrated)
  // Limits after the offset, radians (translation: metres), min <= max.
  double minAngle = -std::numeric_limits<double>::infinity();
  double maxAngle = std::numeric_limits<double>::infinity();
  // Radians (translation: metres), >= 0: changes smaller than this are ignored (hysteresis; Calibrator only).
  double deadband = 0;
  double smoothingMs = 0;  // one-pole low-pass time constant in ms, >= 0 (0: none; Calibrator only)
  EncoderKind encoder = EncoderKind::Absolute;  // translation channels default to Linear
  SourceLoc loc;  // where the file names the channel (its "channel" value)
};

// A joint driven by one or more channels.
struct JointMap {
  std::string joint;
  // Axes in composition order, e.g. "ZXY": the calibrated rotation is Rz * Rx * Ry (BVH's convention). Holds
  // exactly the rotation axes this joint's channels drive. For one channel it is that channel's axis; "" when the
  // joint is only translated.
  std::string order;
  std::vector<size_t> mappings;  // indices into RigMap::channels, in file order
  SourceLoc loc;  // the joint's name in the file
};

struct RigMap {
  int version = kRigMapVersion;
  int bits = 12;                      // encoder resolution: counts are in [0, 2^bits)
  std::string device;                 // optional: the armature it was written for (informational)
  std::vector<ChannelMap> channels;   // every mapping, in file order
  std::vector<JointMap> joints;       // every driven joint, in file order
  std::string info;                   // optional "info" object, kept verbatim as compact JSON ("" when absent)
  std::string file;                   // where it was read from ("" when built in memory)
  SourceLoc bitsLoc;                  // the "bits" value in the file

  // Counts per turn, 2^bits.
  double countsPerTurn() const { return static_cast<double>(uint64_t{1} << bits); }
  // Index into channels of the mapping for device channel `channel`, or -1.
  int findChannel(int channel) const;
  // "channel 7 'L_elbow'" (the name from the map or `device` when known) for messages.
  std::string channelLabel(size_t mapping, const drivers::DeviceInfo* device = nullptr) const;
};

// What a rig map is checked against. Both are optional; without them only the file itself is checked.
struct RigMapContext {
  const Character* character = nullptr;       // joint names must exist (with "did you mean" suggestions)
  const drivers::DeviceInfo* device = nullptr;  // channel indices in range, channel names resolved, bits agree
  bool requireOffsets = false;                // a calibration: every channel must have an "offset"
  // Every device of a session (devices[0] is `device` when both are given): channel names resolve on any of them
  // (the channel's "device" when the file gives one), indices are checked against their own device.
  std::span<const drivers::DeviceInfo> devices = {};
};

// Parses and validates a rig map or calibration file. Every problem is reported (not only the first) as
// `file:line:column: error: …`; unknown fields get a typo suggestion. Warnings (nothing fatal: "device" names
// another armature than context.device) go to *warnings when given.
std::expected<RigMap, Diagnostics> parseRigMap(std::string_view json, std::string_view fileName,
                                               const RigMapContext& context = {}, Diagnostics* warnings = nullptr);
// Reads a file with parseRigMap. An unreadable file gives `path: error: cannot read …`.
std::expected<RigMap, Diagnostics> readRigMapFile(const std::filesystem::path& path, const RigMapContext& context = {},
                                                  Diagnostics* warnings = nullptr);

// Re-checks a map built or changed in memory against a context (the same checks as parseRigMap, at the
// locations the map carries). Resolves channel names when a device is given.
bool validateRigMap(RigMap& map, const RigMapContext& context, Diagnostics& diags);

// The file text (pretty-printed JSON, "version" first); parseRigMap(toJson(m)) reproduces m's fields.
std::string toJson(const RigMap& map);


}  // namespace imps::calibration
