// SPDX-License-Identifier: MIT
// The HID adapter: the only file that touches hidapi. Also reads the hidraw node's report descriptor from sysfs
// (hidapi 0.13 has no hid_get_report_descriptor; this is how hidapi 0.14 reads it on Linux).
#include "drivers/hid_transport.h"

#include "text.h"

#include <hidapi/hidapi.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <cwchar>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>

namespace imps::drivers {

namespace {

std::string narrow(const wchar_t* w) {
  if (!w) return {};
  std::string out;
  std::mbstate_t state{};
  char buf[MB_LEN_MAX];
  for (; *w; ++w) {
    const size_t n = std::wcrtomb(buf, *w, &state);
    if (n == static_cast<size_t>(-1)) out += '?';
    else out.append(buf, n);
  }
  return out;
}

std::string hidError(hid_device* device) {
  const std::string e = narrow(hid_error(device));
  return e.empty() ? "unknown hidapi error" : e;
}

void initHidapi() {
  static std::once_flag once;
  std::call_once(once, [] { hid_init(); });
}

// /dev/hidraw3 -> /sys/class/hidraw/hidraw3/device/report_descriptor (what hidapi 0.14 reads on Linux).
// Errors name the sysfs file in their message (they are wrapped into the device's error).
IoResult<std::vector<uint8_t>> readReportDescriptor(const std::string& devicePath) {
  const auto path = std::filesystem::path("/sys/class/hidraw") /
                    std::filesystem::path(devicePath).filename() / "device" / "report_descriptor";
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::unexpected(IoError{"", cat("cannot read ", path.string())});
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.empty()) return std::unexpected(IoError{"", cat(path.string(), " is empty")});
  return bytes;
}

std::string bcdVersion(uint16_t bcd) {
  return cat(bcd >> 8, ".", (bcd >> 4) & 0xF, bcd & 0xF);
}

std::string specText(uint16_t vid, uint16_t pid) { return cat("hid:", hex4(vid), ":", hex4(pid)); }

// Every hidapi entry, one per hidraw node (hidapi lists a node once per top-level collection).
std::vector<HidDeviceEntry> enumerate(uint16_t vid, uint16_t pid) {
  initHidapi();
  std::vector<HidDeviceEntry> out;
  hid_device_info* list = hid_enumerate(vid, pid);
  for (hid_device_info* d = list; d; d = d->next) {
    if (!d->path) continue;
    if (std::ranges::any_of(out, [&](const HidDeviceEntry& e) { return e.path == d->path; })) continue;
    HidDeviceEntry e;
    e.path = d->path;
    e.vendorId = d->vendor_id;
    e.productId = d->product_id;
    e.releaseNumber = d->release_number;
    e.serialNumber = narrow(d->serial_number);
    e.manufacturer = narrow(d->manufacturer_string);
    e.product = narrow(d->product_string);
    e.usagePage = d->usage_page;
    e.usage = d->usage;
    e.interfaceNumber = d->interface_number;
    out.push_back(std::move(e));
  }
  hid_free_enumeration(list);
  std::ranges::sort(out, {}, &HidDeviceEntry::path);
  return out;
}

// Fills entry.layout (or layoutError) from the sysfs report descriptor.
void describeLayout(HidDeviceEntry& entry) {
  auto bytes = readReportDescriptor(entry.path);
  if (!bytes) {
    entry.layoutError = bytes.error().str();
    return;
  }
  auto parsed = parseHidReportDescriptor(*bytes);
  if (!parsed) {
    entry.layoutError = firstError(parsed.error());
    return;
  }
  auto layout = hidArmatureLayout(*parsed);
  if (!layout) {
    entry.layoutError = firstError(layout.error());
    return;
  }
  entry.layout = std::move(*layout);
}

}  // namespace

IoResult<std::vector<HidDeviceEntry>> listHidDevices() {
  std::vector<HidDeviceEntry> out = enumerate(0, 0);
  for (HidDeviceEntry& e : out) describeLayout(e);
  return out;
}

struct HidTransport::Impl {
  hid_device* device = nullptr;
  ~Impl() {
    if (device) hid_close(device);
  }
};

