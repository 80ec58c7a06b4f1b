// SPDX-License-Identifier: MIT
// Device spec -> transport opener.
#include "device_opener.h"

#include <string>

#include "cli.h"
#include "drivers/hid_transport.h"
#include "drivers/serial_transport.h"
#include "drivers/usb_transport.h"
#include "imps/check.h"
#include "sim/simulated_armature.h"

namespace imps::app {

std::expected<drivers::TransportOpener, OpenerError> openerForSpec(const drivers::DeviceSpec& spec, imps::Clock& clock,
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
      if (!options) return std::unexpected(OpenerError{OpenerError::Kind::BadSpec, std::move(options.error())});
      return sim::simulatedOpener(*options, clock);
    }
    case drivers::DeviceKind::Osc:
      break;
  }
  // An OSC stream carries poses (or channels) as datagrams, not a byte stream: only the live app reads it.
  IMPS_CHECK(spec.kind == drivers::DeviceKind::Osc);  // every other DeviceKind is handled above
  const std::string text = drivers::formatDeviceSpec(spec);
  OpenerError error{OpenerError::Kind::NotBytes, {}};
  std::string message = text + " is an OSC pose stream (docs/osc.md): drive a character with it in ";
  message += "`puppeteer live SCENE --device " + text + "`";
  error.diagnostics.error({std::string("puppeteer ") + command}, std::move(message));
  return std::unexpected(std::move(error));
}

int exitCodeFor(OpenerError::Kind kind) { return kind == OpenerError::Kind::NotBytes ? kExitUsage : kExitInvalidInput; }

}  // namespace imps::app
