// SPDX-License-Identifier: MIT
// Tests for sim/simulated_armature: the device model on a manual clock (decoded with the drivers' own decoders),
// the in-process `sim:` transport under a DeviceSession, and the drivers' real libserialport path against the
// simulator on a umockdev-mocked /dev/ttyACM0 (tests/support/umockdev_serial.h).
#include "sim/simulated_armature.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "drivers/device_session.h"
#include "drivers/line_protocol.h"
#include "drivers/serial_transport.h"
#include "eventually.h"
#include "umockdev_serial.h"

namespace imps::sim {
namespace {

using namespace imps::drivers;
constexpr int64_t kMs = 1'000'000;
constexpr int64_t kS = 1'000'000'000;

std::vector<Message> decodeAll(BinaryDecoder& d, const std::vector<uint8_t>& bytes) {
  d.feed(bytes);
  std::vector<Message> out;
  while (auto m = d.next()) out.push_back(*m);
  return out;
}

std::vector<uint8_t> command(uint32_t seq, Payload p) {
  std::vector<uint8_t> out;
  EXPECT_TRUE(appendFrame(Message{seq, 0, std::move(p)}, out));
  return out;
}

TEST(SimulatedArmature, BootsWithBannerThenHello) {
  ArmatureOptions o;
  o.bootBanner = {"IMPS bootloader", "ok"};
  o.bootDelayNs = 1500 * kMs;
  SimulatedArmature a(o);
  a.powerOn(0);
  std::vector<uint8_t> out;
  a.produce(1000 * kMs, out);
  EXPECT_TRUE(out.empty());  // still in the bootloader
  a.receive(command(0, msg::HostHello{}), 1000 * kMs);
  EXPECT_EQ(a.stats().commandsIgnored, 1u);
  EXPECT_EQ(a.nextDueNs(), 1500 * kMs);
  a.produce(1500 * kMs, out);
  const std::string text(out.begin(), out.begin() + 23);
  EXPECT_EQ(text, "IMPS bootloader\r\nok\r\n\xA5Z");
  BinaryDecoder d;
  auto messages = decodeAll(d, out);
  ASSERT_EQ(messages.size(), 1u);
  ASSERT_TRUE(std::holds_alternative<msg::Hello>(messages[0].payload));
  EXPECT_EQ(std::get<msg::Hello>(messages[0].payload).info, o.info);
  EXPECT_EQ(messages[0].flags & kFlagReply, 0);
}

TEST(SimulatedArmature, AnswersCommandsAndStreamsOnSchedule) {
  SimulatedArmature a(ArmatureOptions{});
  a.powerOn(0);
  std::vector<uint8_t> out;
  a.produce(0, out);  // HELLO
  a.receive(command(7, msg::GetInfo{}), 10 * kMs);
  a.receive(command(8, msg::StartStream{100}), 10 * kMs);
  a.produce(10 * kMs + kS - 1, out);  // one second minus a nanosecond at 100 Hz: samples 0..99
  BinaryDecoder d;
  auto m = decodeAll(d, out);
  ASSERT_EQ(m.size(), 3u + 100u);
  EXPECT_EQ(m[1].type(), MessageType::Info);
  EXPECT_EQ(m[1].sequence, 7u);
  EXPECT_EQ(m[2].type(), MessageType::Ack);
  EXPECT_EQ(m[2].sequence, 8u);
  for (uint32_t i = 0; i < 100; ++i) {
    const auto& s = std::get<msg::SampleFrame>(m[3 + i].payload).sample;
    EXPECT_EQ(s.sequence, i);
    EXPECT_EQ(s.deviceTimeNs, 10 * kMs + i * 10 * kMs);  // due times, on the device's clock
    EXPECT_EQ(s.channelCount, 32);
    for (int c = 0; c < 32; ++c) EXPECT_LT(s.counts[c], 4096u);
  }
  EXPECT_EQ(d.stats().samplesDropped, 0u);
  // STOP_STREAM: acknowledged, nothing more.
  out.clear();
  a.receive(command(9, msg::StopStream{}), 2 * kS);
  a.produce(3 * kS, out);
  EXPECT_EQ(decodeAll(d, out).size(), 1u + 100u);  // the ACK, plus samples due between 1.01 s and 2 s
}

TEST(SimulatedArmature, PollAndBadRate) {
  SimulatedArmature a(ArmatureOptions{});
  a.powerOn(0);
  std::vector<uint8_t> out;
  a.produce(0, out);
  a.receive(command(1, msg::Poll{}), 5 * kMs);
  a.receive(command(2, msg::StartStream{60000}), 5 * kMs);
  a.receive(command(3, msg::Ack{MessageType::Poll}), 5 * kMs);  // a device message sent to the device
  a.produce(5 * kMs, out);
  BinaryDecoder d;
  auto m = decodeAll(d, out);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[1].type(), MessageType::Error);
  EXPECT_EQ(std::get<msg::Error>(m[1].payload).code, ErrorCode::BadRate);
  EXPECT_EQ(std::get<msg::Error>(m[2].payload).code, ErrorCode::UnknownCommand);
  EXPECT_EQ(m[3].type(), MessageType::Sample);
  EXPECT_NE(m[3].flags & kFlagReply, 0);
  EXPECT_FALSE(a.streaming());
}

TEST(SimulatedArmature, FaultsAreDeterministicAndDecoderCountsThem) {
  ArmatureOptions o;
  o.streamAtBoot = true;
  o.rateHz = 1000;
  o.dropoutProbability = 0.05;
  o.garbageProbability = 0.05;
  o.corruptProbability = 0.05;
  o.noiseCounts = 3;
  o.seed = 42;
  auto run = [&] {
    SimulatedArmature a(o);
    a.powerOn(0);
    std::vector<uint8_t> out;
    for (int64_t t = 0; t < 2 * kS; t += 7 * kMs) a.produce(t, out);
    a.produce(2 * kS, out);
    return std::pair(out, a.stats());
  };
  auto [bytes, stats] = run();
  EXPECT_EQ(run().first, bytes);  // same seed, same bytes
  EXPECT_EQ(stats.samplesTaken, 2001u);
  EXPECT_GT(stats.samplesDropped, 0u);
  EXPECT_GT(stats.samplesCorrupted, 0u);
  EXPECT_GT(stats.garbageBytes, 0u);
  BinaryDecoder d;
  auto m = decodeAll(d, bytes);
  // Every sample that was sent uncorrupted comes out; corrupted ones fail their CRC and are skipped.
  EXPECT_EQ(d.stats().samples, stats.samplesSent - stats.samplesCorrupted);
  EXPECT_GE(d.stats().headerCrcErrors + d.stats().crcErrors, stats.samplesCorrupted / 2);
  EXPECT_GT(d.stats().bytesSkipped, stats.garbageBytes / 2);
  // Gaps are seen between received samples only: a loss at either end of the stream is invisible.
  EXPECT_LE(d.stats().samplesDropped, stats.samplesDropped + stats.samplesCorrupted);
  EXPECT_GE(d.stats().samplesDropped + 2, stats.samplesDropped + stats.samplesCorrupted);
}

TEST(SimulatedArmature, LineProtocolDecodes) {
  ArmatureOptions o;
  o.protocol = WireProtocol::Lines;
  o.info = ArmatureOptions::defaultInfo(6, 10);
  o.bootBanner = {"DIY armature v0.2", "ready"};
  o.rateHz = 50;
  SimulatedArmature a(o);
  a.powerOn(0);
  std::vector<uint8_t> out;
  a.produce(kS, out);  // samples at 0, 20, …, 1000 ms
  LineDecoder d;
  d.feed(out);
  std::vector<Sample> samples;
  while (auto s = d.next()) samples.push_back(*s);
  ASSERT_EQ(samples.size(), 51u);
  EXPECT_EQ(d.banner(), o.bootBanner);
  EXPECT_EQ(d.channelCount(), 6);
  EXPECT_EQ(samples[1].deviceTimeNs, 20 * kMs);
  EXPECT_EQ(samples[7].counts, a.poseAt(7, 140 * kMs).counts);
}

TEST(SimulatedArmature, PlaysRecordedSamples) {
  ArmatureOptions o;
  o.info = ArmatureOptions::defaultInfo(2, 16);
  for (uint32_t i = 0; i < 3; ++i) {
    Sample s;
    s.channelCount = 2;
    s.counts[0] = 100 * i;
    s.counts[1] = 65535;
    o.recorded.push_back(s);
  }
  SimulatedArmature a(o);
  EXPECT_EQ(a.poseAt(4, 0).counts[0], 100u);  // loops: 4 % 3 == 1
  EXPECT_EQ(a.poseAt(4, 0).counts[1], 65535u);
}

TEST(SimulatedArmature, SpecOptions) {
  auto spec = parseDeviceSpec("sim:?channels=64&bits=16&rate=1000&noise=1.5&banner=a|b&unplug_ms=300&replug_ms=200");
  ASSERT_TRUE(spec) << spec.error().str();
  auto o = armatureOptionsFromSpec(*spec);
  ASSERT_TRUE(o) << o.error().str();
  EXPECT_EQ(o->info.channelCount, 64);
  EXPECT_EQ(o->info.bitsPerChannel, 16);
  EXPECT_EQ(o->rateHz, 1000);
  EXPECT_EQ(o->noiseCounts, 1.5);
  EXPECT_EQ(o->bootBanner, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(o->unplugAtNs, 300 * kMs);
  EXPECT_EQ(o->replugAfterNs, 200 * kMs);
  auto bad = armatureOptionsFromSpec(*parseDeviceSpec("sim:?chanels=4"));
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().str().find("sim key 'chanels': unknown"), std::string::npos) << bad.error().str();
  EXPECT_FALSE(armatureOptionsFromSpec(*parseDeviceSpec("sim:?channels=65")));
  EXPECT_FALSE(armatureOptionsFromSpec(*parseDeviceSpec("sim:/nonexistent.session")));
}

TEST(SimulatedArmature, TimeKeysOutOfRangeAreRefusedNotWrapped) {
  // 9223372036854 ms is 9.2e18 ns: multiplied out it overflowed int64 and the key was silently ignored.
  for (const char* key : {"boot_ms", "unplug_ms", "replug_ms"}) {
    auto bad = armatureOptionsFromSpec(*parseDeviceSpec(std::string("sim:?") + key + "=9223372036854"));
    ASSERT_FALSE(bad) << key;
    EXPECT_NE(bad.error().str().find(std::string("sim key '") + key +
                                     "': bad value '9223372036854': expected milliseconds "
                                     "from 0 to 31536000000 (a year)"),
              std::string::npos)
        << bad.error().str();
  }
  auto year = armatureOptionsFromSpec(*parseDeviceSpec("sim:?boot_ms=31536000000"));
  ASSERT_TRUE(year) << year.error().str();
  EXPECT_EQ(year->bootDelayNs, int64_t{31536000000} * kMs);
}

// An unknown key lists every key a sim: spec takes — the spec's own (rate, protocol, mode) included — and each
// listed key is accepted.
TEST(SimulatedArmature, UnknownKeyListsEveryKnownKey) {
  auto bad = armatureOptionsFromSpec(*parseDeviceSpec("sim:?rat=1000"));
  ASSERT_FALSE(bad);
  const std::string& message = bad.error().str();
  const std::vector<std::pair<std::string, std::string>> keys = {
      {"protocol", "lines"}, {"mode", "poll"},     {"rate", "100"},        {"channels", "8"},   {"bits", "12"},
      {"motion", "still"},   {"period_s", "4"},    {"noise", "1"},         {"dropout", "0.1"},  {"garbage", "0.1"},
      {"corrupt", "0.1"},    {"banner", "hi"},     {"boot_ms", "10"},      {"unplug_ms", "10"}, {"replug_ms", "10"},
      {"stream_at_boot", "1"}, {"timestamps", "0"}, {"seed", "3"}};
  for (const auto& [key, value] : keys) {
    EXPECT_NE(message.find(" " + key), std::string::npos) << key << " is not listed: " << message;
    auto spec = parseDeviceSpec("sim:?" + key + "=" + value);
    ASSERT_TRUE(spec) << key << ": " << spec.error().str();
    EXPECT_TRUE(armatureOptionsFromSpec(*spec)) << key;
  }
  size_t listed = 1;
  for (char c : std::string(kSimKeys)) listed += c == ',' ? 1 : 0;
  EXPECT_EQ(listed, keys.size()) << kSimKeys;
  auto motion = armatureOptionsFromSpec(*parseDeviceSpec("sim:?motion=dance"));
  ASSERT_FALSE(motion);
  EXPECT_NE(motion.error().str().find("expected wave, still or sweep"), std::string::npos) << motion.error().str();
}

// motion=still holds one pose (mid-scale on every channel); the default wave moves; sweep covers 10..90 %.
TEST(SimulatedArmature, GeneratedMotions) {
  auto make = [](const std::string& spec) {
    auto o = armatureOptionsFromSpec(*parseDeviceSpec(spec));
    EXPECT_TRUE(o) << o.error().str();
    return SimulatedArmature(*o);
  };
  const SimulatedArmature still = make("sim:?motion=still"), wave = make("sim:"), sweep = make("sim:?motion=sweep");
  uint32_t sweepLow = 4096, sweepHigh = 0;
  bool waveMoved = false;
  for (int64_t t = 0; t < 2'000'000'000; t += 10'000'000) {
    const Sample s = still.poseAt(0, t), w = wave.poseAt(0, t), w0 = wave.poseAt(0, 0), sw = sweep.poseAt(0, t);
    for (int c = 0; c < 32; ++c) {
      EXPECT_EQ(s.counts[c], 2048u);
      waveMoved = waveMoved || w.counts[c] != w0.counts[c];
      sweepLow = std::min(sweepLow, sw.counts[c]);
      sweepHigh = std::max(sweepHigh, sw.counts[c]);
    }
  }
  EXPECT_TRUE(waveMoved);
  EXPECT_LT(sweepLow, 450u);
  EXPECT_GT(sweepHigh, 3650u);
}

// ---- Through a DeviceSession

DeviceSessionOptions fastOptions() {
  DeviceSessionOptions o;
  o.bootWaitMs = 300;
  o.replyTimeoutMs = 300;
  o.sampleTimeoutMs = 300;
  o.reconnectIntervalMs = 50;
  o.ioWaitMs = 5;
  return o;
}

PoseMailboxOptions withQueue(size_t capacity) {
  PoseMailboxOptions o;
  o.queueCapacity = capacity;
  return o;
}

TEST(SimulatedArmatureSession, InProcessUnplugAndReplug) {
  auto spec = parseDeviceSpec("sim:?rate=200&channels=8&unplug_ms=400&replug_ms=300");
  ASSERT_TRUE(spec);
  auto options = armatureOptionsFromSpec(*spec);
  ASSERT_TRUE(options) << options.error().str();
  SteadyClock clock;
  PoseMailbox mailbox;
  DeviceSessionOptions so = fastOptions();
  so.rateHz = 200;
  DeviceSession session(simulatedOpener(*options, clock), mailbox, so);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  ASSERT_TRUE(eventually([&] {
    const auto s = session.state();
    return s == ConnectionState::Lost || s == ConnectionState::Reconnecting;
  })) << toString(session.state());
  const uint64_t before = session.stats().samples;
  EXPECT_GT(before, 20u);
  Sample last;
  EXPECT_TRUE(mailbox.latest(last));  // the last pose stays available while lost
  ASSERT_TRUE(eventually([&] { return session.stats().reconnects == 1; })) << session.lastError();
  ASSERT_TRUE(eventually([&] { return session.stats().samples > before + 20; }));
  EXPECT_EQ(session.deviceInfo()->channelCount, 8);
  session.stop();
}

#define IMPS_REQUIRE_UMOCKDEV()                                                                              \
  if (!test::UmockdevSerial::available())                                                                   \
  GTEST_SKIP() << "needs LD_PRELOAD=libimps_modem_ioctl.so:libumockdev-preload.so.0 (run through CTest)"

// The simulator on umockdev's /dev/ttyACM0, the real drivers on the other end.
struct UmockdevRig {
  test::UmockdevSerial bed;
  SteadyClock clock;
  std::unique_ptr<ArmatureFdServer> server;

