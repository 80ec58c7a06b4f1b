// SPDX-License-Identifier: MIT
// Device spec -> transport opener.
#include "device_opener.h"

#include <cstdio>

#include "cli.h"
#include "drivers/hid_transport.h"
#include "drivers/serial_transport.h"
#include "drivers/usb_transport.h"
#include "sim/simulated_armature.h"

namespace imps::app {

std::expected<drivers::TransportOpener, int> openerForSpec(const drivers::DeviceSpec& spec, imps::Clock& clock,
                                                           const char* command) {
  switch (spec.kind) {
    case drivers::DeviceKind::Serial: {
      drivers::SerialTransportOptions options;
      options.baud = spec.baud;
      return drivers::serialOpener(spec.path, options);
    }
    case drivers::DeviceKind::Hid:
      return drivers::hidOpener(spec.vendorId, spec.productId, spec.serialNumber);
    case drivers::DeviceKind::Usb: {
      drivers::UsbTransportOptions options;
      options.vendorId = spec.vendorId;
      options.productId = spec.productId;
      options.serialNumber = spec.serialNumber;
      // Hotplug events make reconnects prompt; without them (no libusb hotplug here) every retry simply opens.
      auto monitor = drivers::UsbHotplugMonitor::start({spec.vendorId, spec.productId});
      return drivers::usbOpener(options, monitor ? std::shared_ptr(std::move(*monitor)) : nullptr);
    }
    case drivers::DeviceKind::Sim: {
      auto options = sim::armatureOptionsFromSpec(spec);
      if (!options) {
        std::fprintf(stderr, "%s\n", options.error().c_str());
        return std::unexpected(int(kExitInvalidInput));
      }
      return sim::simulatedOpener(*options, clock);
    }
    case drivers::DeviceKind::Osc:
      // An OSC stream carries poses (or channels) as datagrams, not a byte stream: only the live app reads it.
      std::fprintf(stderr,
                   "puppeteer %s: error: %s is an OSC pose stream (docs/osc.md): drive a character with it in "
                   "`puppeteer live SCENE --device %s`\n",
                   command, drivers::formatDeviceSpec(spec).c_str(), drivers::formatDeviceSpec(spec).c_str());
      return std::unexpected(int(kExitUsage));
  }
  std::fprintf(stderr, "puppeteer %s: error: unknown device kind\n", command);  // every DeviceKind is handled above
  return std::unexpected(int(kExitUsage));
}

}  // namespace imps::app
