// SPDX-License-Identifier: MIT
// Tests for drivers/hid_transport through the real hidapi (hidraw backend) on umockdev-mocked USB HID devices
// (tests/support/umockdev_hid.h), with the test playing the armature: enumeration, open by VID:PID and serial,
// the descriptor and INFO feature report, and a DeviceSession streaming into a PoseMailbox through garbage,
// timeouts, an unplug and a replug.
#include "drivers/hid_transport.h"

#include <gtest/gtest.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "drivers/device_session.h"
#include "drivers/device_spec.h"
#include "drivers/pose_mailbox.h"
#include "eventually.h"
#include "umockdev_hid.h"

namespace imps::drivers {
namespace {

using test::UmockdevHid;

#define IMPS_REQUIRE_UMOCKDEV_HID()                                                                          \
  if (!UmockdevHid::available())                                                                            \
  GTEST_SKIP() << "needs LD_PRELOAD=libimps_hidraw.so:…:libumockdev-preload.so.0 (run through CTest)"

constexpr int kChannels = 3;

// The armature every test plugs in: 3 channels of 12 bits, 16-bit sequence, 32-bit device time (µs), report ID 1,
// INFO in feature report 2.
HidArmatureDescriptorOptions armatureOptions() {
  HidArmatureDescriptorOptions o;
  o.channels = kChannels;
  o.bits = 12;
  o.reportId = 1;
  o.deviceTime = true;
  o.infoReportSize = 200;
  return o;
}

UmockdevHid::Device armature(int index = 0, std::string serial = "HID0001") {
  UmockdevHid::Device d;
  d.index = index;
  d.serialNumber = std::move(serial);
  d.descriptor = hidArmatureDescriptor(armatureOptions());
  return d;
}

DeviceInfo armatureInfo() {
  DeviceInfo info;
  info.name = "IMPS Monkey HID";
  info.serialNumber = "HID0001";
  info.firmwareVersion = "2.1";
  info.channelCount = kChannels;
  info.bitsPerChannel = 12;
  info.channelNames = {"hip", "knee", "ankle"};
  info.hasDeviceTimestamp = true;
  return info;
}

void setInfo(UmockdevHid& bed, int index) {
  auto report = hidInfoReport(armatureInfo(), 2, 200);
  ASSERT_TRUE(report) << report.error().str();
  bed.setFeatureReport(index, 2, *report);
}

// Report ID 1: sequence u16, time u32 (µs), 3 × 12 bits + 4 padding bits — written out by hand.
std::vector<uint8_t> report(uint16_t seq, uint32_t timeUs, uint32_t a, uint32_t b, uint32_t c) {
  const uint64_t packed = a | (uint64_t{b} << 12) | (uint64_t{c} << 24);
  std::vector<uint8_t> r = {0x01, static_cast<uint8_t>(seq), static_cast<uint8_t>(seq >> 8)};
  for (int i = 0; i < 4; ++i) r.push_back(static_cast<uint8_t>(timeUs >> (8 * i)));
  for (int i = 0; i < 5; ++i) r.push_back(static_cast<uint8_t>(packed >> (8 * i)));
  return r;
}

TEST(HidTransport, ListsDevicesWithDescriptorVerdicts) {
  IMPS_REQUIRE_UMOCKDEV_HID();
  UmockdevHid bed;
  ASSERT_TRUE(bed.add(armature(0))) << bed.lastError();
  UmockdevHid::Device pad;  // a plain game pad: X, Y and 8 buttons
  pad.index = 1;
  pad.vendorId = 0x046d;
  pad.productId = 0xc216;
  pad.serialNumber = "";
  pad.manufacturer = "Logitech";
  pad.product = "Dual Action";
  pad.descriptor = {0x05, 0x01, 0x09, 0x05, 0xA1, 0x01, 0x09, 0x30, 0x09, 0x31, 0x15, 0x00, 0x26, 0xFF, 0x00,
                    0x75, 0x08, 0x95, 0x02, 0x81, 0x02, 0x05, 0x09, 0x19, 0x01, 0x29, 0x08, 0x25, 0x01, 0x75,
                    0x01, 0x95, 0x08, 0x81, 0x02, 0xC0};
  ASSERT_TRUE(bed.add(pad)) << bed.lastError();

  auto list = listHidDevices();
  ASSERT_TRUE(list) << list.error().str();
  ASSERT_EQ(list->size(), 2u);
  const HidDeviceEntry& a = (*list)[0];
  EXPECT_EQ(a.path, "/dev/hidraw0");
  EXPECT_EQ(a.vendorId, 0x2341);
  EXPECT_EQ(a.productId, 0x8036);
  EXPECT_EQ(a.serialNumber, "HID0001");
  EXPECT_EQ(a.manufacturer, "IMPS");
  EXPECT_EQ(a.product, "Monkey HID");
  EXPECT_EQ(a.releaseNumber, 0x0102);
  EXPECT_EQ(a.usagePage, kImpsHidUsagePage);  // hidapi read it from the sysfs descriptor
  EXPECT_EQ(a.usage, kImpsUsageArmature);
  EXPECT_EQ(a.interfaceNumber, 0);
  ASSERT_TRUE(a.layout.has_value()) << a.layoutError;
  EXPECT_TRUE(a.looksLikeArmature());
  EXPECT_EQ(a.layout->channels.size(), static_cast<size_t>(kChannels));
  const HidDeviceEntry& p = (*list)[1];
  EXPECT_EQ(p.path, "/dev/hidraw1");
  EXPECT_EQ(p.usagePage, 0x01);
  EXPECT_EQ(p.usage, 0x05);
  ASSERT_TRUE(p.layout.has_value()) << p.layoutError;
  EXPECT_FALSE(p.looksLikeArmature());
  EXPECT_EQ(p.layout->channels.size(), 2u);
}

TEST(HidTransport, OpensByVidPidAndSerialAndReadsInfo) {
  IMPS_REQUIRE_UMOCKDEV_HID();
  UmockdevHid bed;
  ASSERT_TRUE(bed.add(armature(0, "HID0001"))) << bed.lastError();
  ASSERT_TRUE(bed.add(armature(1, "HID0002"))) << bed.lastError();
  setInfo(bed, 0);  // the second unit answers no INFO: its description comes from USB strings

  auto first = HidTransport::open(0x2341, 0x8036);
  ASSERT_TRUE(first) << first.error().str();
  EXPECT_EQ((*first)->entry().path, "/dev/hidraw0");
  ASSERT_NE((*first)->hidDescription(), nullptr);
  EXPECT_EQ((*first)->hidDescription()->info, armatureInfo());
  EXPECT_TRUE((*first)->warnings().empty());
  EXPECT_NE((*first)->description().find("2341:8036"), std::string::npos) << (*first)->description();

  auto second = HidTransport::open(0x2341, 0x8036, "HID0002");
  ASSERT_TRUE(second) << second.error().str();
  EXPECT_EQ((*second)->entry().path, "/dev/hidraw1");
  const DeviceInfo& info = (*second)->hidDescription()->info;
  EXPECT_EQ(info.name, "Monkey HID");
  EXPECT_EQ(info.serialNumber, "HID0002");
  EXPECT_EQ(info.firmwareVersion, "1.02");
  EXPECT_EQ(info.channelCount, kChannels);
  EXPECT_EQ(info.bitsPerChannel, 12);
  EXPECT_TRUE(info.hasDeviceTimestamp);
  ASSERT_EQ((*second)->warnings().size(), 1u);
  EXPECT_NE((*second)->warnings()[0].find("INFO feature report"), std::string::npos) << (*second)->warnings()[0];

  auto none = HidTransport::open(0x2341, 0x8036, "NOPE");
  ASSERT_FALSE(none);
  EXPECT_NE(errorText(none.error()).find("hid:2341:8036: error: no such HID device with serial number 'NOPE'"),
            std::string::npos)
      << none.error().str();
  EXPECT_NE(errorText(none.error()).find("'HID0002'"), std::string::npos) << none.error().str();
  EXPECT_FALSE(HidTransport::open(0x1209, 0x0001));
}

TEST(HidTransport, EachReadIsOneReportAndTimeoutsReturnZero) {
  IMPS_REQUIRE_UMOCKDEV_HID();
  UmockdevHid bed;
  ASSERT_TRUE(bed.add(armature())) << bed.lastError();
  auto t = HidTransport::open(0x2341, 0x8036);
  ASSERT_TRUE(t) << t.error().str();
  ASSERT_TRUE(bed.waitForOpen(0, 2000));
  // Three reports written back to back arrive as three reads, not one merged chunk.
  const auto r1 = report(1, 10, 0x111, 0x222, 0x333), r2 = report(2, 20, 1, 2, 3);
  const std::vector<uint8_t> r3 = {0x01, 0xAA};  // short garbage
  ASSERT_TRUE(bed.sendReport(0, r1) && bed.sendReport(0, r2) && bed.sendReport(0, r3));
  std::vector<uint8_t> buf(kMaxHidReportSize);
  for (const auto& want : {r1, r2, r3}) {
    auto n = (*t)->read(buf, 500);
    ASSERT_TRUE(n) << n.error().str();
    EXPECT_EQ(std::vector<uint8_t>(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(*n)), want);
  }
  const auto start = std::chrono::steady_clock::now();
  auto n = (*t)->read(buf, 30);
  ASSERT_TRUE(n) << n.error().str();
  EXPECT_EQ(*n, 0u);
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(25));
  // Unplug: hidapi's read fails (its only sign), and the device cannot be opened any more.
  bed.unplug(0);
  auto failed = (*t)->read(buf, 500);
  ASSERT_FALSE(failed);
  EXPECT_NE(errorText(failed.error()).find("/dev/hidraw0: error: HID read failed"), std::string::npos)
      << errorText(failed.error());
  EXPECT_FALSE(HidTransport::open(0x2341, 0x8036));
}

TEST(HidTransport, SessionStreamsSurvivesGarbageTimesOutAndReconnects) {
  IMPS_REQUIRE_UMOCKDEV_HID();
  UmockdevHid bed;
  ASSERT_TRUE(bed.add(armature())) << bed.lastError();
  setInfo(bed, 0);
  auto spec = parseDeviceSpec("hid:2341:8036?serial=HID0001");
  ASSERT_TRUE(spec) << spec.error().str();
  DeviceSessionOptions o = sessionOptionsFor(*spec);
  EXPECT_EQ(o.protocol, WireProtocol::HidReports);
  o.sampleTimeoutMs = 150;
  o.timeoutsBeforeLost = 100;  // this test wants timeouts counted, not a loss
  o.reconnectIntervalMs = 50;
  PoseMailboxOptions mo;
  mo.queueCapacity = 1024;
  PoseMailbox mailbox(mo);
  DeviceSession session(hidOpener(spec->vendorId, spec->productId, spec->serialNumber), mailbox, o);
  session.start();
  ASSERT_TRUE(bed.waitForOpen(0, 3000)) << session.lastError();
  ASSERT_TRUE(session.waitForState(ConnectionState::WaitingForHello, 2000));
  EXPECT_EQ(session.deviceInfo(), armatureInfo());

  // ---- A stream of samples, byte-exact, with garbage between them.
  std::vector<Sample> sent;
  for (uint16_t i = 0; i < 50; ++i) {
    const uint32_t a = (i * 37u) % 4095, b = (i * 91u + 7) % 4095, c = i == 10 ? 0xFFF : (i * 13u) % 4095;
    ASSERT_TRUE(bed.sendReport(0, report(static_cast<uint16_t>(100 + i), 5000 + 1000u * i, a, b, c)));
    Sample s;
    s.sequence = 100 + i;
    s.deviceTimeNs = (5000 + 1000 * int64_t{i}) * 1000;
    s.channelCount = kChannels;
    s.counts[0] = a;
    s.counts[1] = b;
    s.counts[2] = c;
    if (c == 0xFFF) s.flags[2] = ChannelFlag::NotConnected;
    sent.push_back(s);
    if (i == 20) {
      ASSERT_TRUE(bed.sendReport(0, {0x01, 0x02}));                   // short
      ASSERT_TRUE(bed.sendReport(0, {0x09, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));  // unknown report ID
      auto cut = report(0, 0, 0, 0, 0);
      cut.pop_back();
      ASSERT_TRUE(bed.sendReport(0, cut));                            // one byte short
      // (An empty report cannot be told from a timeout through hidapi: hid_read_timeout returns 0 for both.)
    }
  }
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 50; })) << session.stats().samples;
  EXPECT_EQ(session.state(), ConnectionState::Streaming);
  std::vector<Sample> got;
  mailbox.drain(got);
  ASSERT_EQ(got.size(), sent.size());
  for (size_t i = 0; i < got.size(); ++i) {
    EXPECT_GT(got[i].arrivalTimeNs, 0);
    got[i].arrivalTimeNs = 0;
    EXPECT_EQ(got[i], sent[i]) << "sample " << i;
  }
  DeviceSessionStats st = session.stats();
  EXPECT_EQ(st.malformedFrames, 3u);
  EXPECT_EQ(st.samplesDropped, 0u);
  EXPECT_EQ(st.connections, 1u);

  // ---- A gap in the sequence is counted as dropped samples.
  ASSERT_TRUE(bed.sendReport(0, report(153, 60000, 1, 2, 3)));  // 150..152 missing
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 51; }));
  EXPECT_EQ(session.stats().samplesDropped, 3u);

  // ---- Silence: timeouts are counted, the connection stays.
  ASSERT_TRUE(eventually([&] { return session.stats().timeouts >= 2; }));
  EXPECT_EQ(session.state(), ConnectionState::Streaming);

  // ---- Unplug mid-stream: Lost, the last pose stays in the mailbox.
  const uint64_t before = session.stats().samples;
  bed.unplug(0);
  ASSERT_TRUE(session.waitForState(ConnectionState::Lost, 3000)) << toString(session.state());
  // lastError() is the latest problem: the failed read naming the node, or already (on a loaded machine) the first
  // retry's failure to find the device again.
  const std::string lost = session.lastError();
  EXPECT_TRUE(lost.find("hidraw0") != std::string::npos || lost.find("no such HID device") != std::string::npos)
      << lost;
  auto last = mailbox.takeNewest();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->sequence, 153u);
  EXPECT_EQ(last->counts[2], 3u);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_GE(session.stats().openFailures, 1u);  // it keeps trying while the device is away
  EXPECT_EQ(session.stats().samples, before);

  // ---- Replug: reconnects and streams again (the device restarted its counter).
  bed.replug(0);
  ASSERT_TRUE(bed.waitForOpen(0, 3000)) << session.lastError();
  ASSERT_TRUE(bed.sendReport(0, report(0, 0, 7, 8, 9)));
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 3000)) << toString(session.state());
  ASSERT_TRUE(eventually([&] { return session.stats().samples == before + 1; }));
  st = session.stats();
  EXPECT_EQ(st.connections, 2u);
  EXPECT_EQ(st.reconnects, 1u);
  last = mailbox.takeNewest();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->sequence, 0u);
  EXPECT_EQ(last->counts[0], 7u);
  session.stop();
  EXPECT_EQ(session.state(), ConnectionState::Disconnected);
}

TEST(HidTransport, SilentDeviceIsLostAfterRepeatedTimeouts) {
  IMPS_REQUIRE_UMOCKDEV_HID();
  UmockdevHid bed;
  ASSERT_TRUE(bed.add(armature())) << bed.lastError();
  DeviceSessionOptions o;
  o.protocol = WireProtocol::HidReports;
  o.bootWaitMs = 0;
  o.sampleTimeoutMs = 60;
  o.timeoutsBeforeLost = 2;
  o.reconnectIntervalMs = 1000;
  PoseMailbox mailbox;
  DeviceSession session(hidOpener(0x2341, 0x8036), mailbox, o);
  session.start();
  ASSERT_TRUE(bed.waitForOpen(0, 3000)) << session.lastError();
  ASSERT_TRUE(session.waitForState(ConnectionState::Lost, 3000)) << toString(session.state());
  EXPECT_GE(session.stats().timeouts, 2u);
  EXPECT_NE(session.lastError().find("no HID input reports"), std::string::npos) << session.lastError();
}

}  // namespace
}  // namespace imps::drivers
