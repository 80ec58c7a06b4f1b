// SPDX-License-Identifier: MIT
// `puppeteer devices` lists likely armatures first and the motherboard UART last.
#include <gtest/gtest.h>

#include "device_ranking.h"

namespace imps::app {
namespace {

drivers::SerialPortInfo port(std::string path, bool usb = false, uint16_t vid = 0, std::string driver = "") {
  drivers::SerialPortInfo p;
  p.path = std::move(path);
  p.isUsb = usb;
  p.vendorId = vid;
  p.driver = std::move(driver);
  return p;
}

TEST(DeviceRanking, ArmatureBoardsFirstMotherboardUartsLast) {
  // As listSerialPorts returns them: sorted by path, so the UARTs come first.
  std::vector<drivers::SerialPortInfo> ports = {
      port("/dev/pts/3"), port("/dev/ttyACM0", true, 0x2341, "cdc_acm"), port("/dev/ttyS0", false, 0, "serial8250"),
      port("/dev/ttyS1"), port("/dev/ttyUSB0", true, 0x067b, "pl2303"), port("/dev/ttyUSB1", true, 0x0403, "ftdi_sio")};
  rankPorts(ports);
  std::vector<std::string> order;
  for (const auto& p : ports) order.push_back(p.path);
  EXPECT_EQ(order, (std::vector<std::string>{"/dev/ttyACM0", "/dev/ttyUSB1", "/dev/ttyUSB0", "/dev/pts/3",
                                             "/dev/ttyS0", "/dev/ttyS1"}));
  EXPECT_EQ(portLikelihood(ports.front()), PortLikelihood::KnownBoard);
  EXPECT_EQ(portLikelihood(ports.back()), PortLikelihood::Uart);
  EXPECT_NE(std::string(describe(PortLikelihood::Uart)).find("unlikely"), std::string::npos);
}

}  // namespace
}  // namespace imps::app
