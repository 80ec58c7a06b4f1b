// SPDX-License-Identifier: MIT
// The vendor-USB adapter: the only file that touches libusb (listing, the transport, hotplug). The USB framing is in
// docs/protocol.md ("USB transport"); everything above the bytes (codec, handshake, reconnects) is DeviceSession's.
#include "drivers/usb_transport.h"

#include <libusb.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <set>
#include <thread>
#include <utility>

#include "drivers/binary_protocol.h"
#include "drivers/receive_buffer.h"
#include "text.h"
#include "imps/clock.h"

namespace imps::drivers {

namespace {

std::string usbError(int code) { return libusb_strerror(static_cast<libusb_error>(code)); }

std::string idText(uint16_t vendorId, uint16_t productId) {
  return cat("usb ", hex4(vendorId), ":", hex4(productId));
}

timeval toTimeval(int64_t us) {
  us = std::max<int64_t>(us, 0);
  return timeval{static_cast<time_t>(us / 1'000'000), static_cast<suseconds_t>(us % 1'000'000)};
}

bool matches(const libusb_device_descriptor& d, std::span<const UsbId> ids) {
  return std::ranges::any_of(ids, [&](const UsbId& id) {
    return id.vendorId == d.idVendor && id.productId == d.idProduct;
  });
}

// A string descriptor as ASCII (libusb replaces other characters), "" when the index is 0 or the read fails.
std::string stringDescriptor(libusb_device_handle* h, uint8_t index) {
  if (index == 0) return {};
  unsigned char buf[256];
  const int n = libusb_get_string_descriptor_ascii(h, index, buf, sizeof buf);
  return n > 0 ? std::string(reinterpret_cast<const char*>(buf), static_cast<size_t>(n)) : std::string();
}

std::string openProblem(int code) {
  if (code == LIBUSB_ERROR_ACCESS)
    return "permission denied (see docs/devices.md, \"Using the rig without root\")";
  return cat("cannot open: ", usbError(code));
}

// Fills the strings and INFO of an open device into `info`; problems go to info.problem. INFO comes from the
// vendor control request (docs/protocol.md, "USB transport"): the DeviceInfo block.
void describeOpen(libusb_device_handle* h, const libusb_device_descriptor& d, int timeoutMs, UsbDeviceInfo& info) {
  info.manufacturer = stringDescriptor(h, d.iManufacturer);
  info.product = stringDescriptor(h, d.iProduct);
  info.serialNumber = stringDescriptor(h, d.iSerialNumber);
  std::vector<unsigned char> buf(kUsbInfoMaxLength);
  const int n = libusb_control_transfer(h, kUsbInfoRequestType, kUsbInfoRequest, 0, 0, buf.data(),
                                        static_cast<uint16_t>(buf.size()), static_cast<unsigned>(timeoutMs));
  if (n < 0) {
    info.problem = cat("the INFO control request failed: ", usbError(n));
    return;
  }
  if (auto i = decodeDeviceInfo(std::span<const uint8_t>(buf.data(), static_cast<size_t>(n))))
    info.info = std::move(*i);
  else
    info.problem = firstMessage(i.error());
}

UsbDeviceInfo identity(libusb_device* dev, const libusb_device_descriptor& d) {
  UsbDeviceInfo info;
  info.vendorId = d.idVendor;
  info.productId = d.idProduct;
  info.bus = libusb_get_bus_number(dev);
  info.address = libusb_get_device_address(dev);
  return info;
}

// The armature's endpoints: the first vendor-class interface with a bulk/interrupt IN and OUT endpoint.
struct VendorInterface {
  int number = -1;
  uint8_t inEndpoint = 0, outEndpoint = 0;
  bool inInterrupt = false, outInterrupt = false;
  int inPacketSize = 64;
};

int maxPacketBytes(const libusb_endpoint_descriptor& e) {
  // Bits 12..11 of a high-speed interrupt endpoint's wMaxPacketSize add transactions per microframe.
  const int size = e.wMaxPacketSize & 0x7FF;
  return std::max(1, size * (1 + ((e.wMaxPacketSize >> 11) & 3)));
}

std::optional<VendorInterface> findVendorInterface(libusb_device* dev) {
  libusb_config_descriptor* config = nullptr;
  if (libusb_get_active_config_descriptor(dev, &config) != 0 && libusb_get_config_descriptor(dev, 0, &config) != 0)
    return std::nullopt;
  std::optional<VendorInterface> found;
  for (int i = 0; i < config->bNumInterfaces && !found; ++i) {
    if (config->interface[i].num_altsetting < 1) continue;
    const libusb_interface_descriptor& alt = config->interface[i].altsetting[0];
    if (alt.bInterfaceClass != kUsbVendorInterfaceClass) continue;
    VendorInterface v;
    v.number = alt.bInterfaceNumber;
    for (int e = 0; e < alt.bNumEndpoints; ++e) {
      const libusb_endpoint_descriptor& ep = alt.endpoint[e];
      const int type = ep.bmAttributes & LIBUSB_TRANSFER_TYPE_MASK;
      if (type != LIBUSB_TRANSFER_TYPE_BULK && type != LIBUSB_TRANSFER_TYPE_INTERRUPT) continue;
      if ((ep.bEndpointAddress & LIBUSB_ENDPOINT_DIR_MASK) == LIBUSB_ENDPOINT_IN) {
        if (v.inEndpoint) continue;
        v.inEndpoint = ep.bEndpointAddress;
        v.inInterrupt = type == LIBUSB_TRANSFER_TYPE_INTERRUPT;
        v.inPacketSize = maxPacketBytes(ep);
      } else if (!v.outEndpoint) {
        v.outEndpoint = ep.bEndpointAddress;
        v.outInterrupt = type == LIBUSB_TRANSFER_TYPE_INTERRUPT;
      }
    }
    if (v.inEndpoint && v.outEndpoint) found = v;
  }
  libusb_free_config_descriptor(config);
  return found;
}

}  // namespace

// ---- Listing --------------------------------------------------------------------------------------------------

IoResult<std::vector<UsbDeviceInfo>> listUsbDevices(std::span<const UsbId> ids) {
  libusb_context* ctx = nullptr;
  if (const int r = libusb_init(&ctx); r != 0)
    return std::unexpected(IoError{"usb", cat("libusb_init: ", usbError(r))});
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(ctx, &list);
  if (count < 0) {
    libusb_exit(ctx);
    return std::unexpected(IoError{"usb", cat("listing devices: ", usbError(static_cast<int>(count)))});
  }
  std::vector<UsbDeviceInfo> out;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) != 0 || !matches(d, ids)) continue;
    UsbDeviceInfo& info = out.emplace_back(identity(list[i], d));
    libusb_device_handle* h = nullptr;
    if (const int r = libusb_open(list[i], &h); r != 0) {
      info.problem = openProblem(r);
      continue;
    }
    describeOpen(h, d, 500, info);
    libusb_close(h);
  }
  libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  std::ranges::sort(out, {}, [](const UsbDeviceInfo& i) { return (i.bus << 8) | i.address; });
  return out;
}

