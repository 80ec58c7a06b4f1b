// SPDX-License-Identifier: MIT
// `puppeteer devices`: which attached serial ports are likely armatures, so they are listed first.
#pragma once

#include <string>
#include <vector>

#include "drivers/serial_transport.h"

namespace imps::app {

// How likely a serial port is to be an armature, best first.
enum class PortLikelihood : int {
  KnownBoard = 0,  // a USB serial chip or board armatures use (the VIDs of scripts/udev/70-imps-armature.rules)
  OtherUsb = 1,    // another USB serial adapter
  Virtual = 2,     // a pseudo-terminal or similar (puppeteer sim --pty)
  Uart = 3,        // a motherboard UART (/dev/ttyS*, /dev/ttyAMA*): almost never an armature
};
PortLikelihood portLikelihood(const drivers::SerialPortInfo& port);
// The phrase `devices` prints for a likelihood ("likely armature", …).
const char* describe(PortLikelihood likelihood);
// Sorts ports by likelihood, keeping the listing's (path) order within each class.
void rankPorts(std::vector<drivers::SerialPortInfo>& ports);

}  // namespace imps::app
