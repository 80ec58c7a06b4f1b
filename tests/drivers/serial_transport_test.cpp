// SPDX-License-Identifier: MIT
// Tests for drivers/serial_transport through the real libserialport, on umockdev-mocked USB serial ports
// (tests/support/umockdev_serial.h) whose pty master ends the tests drive.
#include "drivers/serial_transport.h"

#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

#include "umockdev_serial.h"

namespace imps::drivers {
namespace {

using test::UmockdevSerial;

#define IMPS_REQUIRE_UMOCKDEV()                                                                              \
  if (!UmockdevSerial::available())                                                                         \
  GTEST_SKIP() << "needs LD_PRELOAD=libimps_modem_ioctl.so:libumockdev-preload.so.0 (run through CTest)"

// Reads from a pty master until `want` bytes arrived or 2 s passed.
std::string readMaster(int fd, size_t want) {
  std::string out;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (out.size() < want && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 50) > 0 && (p.revents & POLLIN)) {
      char buf[256];
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n > 0) out.append(buf, static_cast<size_t>(n));
    }
  }
  return out;
}

// Reads through the transport until `want` bytes arrived or 2 s passed.
std::string readTransport(ByteTransport& t, size_t want) {
  std::string out;
  std::vector<uint8_t> buf(256);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (out.size() < want && std::chrono::steady_clock::now() < deadline) {
    auto n = t.read(buf, 50);
    if (!n) break;
    out.append(reinterpret_cast<const char*>(buf.data()), *n);
  }
  return out;
}

TEST(SerialTransport, ListsUsbPortsWithIdentity) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  ASSERT_GE(bed.addAcm(), 0) << bed.lastError();
  ASSERT_GE(bed.addFtdi(16), 0) << bed.lastError();
  auto ports = listSerialPorts();
  ASSERT_TRUE(ports) << ports.error().str();
  ASSERT_EQ(ports->size(), 2u);
  const SerialPortInfo& acm = (*ports)[0];
  EXPECT_EQ(acm.path, "/dev/ttyACM0");
  EXPECT_TRUE(acm.isUsb);
  EXPECT_EQ(acm.vendorId, 0x2341);
  EXPECT_EQ(acm.productId, 0x0043);
  EXPECT_EQ(acm.serialNumber, "IMPS0001");
  EXPECT_EQ(acm.product, "Monkey");
  EXPECT_EQ(acm.driver, "cdc_acm");
  EXPECT_FALSE(acm.latencyTimerMs.has_value());
  const SerialPortInfo& ftdi = (*ports)[1];
  EXPECT_EQ(ftdi.path, "/dev/ttyUSB0");
  EXPECT_EQ(ftdi.vendorId, kFtdiVendorId);
  EXPECT_EQ(ftdi.serialNumber, "FT123456");
  EXPECT_EQ(ftdi.driver, "ftdi_sio");
  ASSERT_TRUE(ftdi.latencyTimerMs.has_value());
  EXPECT_EQ(*ftdi.latencyTimerMs, 16);
}

TEST(SerialTransport, MovesBytesBothWays) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  const int master = bed.addAcm();
  ASSERT_GE(master, 0) << bed.lastError();
  auto t = SerialTransport::open("/dev/ttyACM0");
  ASSERT_TRUE(t) << t.error().str();
  EXPECT_EQ((*t)->info().vendorId, 0x2341);
  EXPECT_NE((*t)->description().find("2341:0043"), std::string::npos) << (*t)->description();
  EXPECT_TRUE((*t)->warnings().empty());

  // Device → host, including bytes a terminal in cooked mode would eat or translate (raw mode is required).
  const std::string fromDevice("\xA5\x5A\r\n\x03\x11\x13\x7F\x00 end", 14);
  ASSERT_EQ(::write(master, fromDevice.data(), fromDevice.size()), static_cast<ssize_t>(fromDevice.size()));
  EXPECT_EQ(readTransport(**t, fromDevice.size()), fromDevice);

  // Host → device.
  const std::string toDevice("\x81\r\nHELLO\x00\xFF", 10);
  ASSERT_TRUE((*t)->write(std::span(reinterpret_cast<const uint8_t*>(toDevice.data()), toDevice.size()), 500));
  EXPECT_EQ(readMaster(master, toDevice.size()), toDevice);
}

TEST(SerialTransport, ReadTimesOutWithNothing) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  ASSERT_GE(bed.addAcm(), 0) << bed.lastError();
  auto t = SerialTransport::open("/dev/ttyACM0");
  ASSERT_TRUE(t) << t.error().str();
  std::vector<uint8_t> buf(64);
  const auto start = std::chrono::steady_clock::now();
  auto n = (*t)->read(buf, 30);
  const auto elapsed = std::chrono::steady_clock::now() - start;
  ASSERT_TRUE(n) << n.error().str();
  EXPECT_EQ(*n, 0u);
  EXPECT_GE(elapsed, std::chrono::milliseconds(25));  // it waited rather than spinning
}

TEST(SerialTransport, AbsentPortIsAnErrorNotACrash) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;  // empty: no ports at all
  auto t = SerialTransport::open("/dev/ttyACM0");
  ASSERT_FALSE(t);
  EXPECT_NE(errorText(t.error()).find("/dev/ttyACM0: error:"), std::string::npos) << t.error().str();
  EXPECT_EQ(t.error().path, "/dev/ttyACM0");  // the device, so the message can name it
  EXPECT_EQ(t.error().message.find("error:"), std::string::npos) << "the severity is added by errorText";
}

TEST(SerialTransport, UnplugMakesReadsFail) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  ASSERT_GE(bed.addAcm(), 0) << bed.lastError();
  auto t = SerialTransport::open("/dev/ttyACM0");
  ASSERT_TRUE(t) << t.error().str();
  bed.removeAcm();
  std::vector<uint8_t> buf(64);
  bool failed = false;
  for (int i = 0; i < 100 && !failed; ++i) failed = !(*t)->read(buf, 20).has_value();
  EXPECT_TRUE(failed) << "reads kept succeeding after the device was removed";
  EXPECT_FALSE(SerialTransport::open("/dev/ttyACM0"));
}

TEST(SerialTransport, LowersFtdiLatencyTimerWhenWritable) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  ASSERT_GE(bed.addFtdi(16), 0) << bed.lastError();
  auto t = SerialTransport::open("/dev/ttyUSB0");
  ASSERT_TRUE(t) << t.error().str();
  ASSERT_TRUE((*t)->info().latencyTimerMs.has_value());
  EXPECT_EQ(*(*t)->info().latencyTimerMs, 1);
  EXPECT_EQ(bed.sysAttribute("/sys/devices/pci0000:00/usb1/1-2/1-2:1.0/ttyUSB0/latency_timer"), "1\n");
  EXPECT_TRUE((*t)->warnings().empty());
}

TEST(SerialTransport, WarnsAboutFtdiLatencyWhenLeftAlone) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevSerial bed;
  ASSERT_GE(bed.addFtdi(16), 0) << bed.lastError();
  SerialTransportOptions options;
  options.ftdiLatencyMs = 0;  // do not touch it
  auto t = SerialTransport::open("/dev/ttyUSB0", options);
  ASSERT_TRUE(t) << t.error().str();
  EXPECT_EQ(*(*t)->info().latencyTimerMs, 16);
  ASSERT_EQ((*t)->warnings().size(), 1u);
  EXPECT_NE((*t)->warnings()[0].find("FTDI latency timer is 16 ms"), std::string::npos) << (*t)->warnings()[0];
}

}  // namespace
}  // namespace imps::drivers
