// SPDX-License-Identifier: MIT
// Tests for drivers/device_session against a scripted in-memory device (a fake ByteTransport answering with the
// drivers' own encoders): handshake, info, stream and poll modes, resync counters, timeouts, loss and reconnect,
// the line protocol's banner. The same session over real libserialport + the simulator: tests/sim/.
#include "drivers/device_session.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "drivers/binary_protocol.h"
#include "eventually.h"

namespace imps::drivers {
namespace {

// What the scripted device does. Shared by every connection the opener makes.
struct Script {
  bool helloAtOpen = true;
  bool answerHostHello = true;
  int samplesOnStart = 20;          // sent at once after the START_STREAM ACK (and per POLL: one each)
  bool garbageBetweenSamples = false;
  bool corruptThirdSample = false;
  int failReadsAfterSamples = -1;   // the first connection's read fails after this many samples (unplug)
  int openFailures = 0;             // the first N opens fail
  std::string lineText;             // non-empty: a line-protocol device printing this at open

  // Filled in by the device.
  std::mutex mutex;
  int opens = 0;
  std::vector<MessageType> commands;
};

DeviceInfo testInfo() {
  DeviceInfo info;
  info.name = "Scripted";
  info.serialNumber = "S1";
  info.firmwareVersion = "1.0";
  info.channelCount = 4;
  info.bitsPerChannel = 12;
  info.channelNames = {"a", "b", "c", "d"};
  return info;
}

class ScriptedTransport final : public ByteTransport {
 public:
  ScriptedTransport(Script& script, int connection) : script_(script), connection_(connection) {
    if (!script_.lineText.empty()) {
      push(script_.lineText);
    } else if (script_.helloAtOpen) {
      (void)appendFrame(Message{0, 0, msg::Hello{kProtocolVersion, testInfo()}}, out_);
    }
  }

  IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) override {
    if (failed_) return std::unexpected(IoError{"scripted", "unplugged"});
    if (out_.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min(timeoutMs, 5)));
      return 0;
    }
    const size_t n = std::min(out.size(), out_.size());
    std::copy_n(out_.begin(), n, out.begin());
    out_.erase(out_.begin(), out_.begin() + static_cast<std::ptrdiff_t>(n));
    if (out_.empty() && pendingFailure_) failed_ = true;
    return n;
  }

  IoResult<void> write(std::span<const uint8_t> bytes, int) override {
    if (failed_) return std::unexpected(IoError{"scripted", "unplugged"});
    decoder_.feed(bytes);
    while (auto m = decoder_.next()) {
      {
        std::lock_guard lock(script_.mutex);
        script_.commands.push_back(m->type());
      }
      const uint32_t seq = m->sequence;
      switch (m->type()) {
        case MessageType::HostHello:
          if (script_.answerHostHello)
            (void)appendFrame(Message{seq, kFlagReply, msg::Hello{kProtocolVersion, testInfo()}}, out_);
          break;
        case MessageType::GetInfo:
          (void)appendFrame(Message{seq, kFlagReply, msg::Info{testInfo()}}, out_);
          break;
        case MessageType::StartStream:
          (void)appendFrame(Message{seq, kFlagReply, msg::Ack{MessageType::StartStream}}, out_);
          for (int i = 0; i < script_.samplesOnStart; ++i) sample(false);
          if (connection_ == 0 && script_.failReadsAfterSamples >= 0) pendingFailure_ = true;
          break;
        case MessageType::Poll:
          sample(true);
          break;
        default:
          break;
      }
    }
    return {};
  }

  std::string description() const override { return "scripted"; }

 private:
  void push(const std::string& s) { out_.insert(out_.end(), s.begin(), s.end()); }
  void sample(bool reply) {
    Sample s;
    s.sequence = sequence_++;
    s.channelCount = 4;
    for (int c = 0; c < 4; ++c) s.counts[c] = s.sequence * 4 + static_cast<uint32_t>(c);
    if (script_.garbageBetweenSamples) push("garbage!\xA5\x5A\x01");
    const size_t begin = out_.size();
    (void)appendFrame(sampleMessage(s, 12, false, false, reply ? kFlagReply : 0), out_);
    if (script_.corruptThirdSample && s.sequence == 2) out_[begin + 15] ^= 0x10;
  }

  Script& script_;
  int connection_;
  BinaryDecoder decoder_;
  std::vector<uint8_t> out_;
  uint32_t sequence_ = 0;
  bool pendingFailure_ = false;
  bool failed_ = false;
};