// ---- Transport ------------------------------------------------------------------------------------------------

struct UsbTransport::Impl {
  // One IN transfer kept in flight (whole max packets; it completes at the device's short packet).
  struct InTransfer {
    Impl* impl = nullptr;
    libusb_transfer* transfer = nullptr;
    std::vector<unsigned char> buffer;
    bool active = false;  // submitted and not yet given back by libusb
  };

  libusb_context* ctx = nullptr;
  libusb_device_handle* handle = nullptr;
  VendorInterface vi;
  bool claimed = false;
  bool detached = false;
  bool closing = false;
  std::string name;  // "usb 1209:0001" for messages
  std::vector<InTransfer> in;
  ReceiveBuffer received;  // IN bytes not yet returned by read()
  std::string failure;     // first fatal problem; read()/write() report it once the received bytes are delivered
  int wake = 0;            // set by the IN callback: ends libusb_handle_events_timeout_completed() early

  void fail(std::string why) {
    if (failure.empty()) failure = std::move(why);
  }

  static void LIBUSB_CALL onIn(libusb_transfer* t) {
    auto* slot = static_cast<InTransfer*>(t->user_data);
    Impl& self = *slot->impl;
    self.wake = 1;
    slot->active = false;
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
      case LIBUSB_TRANSFER_TIMED_OUT:
        if (t->actual_length > 0) self.received.append(std::span<const uint8_t>(t->buffer, t->actual_length));
        if (self.closing || !self.failure.empty()) return;
        if (const int r = libusb_submit_transfer(t); r == 0) {
          slot->active = true;
        } else {
          self.fail(r == LIBUSB_ERROR_NO_DEVICE ? std::string("the device was unplugged")
                                                : cat("cannot resubmit an IN transfer: ", usbError(r)));
        }
        return;
      case LIBUSB_TRANSFER_CANCELLED: return;
      case LIBUSB_TRANSFER_NO_DEVICE: self.fail("the device was unplugged"); return;
      case LIBUSB_TRANSFER_STALL: self.fail("the IN endpoint stalled"); return;
      case LIBUSB_TRANSFER_OVERFLOW: self.fail("the device sent more than one max packet (IN overflow)"); return;
      default: self.fail("an IN transfer failed (I/O error: unplugged?)"); return;
    }
  }

  // Runs libusb's event handling until an IN transfer completes, something fails or timeoutMs passes.
  void pump(int timeoutMs) {
    const int64_t deadline = (steadyNowNs() / 1000) + int64_t{std::max(timeoutMs, 0)} * 1000;
    do {
      wake = 0;
      timeval tv = toTimeval(deadline - (steadyNowNs() / 1000));
      const int r = libusb_handle_events_timeout_completed(ctx, &tv, &wake);
      if (r < 0 && r != LIBUSB_ERROR_INTERRUPTED && r != LIBUSB_ERROR_TIMEOUT) {
        fail(cat("libusb event handling failed: ", usbError(r)));
        return;
      }
    } while (received.size() == 0 && failure.empty() && (steadyNowNs() / 1000) < deadline);
  }

  bool anyActive() const {
    return std::ranges::any_of(in, [](const InTransfer& s) { return s.active; });
  }

  ~Impl() {
    closing = true;
    for (InTransfer& s : in)
      if (s.active) libusb_cancel_transfer(s.transfer);
    // Cancelled transfers come back through event handling; an unplugged device gives them back at once.
    const int64_t deadline = (steadyNowNs() / 1000) + 500'000;
    while (ctx && anyActive() && (steadyNowNs() / 1000) < deadline) {
      timeval tv = toTimeval(10'000);
      libusb_handle_events_timeout_completed(ctx, &tv, nullptr);
    }
    for (InTransfer& s : in)
      if (s.transfer && !s.active) libusb_free_transfer(s.transfer);  // one still active is leaked, not freed live
    if (handle) {
      if (claimed) libusb_release_interface(handle, vi.number);
      if (detached) libusb_attach_kernel_driver(handle, vi.number);
      libusb_close(handle);
    }
    if (ctx) libusb_exit(ctx);
  }
};