  bool start(ArmatureOptions options) {
    const int master = bed.addAcm();
    if (master < 0) return false;
    ArmatureFdServer::Hooks hooks;
    hooks.onUnplug = [this] { bed.unplugAcmNode(); };
    hooks.onReplug = [this] { return bed.replugAcmNode(); };
    server = std::make_unique<ArmatureFdServer>(SimulatedArmature(std::move(options)), master, clock, hooks);
    server->start();
    return true;
  }
  ~UmockdevRig() {
    if (server) server->stop();
  }
};

TEST(SimulatedArmatureSerial, HandshakeInfoAndStreamThroughLibserialport) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ArmatureOptions o;
  o.bootBanner = {"Arduino boot noise"};
  o.bootDelayNs = 50 * kMs;
  ASSERT_TRUE(rig.start(o)) << rig.bed.lastError();
  PoseMailbox mailbox(withQueue(4096));
  DeviceSessionOptions so = fastOptions();
  so.rateHz = 250;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 100; })) << session.lastError();
  EXPECT_EQ(*session.deviceInfo(), o.info);
  session.stop();
  std::vector<Sample> got;
  mailbox.drain(got);
  ASSERT_GE(got.size(), 100u);
  for (size_t i = 1; i < got.size(); ++i) EXPECT_EQ(got[i].sequence, got[i - 1].sequence + 1);
  const DeviceSessionStats s = session.stats();
  EXPECT_EQ(s.samplesDropped, 0u);
  EXPECT_EQ(s.crcErrors, 0u);
}