HidTransport::HidTransport(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HidTransport::~HidTransport() = default;

IoResult<std::unique_ptr<HidTransport>> HidTransport::open(uint16_t vendorId, uint16_t productId,
                                                           const std::string& serialNumber) {
  const std::string spec = specText(vendorId, productId);
  // ---- Find the node: by VID:PID and, when given, serial number.
  std::vector<HidDeviceEntry> found = enumerate(vendorId, productId);
  auto match = std::ranges::find_if(
      found, [&](const HidDeviceEntry& e) { return serialNumber.empty() || e.serialNumber == serialNumber; });
  if (match == found.end()) {
    std::string message = "no such HID device";
    if (!serialNumber.empty()) {
      message += cat(" with serial number '", serialNumber, "'");
      if (!found.empty()) {
        message += " (found:";
        for (const HidDeviceEntry& e : found) message += cat(" '", e.serialNumber, "'");
        message += ")";
      }
    }
    return std::unexpected(IoError{spec, message + "; `puppeteer devices` lists what is attached", ENODEV});
  }
  HidDeviceEntry entry = *match;

  // ---- The report descriptor gives the layout.
  auto descriptor = readReportDescriptor(entry.path);
  if (!descriptor) return std::unexpected(IoError{spec, cat(entry.path, ": ", descriptor.error().str())});
  // A descriptor that does not parse or has no channels makes the device unusable: it cannot be opened as one.
  auto parsed = parseHidReportDescriptor(*descriptor);
  if (!parsed) return std::unexpected(IoError{spec, cat(entry.path, ": ", firstError(parsed.error()))});
  auto layout = hidArmatureLayout(*parsed);
  if (!layout) return std::unexpected(IoError{spec, cat(entry.path, ": ", firstError(layout.error()))});
  entry.layout = *layout;

  // ---- Open the node.
  auto impl = std::make_unique<Impl>();
  errno = 0;
  impl->device = hid_open_path(entry.path.c_str());
  if (!impl->device) {
    const int err = errno;
    std::string message = cat("cannot open ", entry.path, ": ", hidError(nullptr));
    if (err == EACCES) message += " (see docs/devices.md, \"Using the rig without root\")";
    return std::unexpected(IoError{spec, std::move(message), err});
  }
  std::unique_ptr<HidTransport> t(new HidTransport(std::move(impl)));

  // ---- The description: the INFO feature report, else the USB strings and the layout.
  const std::string name = !entry.product.empty() ? entry.product : "HID armature " + hex4(vendorId) + ":" +
                                                                        hex4(productId);
  DeviceInfo info = hidFallbackInfo(*layout, name, entry.serialNumber, bcdVersion(entry.releaseNumber));
  if (layout->infoReportId) {
    // hidapi's feature-report buffer always starts with the report number, 0 for a device without report IDs
    // (whose layout size does not count that byte).
    const size_t bytes = layout->infoReportSize + (layout->usesReportIds ? 0 : 1);
    std::vector<uint8_t> report(std::max<size_t>(bytes, 2), 0);
    report[0] = *layout->infoReportId;
    const int n = hid_get_feature_report(t->impl_->device, report.data(), report.size());
    if (n < 0) {
      t->warnings_.push_back(cat(entry.path, ": warning: cannot read the INFO feature report (",
                                 hidError(t->impl_->device), "); using the USB strings"));
    } else {
      report.resize(static_cast<size_t>(n));
      auto fromDevice = parseHidInfoReport(report, /*usesReportIds=*/true);  // the number byte is always there
      if (!fromDevice) {
        t->warnings_.push_back(
            cat(entry.path, ": warning: ", firstMessage(fromDevice.error()), "; using the USB strings"));
      } else if (fromDevice->channelCount != static_cast<int>(layout->channels.size())) {
        t->warnings_.push_back(cat(entry.path, ": warning: the INFO feature report says ", fromDevice->channelCount,
                                   " channels, the report descriptor ", layout->channels.size(),
                                   "; using the descriptor"));
      } else {
        info = std::move(*fromDevice);
        if (info.serialNumber.empty()) info.serialNumber = entry.serialNumber;
      }
    }
  }
  for (const std::string& w : layout->warnings) t->warnings_.push_back(cat(entry.path, ": warning: ", w));
  t->described_ = HidDeviceDescription{std::move(info), std::move(*layout)};
  t->entry_ = std::move(entry);
  return t;
}

IoResult<size_t> HidTransport::read(std::span<uint8_t> out, int timeoutMs) {
  if (out.empty()) return 0;
  const int n = hid_read_timeout(impl_->device, out.data(), out.size(), std::max(timeoutMs, 0));
  // hidapi's only sign of an unplug: -1 (poll reported POLLHUP/POLLERR, or read failed).
  if (n < 0)
    return std::unexpected(IoError{entry_.path, cat("HID read failed (unplugged?): ", hidError(impl_->device))});
  return static_cast<size_t>(n);
}

IoResult<void> HidTransport::write(std::span<const uint8_t> bytes, int) {
  const int n = hid_write(impl_->device, bytes.data(), bytes.size());
  if (n < 0 || static_cast<size_t>(n) != bytes.size())
    return std::unexpected(IoError{entry_.path, cat("HID write failed: ", hidError(impl_->device))});
  return {};
}

std::string HidTransport::description() const {
  return cat(entry_.path, " (", hex4(entry_.vendorId), ":", hex4(entry_.productId),
             entry_.product.empty() ? "" : " ", entry_.product, ")");
}

TransportOpener hidOpener(uint16_t vendorId, uint16_t productId, std::string serialNumber) {
  return [=]() -> IoResult<std::unique_ptr<ByteTransport>> {
    auto t = HidTransport::open(vendorId, productId, serialNumber);
    if (!t) return std::unexpected(t.error());
    return std::unique_ptr<ByteTransport>(std::move(*t));
  };
}

}  // namespace imps::drivers