UsbTransport::UsbTransport(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
UsbTransport::~UsbTransport() = default;

bool UsbTransport::detachedKernelDriver() const { return impl_->detached; }

IoResult<std::unique_ptr<UsbTransport>> UsbTransport::open(const UsbTransportOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->name = idText(options.vendorId, options.productId);
  auto error = [&](std::string what) { return std::unexpected(IoError{impl->name, std::move(what)}); };
  if (const int r = libusb_init(&impl->ctx); r != 0) {
    impl->ctx = nullptr;
    return error(cat("libusb_init: ", usbError(r)));
  }

  // ---- Find the unit: VID:PID, then the serial number from its string descriptor.
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(impl->ctx, &list);
  if (count < 0) return error(cat("listing devices: ", usbError(static_cast<int>(count))));
  const UsbId wanted{options.vendorId, options.productId};
  UsbDeviceInfo info;
  libusb_device_descriptor descriptor{};
  std::vector<std::string> otherSerials;
  std::string openFailure;
  // Candidates in bus/address order, so "the first unit" does not depend on libusb's list order.
  std::vector<libusb_device*> candidates;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device_descriptor d{};
    if (libusb_get_device_descriptor(list[i], &d) == 0 && matches(d, std::span(&wanted, 1)))
      candidates.push_back(list[i]);
  }
  std::ranges::sort(candidates, {}, [](libusb_device* d) {
    return (libusb_get_bus_number(d) << 8) | libusb_get_device_address(d);
  });
  for (libusb_device* candidate : candidates) {
    libusb_device_descriptor d{};
    libusb_get_device_descriptor(candidate, &d);
    libusb_device_handle* h = nullptr;
    if (const int r = libusb_open(candidate, &h); r != 0) {
      openFailure = openProblem(r);
      continue;
    }
    const std::string serial = stringDescriptor(h, d.iSerialNumber);
    if (!options.serialNumber.empty() && serial != options.serialNumber) {
      otherSerials.push_back(serial.empty() ? "(none)" : serial);
      libusb_close(h);
      continue;
    }
    impl->handle = h;
    descriptor = d;
    info = identity(candidate, d);
    info.serialNumber = serial;
    break;
  }
  libusb_free_device_list(list, 1);
  if (!impl->handle) {
    if (!openFailure.empty()) return error(openFailure);
    if (!otherSerials.empty()) {
      std::string seen;
      for (const auto& s : otherSerials) seen += (seen.empty() ? "" : ", ") + s;
      return error(cat("no unit with serial number '", options.serialNumber, "' (attached: ", seen, ")"));
    }
    return error("not attached");
  }
  impl->name = cat(impl->name, " (bus ", int{info.bus}, " address ", int{info.address}, ")");

  // ---- The vendor interface: detach a kernel driver, claim it.
  libusb_device* dev = libusb_get_device(impl->handle);
  auto vi = findVendorInterface(dev);
  if (!vi)
    return error("not an IMPS USB armature: no interface of class 0xff with IN and OUT bulk/interrupt endpoints");
  impl->vi = *vi;
  if (libusb_kernel_driver_active(impl->handle, vi->number) == 1) {
    if (const int r = libusb_detach_kernel_driver(impl->handle, vi->number); r != 0)
      return error(cat("cannot detach the kernel driver from interface ", vi->number, ": ", usbError(r)));
    impl->detached = true;
  }
  if (const int r = libusb_claim_interface(impl->handle, vi->number); r != 0) {
    if (r == LIBUSB_ERROR_BUSY) return error(cat("interface ", vi->number, " is in use by another program"));
    return error(cat("cannot claim interface ", vi->number, ": ", usbError(r)));
  }
  impl->claimed = true;

  // ---- Identity for messages and the INFO control request (the session asks GET_INFO on the bulk pipe anyway).
  const std::string serial = info.serialNumber;
  describeOpen(impl->handle, descriptor, options.controlTimeoutMs, info);
  info.serialNumber = serial;
  std::vector<std::string> warnings;
  if (!info.info) warnings.push_back(cat(impl->name, ": warning: ", info.problem));

  // ---- Keep IN transfers in flight from now on.
  impl->in.resize(static_cast<size_t>(std::clamp(options.inTransfers, 1, 64)));
  for (Impl::InTransfer& s : impl->in) {
    s.impl = impl.get();
    const int packets = std::max(1, (options.inTransferBytes + vi->inPacketSize - 1) / vi->inPacketSize);
    s.buffer.resize(static_cast<size_t>(packets * vi->inPacketSize));
    s.transfer = libusb_alloc_transfer(0);
    if (!s.transfer) return error("out of memory for IN transfers");
    if (vi->inInterrupt)
      libusb_fill_interrupt_transfer(s.transfer, impl->handle, vi->inEndpoint, s.buffer.data(),
                                     static_cast<int>(s.buffer.size()), &Impl::onIn, &s, 0);
    else
      libusb_fill_bulk_transfer(s.transfer, impl->handle, vi->inEndpoint, s.buffer.data(),
                                static_cast<int>(s.buffer.size()), &Impl::onIn, &s, 0);
    if (const int r = libusb_submit_transfer(s.transfer); r != 0)
      return error(cat("cannot start reading endpoint 0x", hex4(vi->inEndpoint).substr(2), ": ", usbError(r)));
    s.active = true;
  }

  std::unique_ptr<UsbTransport> transport(new UsbTransport(std::move(impl)));
  transport->info_ = std::move(info);
  transport->warnings_ = std::move(warnings);
  return transport;
}

