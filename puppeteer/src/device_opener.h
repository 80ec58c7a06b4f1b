// SPDX-License-Identifier: MIT
// The transport a device spec names, for every command that talks to an armature (record, calibrate, live).
#pragma once

#include <expected>

#include "drivers/byte_transport.h"
#include "drivers/device_spec.h"
#include "imps/diagnostic.h"
#include "sim/session_file.h"

namespace imps::app {

// Why a spec gives no transport. The command prints `diagnostics` and exits with the code for `kind` (cli.h).
struct OpenerError {
  enum class Kind {
    BadSpec,   // the sim: spec's options or its session file are wrong (kExitInvalidInput)
    NotBytes,  // an OSC pose stream: datagrams, not a byte stream; only `live`/`view` read it (kExitUsage)
  };
  Kind kind = Kind::BadSpec;
  Diagnostics diagnostics;
};

// An opener for `spec`: serial ports through libserialport, `hid:` armatures through hidapi, `usb:` armatures
// through libusb (with hotplug), `sim:` through the in-process simulated armature (timed by `clock`, which must
// outlive every transport opened). `command` names the command in the NotBytes message
// ("puppeteer COMMAND: error: …"). Prints nothing. Opening itself happens later, in the session (a device that is
// absent now may be plugged in).
std::expected<drivers::TransportOpener, OpenerError> openerForSpec(const drivers::DeviceSpec& spec, imps::Clock& clock,
                                                                   const char* command);

// The exit code (cli.h) for an OpenerError of this kind.
int exitCodeFor(OpenerError::Kind kind);

}  // namespace imps::app
