// SPDX-License-Identifier: MIT
// The byte pipe a DeviceSession talks through: a serial port, or the in-process simulator. Transports only move
// bytes; codecs, handshakes and reconnects live in DeviceSession.
#pragma once

#include <cstddef>
#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "imps/io_error.h"

namespace imps::drivers {

struct HidDeviceDescription;  // drivers/hid_report.h

// An open connection to one device. Used by one thread at a time (the session's I/O thread); not thread-safe.
// Closing happens in the destructor. An error from read() or write() means the connection is gone (unplugged,
// device node vanished, I/O error): the session drops the transport and reopens through its TransportOpener.
// Errors are IoErrors whose path names the device ("/dev/ttyACM0", "usb 1209:0001", "hid:2341:8036").
class ByteTransport {
 public:
  virtual ~ByteTransport() = default;
  // Waits up to timeoutMs (0: do not wait) until at least one byte is available, then reads what is available,
  // up to out.size() bytes. Returns the number read; 0 means the timeout passed with nothing to read.
  virtual IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) = 0;
  // Writes all of `bytes`, waiting up to timeoutMs in total; a short write within the time is an error.
  virtual IoResult<void> write(std::span<const uint8_t> bytes, int timeoutMs) = 0;
  // Human-readable name for messages, e.g. "/dev/ttyACM0 (2341:0043 IMPS Monkey)".
  virtual std::string description() const = 0;
  // Problems worth telling the performer that do not stop the connection (e.g. the FTDI latency timer).
  virtual std::vector<std::string> warnings() const { return {}; }
  // Message transports (HID): read() returns exactly one input report per call, and this describes the device
  // and its report layout (valid while the transport lives). nullptr for byte streams.
  virtual const HidDeviceDescription* hidDescription() const { return nullptr; }
};

// Opens a fresh connection each time it is called (the session calls it again to reconnect). Returns an IoError
// when the device is absent or cannot be opened. Called only from the session's I/O thread.
using TransportOpener = std::function<IoResult<std::unique_ptr<ByteTransport>>()>;

// How a device failure reads in DeviceSession::lastError() and in the command line's messages:
// "PATH: error: MESSAGE" (e.g. "/dev/ttyACM0: error: the device hung up (unplugged?)"), MESSAGE alone when the
// error names no path.
std::string errorText(const IoError& error);

}  // namespace imps::drivers