IoResult<size_t> UsbTransport::read(std::span<uint8_t> out, int timeoutMs) {
  Impl& s = *impl_;
  if (out.empty()) return 0;
  if (s.received.size() == 0 && s.failure.empty()) s.pump(timeoutMs);
  if (const size_t n = std::min(out.size(), s.received.size()); n > 0) {
    std::memcpy(out.data(), s.received.data() + s.received.begin(), n);
    s.received.consume(n);
    return n;
  }
  if (!s.failure.empty()) return std::unexpected(IoError{s.name, s.failure});
  return 0;
}

IoResult<void> UsbTransport::write(std::span<const uint8_t> bytes, int timeoutMs) {
  Impl& s = *impl_;
  if (!s.failure.empty()) return std::unexpected(IoError{s.name, s.failure});
  if (bytes.empty()) return {};
  int sent = 0;
  auto* data = const_cast<unsigned char*>(bytes.data());  // libusb's API is not const-correct; OUT only reads it
  const int length = static_cast<int>(bytes.size());
  const unsigned timeout = static_cast<unsigned>(std::max(timeoutMs, 1));  // 0 would mean "wait forever"
  const int r = s.vi.outInterrupt ? libusb_interrupt_transfer(s.handle, s.vi.outEndpoint, data, length, &sent, timeout)
                                  : libusb_bulk_transfer(s.handle, s.vi.outEndpoint, data, length, &sent, timeout);
  if (r == 0 && sent == length) return {};
  if (r == LIBUSB_ERROR_NO_DEVICE) s.fail("the device was unplugged");
  if (r == LIBUSB_ERROR_TIMEOUT || r == 0)
    return std::unexpected(IoError{s.name, cat("write timed out after ", sent, " of ", length, " bytes"), ETIMEDOUT});
  return std::unexpected(IoError{s.name, cat("write failed: ", usbError(r))});
}