TransportOpener scriptedOpener(Script& script) {
  return [&script]() -> IoResult<std::unique_ptr<ByteTransport>> {
    std::lock_guard lock(script.mutex);
    const int n = script.opens++;
    if (n < script.openFailures) return std::unexpected(IoError{"scripted", "no such device"});
    return std::unique_ptr<ByteTransport>(new ScriptedTransport(script, n - script.openFailures));
  };
}

PoseMailboxOptions withQueue(size_t capacity) {
  PoseMailboxOptions o;
  o.queueCapacity = capacity;
  return o;
}

DeviceSessionOptions fastOptions() {
  DeviceSessionOptions o;
  o.bootWaitMs = 100;
  o.replyTimeoutMs = 100;
  o.sampleTimeoutMs = 100;
  o.reconnectIntervalMs = 20;
  o.ioWaitMs = 5;
  return o;
}

TEST(DeviceSession, HandshakeInfoAndStream) {
  Script script;
  PoseMailbox mailbox(withQueue(64));
  DeviceSession session(scriptedOpener(script), mailbox, fastOptions());
  EXPECT_EQ(session.state(), ConnectionState::Disconnected);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  ASSERT_TRUE(eventually([&] { return session.stats().samples == 20; }));
  ASSERT_TRUE(session.deviceInfo());
  EXPECT_EQ(*session.deviceInfo(), testInfo());
  std::vector<Sample> got;
  mailbox.drain(got);
  ASSERT_EQ(got.size(), 20u);
  for (uint32_t i = 0; i < 20; ++i) {
    EXPECT_EQ(got[i].sequence, i);
    EXPECT_EQ(got[i].counts[3], i * 4 + 3);
    EXPECT_GT(got[i].arrivalTimeNs, 0);
  }
  session.stop();
  EXPECT_EQ(session.state(), ConnectionState::Disconnected);
  std::lock_guard lock(script.mutex);
  // The boot HELLO made HOST_HELLO unnecessary; then GET_INFO, START_STREAM, and STOP_STREAM at stop().
  EXPECT_EQ(script.commands,
            (std::vector<MessageType>{MessageType::GetInfo, MessageType::StartStream, MessageType::StopStream}));
  EXPECT_EQ(session.stats().timeouts, 0u);
}

TEST(DeviceSession, AsksWithHostHelloWhenNoBootHello) {
  Script script;
  script.helloAtOpen = false;
  PoseMailbox mailbox;
  DeviceSession session(scriptedOpener(script), mailbox, fastOptions());
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  session.stop();
  std::lock_guard lock(script.mutex);
  ASSERT_FALSE(script.commands.empty());
  EXPECT_EQ(script.commands.front(), MessageType::HostHello);
}

TEST(DeviceSession, PollMode) {
  Script script;
  PoseMailbox mailbox(withQueue(1024));
  DeviceSessionOptions o = fastOptions();
  o.mode = AcquisitionMode::Poll;
  DeviceSession session(scriptedOpener(script), mailbox, o);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 50; })) << session.lastError();
  session.stop();
  std::vector<Sample> got;
  mailbox.drain(got);
  for (size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].sequence, i);
  std::lock_guard lock(script.mutex);
  EXPECT_EQ(std::count(script.commands.begin(), script.commands.end(), MessageType::StartStream), 0);
  EXPECT_GE(std::count(script.commands.begin(), script.commands.end(), MessageType::Poll), 50);
}

TEST(DeviceSession, GarbageAndCorruptFramesAreCountedAndSkipped) {
  Script script;
  script.garbageBetweenSamples = true;
  script.corruptThirdSample = true;
  PoseMailbox mailbox(withQueue(64));
  DeviceSession session(scriptedOpener(script), mailbox, fastOptions());
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples == 19; })) << session.lastError();
  const DeviceSessionStats s = session.stats();
  EXPECT_GE(s.crcErrors, 1u);
  EXPECT_GE(s.garbageBytes, 19u * 11u);  // every burst of 11 garbage bytes is skipped, plus the corrupt frame
  EXPECT_EQ(s.samplesDropped, 1u);       // the corrupt sample leaves a sequence gap
  std::vector<Sample> got;
  mailbox.drain(got);
  ASSERT_EQ(got.size(), 19u);
  EXPECT_EQ(got[2].sequence, 3u);
  session.stop();
}