TEST(SimulatedArmatureSerial, PollModeThroughLibserialport) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ASSERT_TRUE(rig.start(ArmatureOptions{})) << rig.bed.lastError();
  PoseMailbox mailbox(withQueue(1024));
  DeviceSessionOptions so = fastOptions();
  so.mode = AcquisitionMode::Poll;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 100; })) << session.lastError();
  session.stop();
  std::vector<Sample> got;
  mailbox.drain(got);
  for (size_t i = 1; i < got.size(); ++i) EXPECT_EQ(got[i].sequence, got[i - 1].sequence + 1);
  EXPECT_EQ(session.stats().timeouts, 0u);
}

TEST(SimulatedArmatureSerial, GarbageAndCorruptionResync) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ArmatureOptions o;
  o.garbageProbability = 0.1;
  o.corruptProbability = 0.1;
  o.seed = 7;
  ASSERT_TRUE(rig.start(o)) << rig.bed.lastError();
  PoseMailbox mailbox;
  DeviceSessionOptions so = fastOptions();
  so.rateHz = 500;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 300; })) << session.lastError();
  const DeviceSessionStats s = session.stats();
  EXPECT_GT(s.crcErrors, 0u);
  EXPECT_GT(s.garbageBytes, 0u);
  EXPECT_GT(s.samplesDropped, 0u);  // the corrupted samples, seen as sequence gaps
  EXPECT_EQ(s.state, ConnectionState::Streaming);
  session.stop();
}

