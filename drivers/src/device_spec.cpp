// SPDX-License-Identifier: MIT
// Device spec parsing and formatting (grammar in docs/devices.md).
#include "drivers/device_spec.h"

#include "text.h"

#include <charconv>
#include <cstdio>
#include <sstream>

namespace imps::drivers {

const char* toString(DeviceKind kind) {
  switch (kind) {
    case DeviceKind::Serial: return "serial";
    case DeviceKind::Hid: return "hid";
    case DeviceKind::Usb: return "usb";
    case DeviceKind::Sim: return "sim";
    case DeviceKind::Osc: return "osc.udp";
  }
  return "?";
}
const char* toString(WireProtocol protocol) {
  switch (protocol) {
    case WireProtocol::Binary: return "binary";
    case WireProtocol::Lines: return "lines";
    case WireProtocol::HidReports: return "hid-reports";
  }
  return "?";
}
const char* toString(AcquisitionMode mode) { return mode == AcquisitionMode::Stream ? "stream" : "poll"; }

namespace {

// A spec is one line of text: "spec:1:COLUMN", COLUMN 1-based.
std::unexpected<Diagnostics> fail(size_t offset, std::string what) {
  return diagnosticError({"spec", 1, static_cast<int>(offset + 1)}, std::move(what));
}

template <class T>
bool parseNumber(std::string_view s, T& out, int base = 10) {
  if (s.empty()) return false;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out, base);
  return ec == std::errc() && end == s.data() + s.size();
}

bool parseHexId(std::string_view s, uint16_t& out) { return s.size() >= 1 && s.size() <= 4 && parseNumber(s, out, 16); }

}  // namespace

// `osc.udp://[ADDRESS]:PORT`: the text after the scheme.
std::expected<DeviceSpec, Diagnostics> parseOscSpec(std::string_view text) {
  constexpr std::string_view kPrefix = "osc.udp://";
  if (!text.starts_with(kPrefix)) return fail(0, "expected osc.udp://:PORT (or osc.udp://ADDRESS:PORT)");
  const std::string_view rest = text.substr(kPrefix.size());
  const size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos) return fail(kPrefix.size(), "expected :PORT, e.g. osc.udp://:9000");
  DeviceSpec spec;
  spec.kind = DeviceKind::Osc;
  spec.path = rest.substr(0, colon);
  std::string_view port = rest.substr(colon + 1);
  if (!port.empty() && port.back() == '/') port.remove_suffix(1);
  if (!parseNumber(port, spec.port) || spec.port == 0)
    return fail(kPrefix.size() + colon + 1, "expected a UDP port in 1..65535");
  return spec;
}

