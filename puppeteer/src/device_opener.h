// SPDX-License-Identifier: MIT
// The transport a device spec names, for every command that talks to an armature (record, calibrate, live).
#pragma once

#include <expected>

#include "drivers/byte_transport.h"
#include "drivers/device_spec.h"
#include "sim/session_file.h"

namespace imps::app {

// An opener for `spec`: serial ports through libserialport, `hid:` armatures through hidapi, `usb:` armatures
// through libusb (with hotplug), `sim:` through the in-process simulated armature
// (timed by `clock`, which must outlive every transport opened). On failure prints `puppeteer COMMAND: error: …`
// to stderr and returns the exit code to use (cli.h).
std::expected<drivers::TransportOpener, int> openerForSpec(const drivers::DeviceSpec& spec, imps::Clock& clock,
                                                           const char* command);

}  // namespace imps::app