TEST(SimulatedArmatureSerial, UnplugAndReconnect) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ArmatureOptions o;
  o.unplugAtNs = 600 * kMs;
  o.replugAfterNs = 400 * kMs;
  ASSERT_TRUE(rig.start(o)) << rig.bed.lastError();
  PoseMailbox mailbox;
  DeviceSessionOptions so = fastOptions();
  so.rateHz = 200;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  ASSERT_TRUE(eventually([&] {
    const auto s = session.state();
    return s == ConnectionState::Lost || s == ConnectionState::Reconnecting;
  })) << toString(session.state());
  const uint64_t before = session.stats().samples;
  ASSERT_TRUE(eventually([&] { return session.stats().reconnects == 1; })) << session.lastError();
  ASSERT_TRUE(eventually([&] { return session.stats().samples > before + 20; }));
  EXPECT_EQ(rig.server->powerOns(), 2u);
  session.stop();
}

TEST(SimulatedArmatureSerial, LineProtocolRigWithBootBanner) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ArmatureOptions o;
  o.protocol = WireProtocol::Lines;
  o.info = ArmatureOptions::defaultInfo(6, 10);
  o.bootBanner = {"DIY armature v0.2", "ready"};
  o.bootDelayNs = 100 * kMs;
  o.rateHz = 100;
  ASSERT_TRUE(rig.start(o)) << rig.bed.lastError();
  PoseMailbox mailbox;
  DeviceSessionOptions so = fastOptions();
  so.protocol = WireProtocol::Lines;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 30; })) << session.lastError();
  EXPECT_EQ(session.deviceInfo()->channelCount, 6);
  EXPECT_EQ(session.stats().parseErrors, 0u);
  session.stop();
}