TEST(DeviceSession, SilenceIsTimeoutsThenLostThenReconnect) {
  Script script;
  script.samplesOnStart = 0;  // acknowledges START_STREAM, then says nothing
  PoseMailbox mailbox;
  DeviceSessionOptions o = fastOptions();
  o.timeoutsBeforeLost = 2;
  DeviceSession session(scriptedOpener(script), mailbox, o);
  session.start();
  ASSERT_TRUE(eventually([&] { 
    std::lock_guard lock(script.mutex);
    return session.stats().timeouts >= 2 && script.opens >= 2;
  }));
  EXPECT_NE(session.lastError().find("no samples"), std::string::npos) << session.lastError();
  session.stop();
}

TEST(DeviceSession, UnplugKeepsLastPoseAndReconnects) {
  Script script;
  script.failReadsAfterSamples = 20;  // the first connection dies after its 20 samples
  script.openFailures = 0;
  PoseMailbox mailbox(withQueue(128));
  DeviceSession session(scriptedOpener(script), mailbox, fastOptions());
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().reconnects == 1 && session.stats().samples == 40; }))
      << session.lastError() << " state " << toString(session.state());
  EXPECT_EQ(session.stats().connections, 2u);
  EXPECT_NE(session.lastError().find("scripted: error: unplugged"), std::string::npos) << session.lastError();
  Sample newest;
  ASSERT_TRUE(mailbox.latest(newest));
  EXPECT_EQ(newest.sequence, 19u);  // the second connection's last sample (sequence restarts on reconnect)
  session.stop();
}

TEST(DeviceSession, ReportsLostWhileTheDeviceIsAway) {
  // Opening fails after the first connection dies: the state must say lost, and counters keep counting.
  Script script;
  script.failReadsAfterSamples = 20;
  PoseMailbox mailbox;
  int opens = 0;
  TransportOpener inner = scriptedOpener(script);
  TransportOpener opener = [&]() -> IoResult<std::unique_ptr<ByteTransport>> {
    if (opens++ >= 1) return std::unexpected(IoError{"", "gone"});
    return inner();
  };
  DeviceSession session(opener, mailbox, fastOptions());
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().openFailures >= 2; }));
  EXPECT_TRUE(eventually([&] { return session.state() == ConnectionState::Lost; }));
  EXPECT_EQ(session.stats().samples, 20u);
  Sample last;
  EXPECT_TRUE(mailbox.latest(last));  // the last pose is still there for the frame loop
  EXPECT_EQ(last.sequence, 19u);
  session.stop();
  EXPECT_EQ(session.state(), ConnectionState::Disconnected);
}

TEST(DeviceSession, FirstOpenFailuresAreRetried) {
  Script script;
  script.openFailures = 3;
  PoseMailbox mailbox;
  DeviceSession session(scriptedOpener(script), mailbox, fastOptions());
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 5000)) << session.lastError();
  EXPECT_EQ(session.stats().openFailures, 3u);
  EXPECT_EQ(session.stats().reconnects, 0u);
  session.stop();
}

TEST(DeviceSession, LineProtocolWithBanner) {
  Script script;
  script.lineText = "DIY armature v0.2\r\nready\r\n1,2,3\r\nt=15000, 4, 5, 6\r\nbad line\r\n7 8 9\r\n";
  PoseMailbox mailbox(withQueue(16));
  DeviceSessionOptions o = fastOptions();
  o.protocol = WireProtocol::Lines;
  DeviceSession session(scriptedOpener(script), mailbox, o);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.stats().samples == 3; }));
  EXPECT_EQ(session.state(), ConnectionState::Streaming);
  EXPECT_EQ(session.banner(), (std::vector<std::string>{"DIY armature v0.2", "ready"}));
  EXPECT_EQ(session.stats().parseErrors, 1u);
  ASSERT_TRUE(session.deviceInfo());
  EXPECT_EQ(session.deviceInfo()->channelCount, 3);
  EXPECT_EQ(session.deviceInfo()->name, "DIY armature v0.2");
  std::vector<Sample> got;
  mailbox.drain(got);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[1].deviceTimeNs, 15'000'000);
  EXPECT_EQ(got[2].counts[2], 9u);
  session.stop();
}

}  // namespace
}  // namespace imps::drivers
