// SPDX-License-Identifier: MIT
// Tests for drivers/device_spec: the grammar in docs/devices.md, its error messages and round trips.
#include "drivers/device_spec.h"
#include "drivers/device_session.h"

#include <gtest/gtest.h>

namespace imps::drivers {
namespace {

TEST(DeviceSpec, SerialWithQuery) {
  auto spec = parseDeviceSpec("serial:/dev/ttyACM0?baud=57600&protocol=lines&channels=6");
  ASSERT_TRUE(spec) << spec.error().str();
  EXPECT_EQ(spec->kind, DeviceKind::Serial);
  EXPECT_EQ(spec->path, "/dev/ttyACM0");
  EXPECT_EQ(spec->baud, 57600);
  EXPECT_EQ(spec->protocol, WireProtocol::Lines);
  EXPECT_EQ(spec->channels, 6);
  EXPECT_EQ(spec->mode, AcquisitionMode::Stream);
}

TEST(DeviceSpec, SerialDefaultsAndPollMode) {
  auto spec = parseDeviceSpec("serial:/dev/ttyUSB0?mode=poll&rate=60");
  ASSERT_TRUE(spec) << spec.error().str();
  EXPECT_EQ(spec->baud, 115200);
  EXPECT_EQ(spec->protocol, WireProtocol::Binary);
  EXPECT_EQ(spec->mode, AcquisitionMode::Poll);
  EXPECT_EQ(spec->rateHz, 60);
}

TEST(DeviceSpec, HidAndUsbIds) {
  auto hid = parseDeviceSpec("hid:2341:8036?serial=A1B2");
  ASSERT_TRUE(hid) << hid.error().str();
  EXPECT_EQ(hid->kind, DeviceKind::Hid);
  EXPECT_EQ(hid->vendorId, 0x2341);
  EXPECT_EQ(hid->productId, 0x8036);
  EXPECT_EQ(hid->serialNumber, "A1B2");
  auto usb = parseDeviceSpec("usb:1209:1");
  ASSERT_TRUE(usb) << usb.error().str();
  EXPECT_EQ(usb->vendorId, 0x1209);
  EXPECT_EQ(usb->productId, 0x0001);
  // A USB armature speaks the binary protocol: poll or stream mode and a rate (sessionOptionsFor passes them on).
  auto usbPoll = parseDeviceSpec("usb:1209:0001?serial=U1&mode=poll&rate=250");
  ASSERT_TRUE(usbPoll) << usbPoll.error().str();
  EXPECT_EQ(usbPoll->serialNumber, "U1");
  EXPECT_EQ(usbPoll->mode, AcquisitionMode::Poll);
  EXPECT_EQ(usbPoll->rateHz, 250);
  EXPECT_EQ(sessionOptionsFor(*usbPoll).mode, AcquisitionMode::Poll);
  EXPECT_EQ(sessionOptionsFor(*usbPoll).rateHz, 250);
  EXPECT_FALSE(parseDeviceSpec("usb:1209:0001?protocol=lines"));
}

TEST(DeviceSpec, SimKeepsSimulatorKeysInOrder) {
  auto spec = parseDeviceSpec("sim:take3.session?rate=200&noise=2&channels=16");
  ASSERT_TRUE(spec) << spec.error().str();
  EXPECT_EQ(spec->kind, DeviceKind::Sim);
  EXPECT_EQ(spec->path, "take3.session");
  EXPECT_EQ(spec->rateHz, 200);
  ASSERT_EQ(spec->simParams.size(), 2u);
  EXPECT_EQ(spec->simParams[0].first, "noise");
  EXPECT_EQ(spec->simParams[1].second, "16");
  auto bare = parseDeviceSpec("sim:");
  ASSERT_TRUE(bare) << bare.error().str();
  EXPECT_TRUE(bare->path.empty());
}

// A bare device node is a serial port, with the same keys (and error columns into the text as given).
TEST(DeviceSpec, BareDevicePathIsASerialPort) {
  auto bare = parseDeviceSpec("/dev/ttyACM0");
  ASSERT_TRUE(bare) << bare.error().str();
  EXPECT_EQ(*bare, *parseDeviceSpec("serial:/dev/ttyACM0"));
  auto withKeys = parseDeviceSpec("/dev/ttyUSB0?baud=9600&protocol=lines");
  ASSERT_TRUE(withKeys) << withKeys.error().str();
  EXPECT_EQ(withKeys->kind, DeviceKind::Serial);
  EXPECT_EQ(withKeys->path, "/dev/ttyUSB0");
  EXPECT_EQ(withKeys->baud, 9600);
  auto bad = parseDeviceSpec("/dev/ttyACM0?bard=1");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().str().find("spec:1:14: error: unknown key 'bard' for serial"), std::string::npos)
      << bad.error().str();
}

// A line device cannot say its encoders' bits: the spec can, and the session's DeviceInfo reports them, so that
// calibrate (which checks a rig map against the device) and live agree on a 12-bit rig map.
TEST(DeviceSpec, LineBitsReachTheSessionOptions) {
  auto lines = parseDeviceSpec("serial:/dev/ttyACM0?protocol=lines&bits=12");
  ASSERT_TRUE(lines) << lines.error().str();
  EXPECT_EQ(lines->bits, 12);
  EXPECT_EQ(sessionOptionsFor(*lines).lineBitsPerChannel, 12);
  auto unsaid = parseDeviceSpec("serial:/dev/ttyACM0?protocol=lines");
  ASSERT_TRUE(unsaid) << unsaid.error().str();
  EXPECT_EQ(sessionOptionsFor(*unsaid).lineBitsPerChannel, 32);
  // The simulator's own bits key tells the host too when it prints lines.
  auto sim = parseDeviceSpec("sim:?protocol=lines&bits=12");
  ASSERT_TRUE(sim) << sim.error().str();
  EXPECT_EQ(sessionOptionsFor(*sim).lineBitsPerChannel, 12);
}

TEST(DeviceSpec, ErrorsSayWhereAndWhat) {
  struct Case {
    const char* text;
    const char* expected;
  } cases[] = {
      {"ttyACM0", "spec:1:1: error: expected SCHEME:"},
      {"bluetooth:xx", "spec:1:1: error: unknown scheme 'bluetooth'"},
      {"serial:", "spec:1:8: error: expected a device path"},
      {"serial:/dev/ttyACM0?baud=fast", "spec:1:26: error: expected a baud rate"},
      {"serial:/dev/ttyACM0?bard=9600", "spec:1:21: error: unknown key 'bard'"},
      {"serial:/dev/ttyACM0?baud=9600&baud=9600", "spec:1:31: error: key 'baud' given twice"},
      {"serial:/dev/ttyACM0?protocol=ascii", "error: expected protocol=binary or protocol=lines"},
      {"serial:/dev/ttyACM0?rate=70000", "error: expected a rate in Hz"},
      {"serial:/dev/ttyACM0?channels=65", "error: expected a channel count in 0..64"},
      {"serial:/dev/ttyACM0?", "error: expected key=value"},
      {"hid:2341", "spec:1:5: error: expected VID:PID"},
      {"hid:12345:1", "error: expected a USB vendor id"},
      {"usb:1209:xyz", "spec:1:10: error: expected a USB product id"},
      {"usb:1209:0001?baud=9600", "error: unknown key 'baud' for usb"},
      {"osc:9000", "spec:1:1: error: unknown scheme 'osc': expected serial, hid, usb, sim or osc.udp"},
      {"osc.udp://9000", "spec:1:11: error: expected :PORT"},
      {"osc.udp://:0", "spec:1:12: error: expected a UDP port in 1..65535"},
      {"osc.udp://:70000", "spec:1:12: error: expected a UDP port in 1..65535"},
      {"serial:/dev/ttyACM0?protocol=lines&bits=0", "error: expected bits per channel in 1..32"},
      {"serial:/dev/ttyACM0?protocol=lines&bits=33", "error: expected bits per channel in 1..32"},
      {"serial:/dev/ttyACM0?bits=12", "error: bits applies to protocol=lines only"},
  };
  for (const Case& c : cases) {
    auto spec = parseDeviceSpec(c.text);
    ASSERT_FALSE(spec) << c.text;
    EXPECT_NE(spec.error().str().find(c.expected), std::string::npos) << c.text << " gave: " << spec.error().str();
  }
}

TEST(DeviceSpec, OscPoseStream) {
  auto any = parseDeviceSpec("osc.udp://:9000");
  ASSERT_TRUE(any) << any.error().str();
  EXPECT_EQ(any->kind, DeviceKind::Osc);
  EXPECT_EQ(any->port, 9000);
  EXPECT_TRUE(any->path.empty());
  auto bound = parseDeviceSpec("osc.udp://127.0.0.1:9001/");
  ASSERT_TRUE(bound) << bound.error().str();
  EXPECT_EQ(bound->path, "127.0.0.1");
  EXPECT_EQ(bound->port, 9001);
  EXPECT_EQ(formatDeviceSpec(*bound), "osc.udp://127.0.0.1:9001");
}

TEST(DeviceSpec, FormatRoundTrips) {
  for (const char* text : {"serial:/dev/ttyACM0", "serial:/dev/ttyUSB1?baud=9600&protocol=lines&channels=4",
                           "serial:/dev/ttyUSB1?protocol=lines&bits=12",
                           "serial:/dev/ttyACM0?mode=poll&rate=30", "hid:2341:8036?serial=X", "usb:1209:0001",
                           "usb:1209:0001?serial=U1&mode=poll&rate=250",
                           "sim:?rate=1000&channels=64&noise=1", "osc.udp://:9000", "osc.udp://10.0.0.2:57120"}) {
    auto spec = parseDeviceSpec(text);
    ASSERT_TRUE(spec) << spec.error().str();
    EXPECT_EQ(formatDeviceSpec(*spec), text);
    auto again = parseDeviceSpec(formatDeviceSpec(*spec));
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, *spec);
  }
}

}  // namespace
}  // namespace imps::drivers
