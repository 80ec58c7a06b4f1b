// SPDX-License-Identifier: MIT
// Device specs: the one-line text that names an armature and how to talk to it (docs/devices.md), e.g.
// `serial:/dev/ttyACM0?baud=115200&protocol=lines`, `hid:2341:8036`, `usb:1209:0001`, `sim:?channels=32`,
// `osc.udp://:9000` (an OSC pose stream, docs/osc.md).
#pragma once

#include <cstdint>
#include <expected>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "imps/diagnostic.h"

namespace imps::drivers {

enum class DeviceKind : uint8_t { Serial, Hid, Usb, Sim, Osc };
// Which codec the session feeds: the binary framed protocol or the DIY line protocol (docs/protocol.md), or HID
// input reports (one per transport read, decoded with drivers/hid_report.h; used for hid: specs, not a spec key).
enum class WireProtocol : uint8_t { Binary, Lines, HidReports };
// Binary protocol only: the device streams at a rate (START_STREAM) or answers one POLL at a time.
enum class AcquisitionMode : uint8_t { Stream, Poll };

const char* toString(DeviceKind kind);
const char* toString(WireProtocol protocol);
const char* toString(AcquisitionMode mode);

// A parsed device spec. Fields not meaningful for `kind` keep their defaults.
struct DeviceSpec {
  DeviceKind kind = DeviceKind::Serial;
  // serial: the device node ("/dev/ttyACM0"); sim: the optional session file to play ("" = generated motion);
  // osc: the numeric IPv4 address to listen on ("" = every interface).
  std::string path;
  uint16_t port = 0;  // osc: the UDP port to listen on (1..65535)
  // hid, usb: USB vendor and product id; serialNumber selects one of several identical units ("" = first).
  uint16_t vendorId = 0;
  uint16_t productId = 0;
  std::string serialNumber;
  // serial, sim: transport and session settings.
  int baud = 115200;
  WireProtocol protocol = WireProtocol::Binary;
  AcquisitionMode mode = AcquisitionMode::Stream;
  uint16_t rateHz = 0;    // stream rate requested with START_STREAM (poll rate in poll mode); 0 = the default
  int channels = 0;       // lines: expected channel count (0 = inferred from the first sample line)
  int bits = 0;           // serial lines: the encoders' bits per channel, which lines cannot say (0 = 32)
  // sim: every other `key=value` of the query, in order, for the simulator to interpret (it reports unknown keys).
  std::vector<std::pair<std::string, std::string>> simParams;
  bool operator==(const DeviceSpec&) const = default;
};

// Parses a device spec; a bare path starting with '/' is a serial port ("/dev/ttyACM0" = "serial:/dev/ttyACM0").
// Bad input gives one diagnostic at spec:1:COLUMN, COLUMN 1-based into `text` (printed
// "spec:1:COLUMN: error: what was expected"):
// an unknown scheme, a missing path, VID/PID that are not 1..4 hex digits, an unknown or repeated key (catches
// typos), or a value out of range (baud 1..4000000, rate 0..65535, channels 0..64, bits 1..32; bits only with
// protocol=lines: a binary device reports its own; port 1..65535). An osc spec is `osc.udp://[ADDRESS]:PORT` and
// takes no keys. Never throws.
std::expected<DeviceSpec, Diagnostics> parseDeviceSpec(std::string_view text);

// The canonical text of a spec; parseDeviceSpec(formatDeviceSpec(s)) == s. Keys at their defaults are omitted.
std::string formatDeviceSpec(const DeviceSpec& spec);

}  // namespace imps::drivers
