// SPDX-License-Identifier: MIT
// Vendor-specific USB armatures through libusb: listing them, a ByteTransport over one (binary-protocol frames on a
// bulk OUT and an interrupt or bulk IN endpoint, INFO by a vendor control request) and a hotplug monitor that
// notices them arriving and leaving. The USB framing is in docs/protocol.md, "USB transport"; docs/devices.md.
#pragma once

#include <cstdint>
#include <expected>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivers/byte_transport.h"
#include "drivers/sample.h"

namespace imps::drivers {

// The armature's vendor interface (docs/protocol.md, "USB transport").
inline constexpr uint8_t kUsbVendorInterfaceClass = 0xFF;
// bmRequestType of the INFO request: device-to-host, vendor, recipient device.
inline constexpr uint8_t kUsbInfoRequestType = 0xC0;
// bRequest of the vendor control request whose data stage is the DeviceInfo block (INFO's payload).
inline constexpr uint8_t kUsbInfoRequest = 0x01;
// wLength the host asks for: every valid DeviceInfo block fits.
inline constexpr uint16_t kUsbInfoMaxLength = 2048;

struct UsbId {
  uint16_t vendorId = 0, productId = 0;
  bool operator==(const UsbId&) const = default;
};
// The VID:PIDs `puppeteer devices` lists as armatures: the project's pid.codes id (docs/devices.md).
inline constexpr UsbId kKnownUsbArmatures[] = {{0x1209, 0x0001}};

// One attached USB device as libusb reports it.
struct UsbDeviceInfo {
  uint16_t vendorId = 0, productId = 0;
  uint8_t bus = 0, address = 0;
  std::string manufacturer, product, serialNumber;  // string descriptors; "" when absent or unreadable
  // The armature's own description from the INFO control request; nullopt when it could not be asked.
  std::optional<DeviceInfo> info;
  // Why the strings or INFO could not be read (e.g. "permission denied: see docs/devices.md (udev)"), "" if fine.
  std::string problem;
};

// Every attached device whose VID:PID is in `ids` (default: the known armatures), sorted by bus and address. Opens
// each briefly to read its strings and INFO (not claiming any interface, so it does not disturb a program that is
// using it). Errors (path "usb") only when libusb itself cannot start. Thread-safe (a private libusb context per
// call).
IoResult<std::vector<UsbDeviceInfo>> listUsbDevices(std::span<const UsbId> ids = kKnownUsbArmatures);

struct UsbTransportOptions {
  uint16_t vendorId = 0x1209, productId = 0x0001;
  // "" = the first matching device (lowest bus, then address) that opens; else the unit with this serial number.
  std::string serialNumber;
  int controlTimeoutMs = 500;   // string descriptors and the INFO request at open
  int inTransfers = 8;          // IN transfers kept in flight so no packet waits for a resubmission
  // Size of each IN transfer, rounded up to whole max packets. A transfer completes at the device's short (or
  // zero-length) packet, so a large one adds no latency and drains a backlog in one completion.
  int inTransferBytes = 4096;
};

// A ByteTransport over a vendor-specific USB armature: write() sends bytes on the interface's OUT endpoint,
// read() returns what the IN endpoint delivered (the bytes of binary-protocol frames, split anywhere). Several IN
// transfers are kept in flight and completed by libusb's event handling inside read(), which returns as soon as
// one completes. Unplugging makes read() and write() fail (LIBUSB_ERROR_NO_DEVICE or
// an I/O error). One thread at a time, like every transport; the destructor cancels the transfers, releases the
// interface, re-attaches a kernel driver it detached and closes the device.
class UsbTransport final : public ByteTransport {
 public:
  // Finds the device (VID:PID, then serial number from its string descriptor), picks the first interface of class
  // 0xFF with an IN and an OUT bulk or interrupt endpoint, detaches a kernel driver bound to it, claims it, asks
  // for INFO (a device that does not answer gets a warning, not an error: the session asks GET_INFO anyway) and
  // starts reading. Errors name "usb 1209:0001" (errorText: "usb 1209:0001: error: …"): not attached, no such
  // serial number, permission denied — see docs/devices.md on udev —, no vendor interface, interface busy.
  static IoResult<std::unique_ptr<UsbTransport>> open(const UsbTransportOptions& options);
  ~UsbTransport() override;
  UsbTransport(const UsbTransport&) = delete;
  UsbTransport& operator=(const UsbTransport&) = delete;

  IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) override;
  IoResult<void> write(std::span<const uint8_t> bytes, int timeoutMs) override;
  std::string description() const override;
  std::vector<std::string> warnings() const override { return warnings_; }

  // What the device was when opened (identity, strings, INFO from the control request).
  const UsbDeviceInfo& info() const { return info_; }
  // Whether a kernel driver had to be detached from the interface (it is re-attached on close).
  bool detachedKernelDriver() const;

 private:
  struct Impl;
  explicit UsbTransport(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  UsbDeviceInfo info_;
  std::vector<std::string> warnings_;
};

// Counts arrivals and departures of one VID:PID through libusb hotplug events, on its own event thread (its own
// libusb context). Devices already attached when it starts count as arrivals. Thread-safe: every member may be
// called from any thread.
class UsbHotplugMonitor {
 public:
  struct Stats {
    uint64_t arrivals = 0;
    uint64_t departures = 0;
    int64_t present = 0;  // arrivals - departures: matching devices attached now
  };
  // Starts monitoring. Errors when libusb cannot start or has no hotplug support on this platform
  // (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG) is false).
  static IoResult<std::unique_ptr<UsbHotplugMonitor>> start(UsbId id);
  ~UsbHotplugMonitor();  // deregisters and joins the event thread
  UsbHotplugMonitor(const UsbHotplugMonitor&) = delete;
  UsbHotplugMonitor& operator=(const UsbHotplugMonitor&) = delete;

  Stats stats() const;
  // Blocks until a matching device is attached (returns true at once if one is) or timeoutMs passes.
  bool waitForPresent(int timeoutMs) const;
  // Blocks until stats().arrivals > arrivals (or departures > departures) or timeoutMs passes.
  bool waitForArrivals(uint64_t arrivals, int timeoutMs) const;
  bool waitForDepartures(uint64_t departures, int timeoutMs) const;

 private:
  struct Impl;
  explicit UsbHotplugMonitor(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A TransportOpener for a USB armature (the session calls it to open and to reconnect). With a monitor that says
// no matching device is attached, it waits up to arrivalWaitMs for one to arrive — so a replugged armature is
// reopened the moment it enumerates — and fails without touching libusb if none does. Without a monitor every call
// tries to open. The monitor is shared with the caller (e.g. to show its counts).
TransportOpener usbOpener(UsbTransportOptions options, std::shared_ptr<UsbHotplugMonitor> monitor = nullptr,
                          int arrivalWaitMs = 400);

}  // namespace imps::drivers