std::string UsbTransport::description() const {
  std::string text = impl_->name;
  if (!info_.product.empty()) text += cat(" \"", info_.product, "\"");
  if (!info_.serialNumber.empty()) text += cat(" serial ", info_.serialNumber);
  return text;
}

// ---- Hotplug --------------------------------------------------------------------------------------------------

struct UsbHotplugMonitor::Impl {
  libusb_context* ctx = nullptr;
  libusb_hotplug_callback_handle callback{};
  bool registered = false;
  std::thread thread;
  std::atomic<bool> stop{false};
  mutable std::mutex mutex;  // guards the fields below
  mutable std::condition_variable changed;
  std::set<int> attached;  // bus << 8 | address of matching devices attached now
  Stats stats;

  static int LIBUSB_CALL onEvent(libusb_context*, libusb_device* dev, libusb_hotplug_event event, void* user) {
    Impl& self = *static_cast<Impl*>(user);
    const int key = (libusb_get_bus_number(dev) << 8) | libusb_get_device_address(dev);
    {
      std::lock_guard lock(self.mutex);
      // A device enumerated at registration may also be announced by the udev monitor: count each once.
      if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED && self.attached.insert(key).second) ++self.stats.arrivals;
      if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT && self.attached.erase(key) > 0) ++self.stats.departures;
      self.stats.present = static_cast<int64_t>(self.attached.size());
    }
    self.changed.notify_all();
    return 0;  // stay registered
  }

  template <class Pred>
  bool waitFor(int timeoutMs, Pred pred) const {
    std::unique_lock lock(mutex);
    return changed.wait_for(lock, std::chrono::milliseconds(std::max(timeoutMs, 0)), [&] { return pred(stats); });
  }

  ~Impl() {
    stop.store(true);
    if (registered) libusb_hotplug_deregister_callback(ctx, callback);
    if (ctx) libusb_interrupt_event_handler(ctx);
    if (thread.joinable()) thread.join();
    if (ctx) libusb_exit(ctx);
  }
};

