// SPDX-License-Identifier: MIT
// Serial ports through libserialport: listing ports with their USB identity, and a ByteTransport over one port
// (8N1, no flow control, non-blocking reads with timeouts), with the FTDI latency-timer check. docs/devices.md.
#pragma once

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/byte_transport.h"

namespace imps::drivers {

// FTDI's USB vendor id; their USB-serial chips hold received bytes up to `latency_timer` ms (16 by default).
inline constexpr uint16_t kFtdiVendorId = 0x0403;

// One serial port as the OS reports it.
struct SerialPortInfo {
  std::string path;         // "/dev/ttyACM0"
  std::string description;  // libserialport's description, e.g. "Arduino Uno - 85734323"
  bool isUsb = false;
  uint16_t vendorId = 0, productId = 0;  // USB ids when isUsb
  std::string serialNumber, manufacturer, product;  // USB strings, "" when unknown
  std::string driver;  // kernel driver from sysfs ("cdc_acm", "ftdi_sio"), "" when unknown
  // FTDI only: the latency timer in ms read from sysfs, and whether this process may write it.
  std::optional<int> latencyTimerMs;
  bool latencyTimerWritable = false;
};

// Every serial port libserialport finds, sorted by path. Errors carry libserialport's message (and no path).
// Thread-safe (no shared state).
IoResult<std::vector<SerialPortInfo>> listSerialPorts();

struct SerialTransportOptions {
  int baud = 115200;
  // For FTDI chips: lower the latency timer to this many ms through sysfs when it is higher and the file is
  // writable (see docs/devices.md, udev); otherwise add a warning. 0 leaves it alone (still warns when > 1).
  int ftdiLatencyMs = 1;
};

// A ByteTransport over one serial port, configured 8 data bits, no parity, 1 stop bit, no flow control, DTR and
// RTS asserted (opening resets an Arduino). Reads wait with libserialport's event API, so read(…, timeoutMs)
// returns as soon as bytes arrive. One thread at a time; the port is closed by the destructor.
class SerialTransport final : public ByteTransport {
 public:
  // Opens and configures `path`. Errors name `path` (errorText: "PATH: error: …"): absent, permission denied —
  // see docs/devices.md on udev —, not a serial port, configuration refused; code is the OS's errno.
  static IoResult<std::unique_ptr<SerialTransport>> open(const std::string& path, SerialTransportOptions options = {});
  ~SerialTransport() override;
  SerialTransport(const SerialTransport&) = delete;
  SerialTransport& operator=(const SerialTransport&) = delete;

  IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) override;
  IoResult<void> write(std::span<const uint8_t> bytes, int timeoutMs) override;
  std::string description() const override;
  std::vector<std::string> warnings() const override { return warnings_; }

  // What the port looked like when opened (USB identity, driver, FTDI latency after any change made).
  const SerialPortInfo& info() const { return info_; }

 private:
  struct Impl;
  explicit SerialTransport(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  SerialPortInfo info_;
  std::vector<std::string> warnings_;
};

// A TransportOpener for `path` (used by DeviceSession to open and reopen the port).
TransportOpener serialOpener(std::string path, SerialTransportOptions options = {});

}  // namespace imps::drivers
