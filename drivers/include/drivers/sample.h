// SPDX-License-Identifier: MIT
// The device vocabulary: what an armature is (DeviceInfo) and what it reports (Sample). Knows nothing of joints.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace imps::drivers {

// Largest channel count any armature may report.
inline constexpr int kMaxChannels = 64;

// Per-channel state of one reading (as QUMARION's SDK and OpenVR flag theirs).
enum class ChannelFlag : uint8_t {
  Valid = 0,         // a fresh, trusted reading
  NotConnected = 1,  // the encoder is absent or unplugged; the count is meaningless
  Outlier = 2,       // the device (or decoder) judged the reading implausible; the count is the raw value
};

// What a device says about itself in its hello / device-info reply.
struct DeviceInfo {
  std::string name;          // e.g. "IMPS Monkey-32"
  std::string serialNumber;  // unique per unit; "" when unknown
  std::string firmwareVersion;
  int channelCount = 0;                   // 1..kMaxChannels
  int bitsPerChannel = 12;                // encoder resolution: counts are in [0, 2^bits)
  std::vector<std::string> channelNames;  // channelCount entries ("ch0"... when the device gives none)
  bool hasDeviceTimestamp = false;        // samples carry the device's own clock
  bool operator==(const DeviceInfo&) const = default;
};

// One reading of every channel. Timestamps are nanoseconds: deviceTimeNs on the device's clock (0 when the
// device has none), arrivalTimeNs on the host's steady clock when the bytes were decoded.
struct Sample {
  uint32_t sequence = 0;  // device sequence number (wraps); gaps mean dropped samples
  int64_t deviceTimeNs = 0;
  int64_t arrivalTimeNs = 0;
  uint16_t channelCount = 0;
  std::array<uint32_t, kMaxChannels> counts{};  // raw encoder counts, only [0, channelCount) meaningful
  std::array<ChannelFlag, kMaxChannels> flags{};
  bool operator==(const Sample&) const = default;
};

}  // namespace imps::drivers