TEST(SimulatedArmatureSerial, Stream1kHz64ChannelsWithoutLoss) {
  IMPS_REQUIRE_UMOCKDEV();
  UmockdevRig rig;
  ArmatureOptions o;
  o.info = ArmatureOptions::defaultInfo(64, 16);
  ASSERT_TRUE(rig.start(o)) << rig.bed.lastError();
  PoseMailbox mailbox(withQueue(8192));
  DeviceSessionOptions so = fastOptions();
  so.rateHz = 1000;
  DeviceSession session(serialOpener("/dev/ttyACM0"), mailbox, so);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  // Drain as a recorder would, for about 3 s.
  std::vector<Sample> got;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (std::chrono::steady_clock::now() < end) {
    mailbox.drain(got);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  session.stop();
  mailbox.drain(got);
  ASSERT_GE(got.size(), 2000u);  // generous: 3 s at 1 kHz on a loaded machine
  for (size_t i = 1; i < got.size(); ++i) ASSERT_EQ(got[i].sequence, got[i - 1].sequence + 1) << i;
  const DeviceSessionStats s = session.stats();
  EXPECT_EQ(s.samplesDropped, 0u);
  EXPECT_EQ(s.crcErrors, 0u);
  EXPECT_EQ(s.garbageBytes, 0u);
  EXPECT_EQ(mailbox.stats().queueOverflows, 0u);
  EXPECT_EQ(rig.server->bytesDropped(), 0u);
  std::printf("[   INFO   ] %zu samples in 3 s, 0 lost\n", got.size());
}

}  // namespace
}  // namespace imps::sim