UsbHotplugMonitor::UsbHotplugMonitor(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
UsbHotplugMonitor::~UsbHotplugMonitor() = default;

IoResult<std::unique_ptr<UsbHotplugMonitor>> UsbHotplugMonitor::start(UsbId id) {
  const std::string name = idText(id.vendorId, id.productId);
  if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG))
    return std::unexpected(IoError{name, "this libusb has no hotplug support"});
  auto impl = std::make_unique<Impl>();
  if (const int r = libusb_init(&impl->ctx); r != 0) {
    impl->ctx = nullptr;
    return std::unexpected(IoError{name, cat("libusb_init: ", usbError(r))});
  }
  const int r = libusb_hotplug_register_callback(
      impl->ctx,
      static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
      LIBUSB_HOTPLUG_ENUMERATE, id.vendorId, id.productId, LIBUSB_HOTPLUG_MATCH_ANY, &Impl::onEvent, impl.get(),
      &impl->callback);
  if (r != 0) return std::unexpected(IoError{name, cat("cannot register for hotplug events: ", usbError(r))});
  impl->registered = true;
  Impl* self = impl.get();
  impl->thread = std::thread([self] {
    while (!self->stop.load()) {
      timeval tv = toTimeval(200'000);  // libusb_interrupt_event_handler() cuts this short on destruction
      libusb_handle_events_timeout_completed(self->ctx, &tv, nullptr);
    }
  });
  return std::unique_ptr<UsbHotplugMonitor>(new UsbHotplugMonitor(std::move(impl)));
}

UsbHotplugMonitor::Stats UsbHotplugMonitor::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

bool UsbHotplugMonitor::waitForPresent(int timeoutMs) const {
  return impl_->waitFor(timeoutMs, [](const Stats& s) { return s.present > 0; });
}

bool UsbHotplugMonitor::waitForArrivals(uint64_t arrivals, int timeoutMs) const {
  return impl_->waitFor(timeoutMs, [&](const Stats& s) { return s.arrivals > arrivals; });
}

bool UsbHotplugMonitor::waitForDepartures(uint64_t departures, int timeoutMs) const {
  return impl_->waitFor(timeoutMs, [&](const Stats& s) { return s.departures > departures; });
}

// ---- Opener ---------------------------------------------------------------------------------------------------

TransportOpener usbOpener(UsbTransportOptions options, std::shared_ptr<UsbHotplugMonitor> monitor,
                          int arrivalWaitMs) {
  return [options = std::move(options), monitor = std::move(monitor),
          arrivalWaitMs]() -> IoResult<std::unique_ptr<ByteTransport>> {
    if (monitor && !monitor->waitForPresent(arrivalWaitMs))
      return std::unexpected(IoError{idText(options.vendorId, options.productId),
                                     "not attached (waiting for it to be plugged in)", ENODEV});
    auto t = UsbTransport::open(options);
    if (!t) return std::unexpected(t.error());
    return std::unique_ptr<ByteTransport>(std::move(*t));
  };
}

}  // namespace imps::drivers
