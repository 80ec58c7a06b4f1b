// SPDX-License-Identifier: MIT
// HID armatures through hidapi (hidraw backend): listing HID devices with their report descriptors, and a
// transport that hands the session one input report per read. docs/devices.md, docs/protocol.md ("HID").
#pragma once

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/byte_transport.h"
#include "drivers/hid_report.h"
#include "drivers/sample.h"

namespace imps::drivers {

// One HID device (one hidraw node) as hidapi enumerates it, plus what its report descriptor says.
struct HidDeviceEntry {
  std::string path;  // "/dev/hidraw0"
  uint16_t vendorId = 0, productId = 0;
  uint16_t releaseNumber = 0;  // bcdDevice
  std::string serialNumber, manufacturer, product;  // "" when unknown
  uint16_t usagePage = 0, usage = 0;  // of the first top-level collection
  int interfaceNumber = -1;
  // From /sys/class/hidraw/<node>/device/report_descriptor: the input layout, or why there is none.
  std::optional<HidInputLayout> layout;
  std::string layoutError;
  bool looksLikeArmature() const { return layout && layout->looksLikeArmature; }
};

// Every HID device hidapi finds, one entry per hidraw node, sorted by path. Thread-safe. Errors: hidapi's
// message when enumeration itself fails (no devices is an empty list, not an error).
IoResult<std::vector<HidDeviceEntry>> listHidDevices();

// A HID armature's input report source. read() returns exactly one input report per call (as hidraw delivers
// it: the report ID byte first when the device uses IDs), 0 on timeout, and an error when hidapi reports one —
// which is how hidapi reports an unplug. write() sends an output report (ID byte first). Opening reads the
// report descriptor from sysfs, lays out the input report (hidArmatureLayout) and asks for the INFO feature
// report when the descriptor declares one; the description falls back to the USB strings and the layout.
// One thread at a time; closed by the destructor.
class HidTransport final : public ByteTransport {
 public:
  // Opens the first HID device with this VID:PID (and serial number, when not empty). Errors name "hid:VID:PID"
  // (errorText: "hid:VID:PID: error: …"): no such device (with what was found instead), permission denied (see
  // the udev rules), a report descriptor that cannot be read or parsed (its diagnostic in the message), no input
  // channels.
  static IoResult<std::unique_ptr<HidTransport>> open(uint16_t vendorId, uint16_t productId,
                                                      const std::string& serialNumber = {});
  ~HidTransport() override;
  HidTransport(const HidTransport&) = delete;
  HidTransport& operator=(const HidTransport&) = delete;

  IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) override;
  IoResult<void> write(std::span<const uint8_t> bytes, int timeoutMs) override;
  std::string description() const override;
  std::vector<std::string> warnings() const override { return warnings_; }
  const HidDeviceDescription* hidDescription() const override { return &described_; }

  const HidDeviceEntry& entry() const { return entry_; }

 private:
  struct Impl;
  explicit HidTransport(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  HidDeviceEntry entry_;
  HidDeviceDescription described_;
  std::vector<std::string> warnings_;
};

// A TransportOpener for `hid:VID:PID[?serial=…]` (the session calls it again to reconnect).
TransportOpener hidOpener(uint16_t vendorId, uint16_t productId, std::string serialNumber = {});

}  // namespace imps::drivers