std::expected<DeviceSpec, Diagnostics> parseDeviceSpec(std::string_view text) {
  DeviceSpec spec;
  if (text.starts_with("osc.")) return parseOscSpec(text);
  // A bare device node ("/dev/ttyACM0?baud=9600") is a serial port: as if written "serial:/dev/ttyACM0…".
  const bool barePath = text.starts_with('/');
  const size_t colon = barePath ? size_t(0) : text.find(':');
  if (colon == std::string_view::npos)
    return fail(
        0, "expected SCHEME:… where SCHEME is serial, hid, usb, sim or osc.udp, or a device path such as /dev/ttyACM0");
  const std::string_view scheme = barePath ? "serial" : text.substr(0, colon);
  if (scheme == "serial") spec.kind = DeviceKind::Serial;
  else if (scheme == "hid") spec.kind = DeviceKind::Hid;
  else if (scheme == "usb") spec.kind = DeviceKind::Usb;
  else if (scheme == "sim") spec.kind = DeviceKind::Sim;
  else return fail(0, cat("unknown scheme '", scheme, "': expected serial, hid, usb, sim or osc.udp"));

  const size_t bodyBegin = barePath ? 0 : colon + 1;
  const size_t question = text.find('?', bodyBegin);
  const std::string_view body =
      text.substr(bodyBegin, question == std::string_view::npos ? std::string_view::npos : question - bodyBegin);

  // ---- Body: a path or VID:PID
  switch (spec.kind) {
    case DeviceKind::Osc:  // parsed above
      break;
    case DeviceKind::Serial:
      if (body.empty()) return fail(bodyBegin, "expected a device path, e.g. serial:/dev/ttyACM0");
      spec.path = body;
      break;
    case DeviceKind::Sim:
      spec.path = body;  // optional session file
      break;
    case DeviceKind::Hid:
    case DeviceKind::Usb: {
      const size_t idColon = body.find(':');
      if (idColon == std::string_view::npos)
        return fail(bodyBegin, "expected VID:PID as hexadecimal USB ids, e.g. 2341:8036");
      if (!parseHexId(body.substr(0, idColon), spec.vendorId))
        return fail(bodyBegin, "expected a USB vendor id of 1 to 4 hex digits");
      if (!parseHexId(body.substr(idColon + 1), spec.productId))
        return fail(bodyBegin + idColon + 1, "expected a USB product id of 1 to 4 hex digits");
      break;
    }
  }

  // ---- Query: key=value pairs separated by '&'
  if (question == std::string_view::npos) return spec;
  std::vector<std::string_view> seen;
  size_t pos = question + 1;
  while (pos <= text.size()) {
    size_t amp = text.find('&', pos);
    if (amp == std::string_view::npos) amp = text.size();
    const std::string_view item = text.substr(pos, amp - pos);
    const size_t eq = item.find('=');
    if (item.empty() || eq == std::string_view::npos || eq == 0)
      return fail(pos, "expected key=value");
    const std::string_view key = item.substr(0, eq);
    const std::string_view value = item.substr(eq + 1);
    const size_t valueAt = pos + eq + 1;
    for (std::string_view k : seen)
      if (k == key) return fail(pos, cat("key '", key, "' given twice"));
    seen.push_back(key);

    const bool serialLike = spec.kind == DeviceKind::Serial || spec.kind == DeviceKind::Sim;
    if (key == "baud" && spec.kind == DeviceKind::Serial) {
      if (!parseNumber(value, spec.baud) || spec.baud < 1 || spec.baud > 4'000'000)
        return fail(valueAt, "expected a baud rate in 1..4000000");
    } else if (key == "protocol" && serialLike) {
      if (value == "binary") spec.protocol = WireProtocol::Binary;
      else if (value == "lines") spec.protocol = WireProtocol::Lines;
      else return fail(valueAt, "expected protocol=binary or protocol=lines");
    } else if (key == "mode" && (serialLike || spec.kind == DeviceKind::Usb)) {
      if (value == "stream") spec.mode = AcquisitionMode::Stream;
      else if (value == "poll") spec.mode = AcquisitionMode::Poll;
      else return fail(valueAt, "expected mode=stream or mode=poll");
    } else if (key == "rate" && (serialLike || spec.kind == DeviceKind::Usb)) {
      if (!parseNumber(value, spec.rateHz)) return fail(valueAt, "expected a rate in Hz, 0..65535");
    } else if (key == "channels" && spec.kind == DeviceKind::Serial) {
      if (!parseNumber(value, spec.channels) || spec.channels < 0 || spec.channels > 64)
        return fail(valueAt, "expected a channel count in 0..64");
    } else if (key == "bits" && spec.kind == DeviceKind::Serial) {
      if (!parseNumber(value, spec.bits) || spec.bits < 1 || spec.bits > 32)
        return fail(valueAt, "expected bits per channel in 1..32");
    } else if (key == "serial" && (spec.kind == DeviceKind::Hid || spec.kind == DeviceKind::Usb)) {
      if (value.empty()) return fail(valueAt, "expected a serial number");
      spec.serialNumber = value;
    } else if (spec.kind == DeviceKind::Sim) {
      spec.simParams.emplace_back(key, value);
    } else {
      const char* known = spec.kind == DeviceKind::Serial ? "baud, protocol, mode, rate, channels, bits"
                          : spec.kind == DeviceKind::Usb  ? "serial, mode, rate"
                                                          : "serial";
      return fail(pos, cat("unknown key '", key, "' for ", toString(spec.kind), " (known: ", known, ")"));
    }
    pos = amp + 1;
  }
  if (spec.bits != 0 && spec.protocol != WireProtocol::Lines)
    return fail(question + 1, "bits applies to protocol=lines only: a binary device reports its own in INFO");
  return spec;
}

std::string formatDeviceSpec(const DeviceSpec& spec) {
  if (spec.kind == DeviceKind::Osc) return cat("osc.udp://", spec.path, ":", spec.port);
  std::string out = toString(spec.kind);
  out += ':';
  std::vector<std::string> query;
  if (spec.kind == DeviceKind::Hid || spec.kind == DeviceKind::Usb) {
    out += hex4(spec.vendorId) + ":" + hex4(spec.productId);
    if (!spec.serialNumber.empty()) query.push_back("serial=" + spec.serialNumber);
    if (spec.mode != AcquisitionMode::Stream) query.push_back("mode=poll");
    if (spec.rateHz != 0) query.push_back(cat("rate=", spec.rateHz));
  } else {
    out += spec.path;
    if (spec.kind == DeviceKind::Serial && spec.baud != 115200) query.push_back(cat("baud=", spec.baud));
    if (spec.protocol != WireProtocol::Binary) query.push_back("protocol=lines");
    if (spec.mode != AcquisitionMode::Stream) query.push_back("mode=poll");
    if (spec.rateHz != 0) query.push_back(cat("rate=", spec.rateHz));
    if (spec.channels != 0) query.push_back(cat("channels=", spec.channels));
    if (spec.bits != 0) query.push_back(cat("bits=", spec.bits));
    for (const auto& [k, v] : spec.simParams) query.push_back(k + "=" + v);
  }
  for (size_t i = 0; i < query.size(); ++i) out += (i == 0 ? "?" : "&") + query[i];
  return out;
}

}  // namespace imps::drivers
