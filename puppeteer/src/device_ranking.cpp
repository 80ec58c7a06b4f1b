// SPDX-License-Identifier: MIT
// Serial ports ranked by how likely they are to be an armature (see device_ranking.h).
#include "device_ranking.h"

#include <algorithm>
#include <cstdint>

namespace imps::app {

PortLikelihood portLikelihood(const drivers::SerialPortInfo& port) {
  if (port.isUsb) {
    // Arduino (2341, 2a03), CH340 (1a86), CP210x (10c4), FTDI (0403), pid.codes armatures (1209).
    constexpr uint16_t kBoards[] = {0x2341, 0x2a03, 0x1a86, 0x10c4, 0x0403, 0x1209};
    return std::find(std::begin(kBoards), std::end(kBoards), port.vendorId) != std::end(kBoards)
               ? PortLikelihood::KnownBoard
               : PortLikelihood::OtherUsb;
  }
  const std::string& p = port.path;
  if (p.starts_with("/dev/ttyS") || p.starts_with("/dev/ttyAMA") || p.starts_with("/dev/ttymxc") ||
      port.driver == "serial8250" || port.driver == "serial")
    return PortLikelihood::Uart;
  return PortLikelihood::Virtual;
}

const char* describe(PortLikelihood likelihood) {
  switch (likelihood) {
    case PortLikelihood::KnownBoard: return "likely armature (a board armatures use)";
    case PortLikelihood::OtherUsb: return "possible armature (USB serial)";
    case PortLikelihood::Virtual: return "virtual port";
    case PortLikelihood::Uart: return "motherboard UART, unlikely to be an armature";
  }
  return "?";
}

void rankPorts(std::vector<drivers::SerialPortInfo>& ports) {
  std::stable_sort(ports.begin(), ports.end(), [](const auto& a, const auto& b) {
    return static_cast<int>(portLikelihood(a)) < static_cast<int>(portLikelihood(b));
  });
}

}  // namespace imps::app
