// SPDX-License-Identifier: MIT
// A device written by hand from docs/protocol.md alone (as a third party would), on the master side of a
// pseudo-terminal, under the real drivers (SerialTransport's termios path, DeviceSession, PoseMailbox): the faults
// of issue 14 that the simulator does not make — a numeric boot banner, silence longer than the session timeout, a
// reconnect without a reboot, unanswered polls, a forged header in poll mode, a repeated frame. Every assertion
// counts samples; time only bounds the waits (eventually()).
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "drivers/binary_protocol.h"
#include "drivers/device_session.h"
#include "drivers/serial_transport.h"
#include "eventually.h"
#include "sim/pseudo_terminal.h"

namespace imps::sim {
namespace {

using namespace imps::drivers;

DeviceInfo handInfo() {
  DeviceInfo info;
  info.name = "Hand-made armature";
  info.serialNumber = "H1";
  info.firmwareVersion = "0.1";
  info.channelCount = 3;
  info.bitsPerChannel = 12;
  return info;
}

// The device: answers HOST_HELLO, GET_INFO, START/STOP_STREAM from its own thread; POLL through `onPoll`; the test
// sends samples and raw bytes whenever it likes. Writes are serialised.
class HandDevice {
 public:
  explicit HandDevice(int master) : master_(master) { thread_ = std::thread([this] { serve(); }); }
  ~HandDevice() {
    stop_.store(true);
    thread_.join();
  }

  void send(const std::vector<uint8_t>& bytes) {
    std::lock_guard lock(mutex_);
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
      if (n > 0) done += static_cast<size_t>(n);
      else std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  void sendText(const std::string& text) { send(std::vector<uint8_t>(text.begin(), text.end())); }
  static std::vector<uint8_t> frame(const Message& m) {
    std::vector<uint8_t> out;
    EXPECT_TRUE(appendFrame(m, out).has_value());
    return out;
  }
  static Sample sample(uint32_t sequence) {
    Sample s;
    s.sequence = sequence;
    s.channelCount = 3;
    for (int c = 0; c < 3; ++c) s.counts[c] = (sequence * 7 + static_cast<uint32_t>(c)) & 0xFFF;
    return s;
  }
  static std::vector<uint8_t> sampleFrame(uint32_t sequence, bool reply = false) {
    return frame(sampleMessage(sample(sequence), 12, false, false, reply ? kFlagReply : 0));
  }
  void sendSamples(uint32_t first, uint32_t end) {
    std::vector<uint8_t> bytes;
    for (uint32_t q = first; q < end; ++q) {
      const auto f = sampleFrame(q);
      bytes.insert(bytes.end(), f.begin(), f.end());
    }
    send(bytes);
  }

  // Called for each POLL with its command sequence; returns the bytes to answer with (may be none).
  std::function<std::vector<uint8_t>(uint32_t)> onPoll;
  std::atomic<int> startStreams{0};

 private:
  void serve() {
    BinaryDecoder commands;
    uint8_t buf[512];
    while (!stop_.load()) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 5) <= 0) continue;
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n <= 0) continue;
      commands.feed(std::span<const uint8_t>(buf, static_cast<size_t>(n)));
      while (auto m = commands.next()) answer(*m);
    }
  }
  void answer(const Message& m) {
    switch (m.type()) {
      case MessageType::HostHello:
        send(frame({m.sequence, kFlagReply, msg::Hello{kProtocolVersion, handInfo()}}));
        break;
      case MessageType::GetInfo:
        send(frame({m.sequence, kFlagReply, msg::Info{handInfo()}}));
        break;
      case MessageType::StartStream:
        ++startStreams;
        send(frame({m.sequence, kFlagReply, msg::Ack{MessageType::StartStream}}));
        break;
      case MessageType::StopStream:
        send(frame({m.sequence, kFlagReply, msg::Ack{MessageType::StopStream}}));
        break;
      case MessageType::Poll:
        if (onPoll) {
          const auto bytes = onPoll(m.sequence);
          if (!bytes.empty()) send(bytes);
        }
        break;
      default:
        break;
    }
  }

  int master_;
  std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Quick timeouts so the faults happen within a test; nothing is asserted about time.
DeviceSessionOptions quickOptions() {
  DeviceSessionOptions o;
  o.bootWaitMs = 50;  // the device never says HELLO unasked: ask with HOST_HELLO soon
  o.replyTimeoutMs = 300;
  o.sampleTimeoutMs = 300;
  o.timeoutsBeforeLost = 1000;  // silence is timeouts, not a loss, unless a test says otherwise
  o.reconnectIntervalMs = 50;
  return o;
}

std::set<uint32_t> sequencesOf(const std::vector<Sample>& samples) {
  std::set<uint32_t> out;
  for (const Sample& s : samples) out.insert(s.sequence);
  return out;
}

struct Rig {
  PseudoTerminal pty;
  PoseMailbox mailbox{[] {
    PoseMailboxOptions o;
    o.queueCapacity = 1 << 12;
    return o;
  }()};
  std::vector<Sample> got;
  explicit Rig(PseudoTerminal terminal) : pty(std::move(terminal)) {}
  void drain() { mailbox.drain(got); }
};

// Issue 14 item 2: a 500-sample hole behind a silence longer than the session timeout is 500 dropped samples.
TEST(HandDevicePty, SamplesLostAcrossATimeoutAreCounted) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  Rig rig(std::move(*pty));
  HandDevice device(rig.pty.master());
  DeviceSession session(serialOpener(rig.pty.slavePath()), rig.mailbox, quickOptions());
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 10000)) << session.lastError();
  device.sendSamples(0, 100);
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 100; }));
  ASSERT_TRUE(eventually([&] { return session.stats().timeouts >= 1; }));  // the link went quiet
  device.sendSamples(600, 700);
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 200; }));
  session.stop();
  EXPECT_EQ(session.stats().samplesDropped, 500u);
  EXPECT_EQ(session.stats().deviceResets, 0u);
}

// Issue 14 item 2: the link is lost and reopened; the device did not reboot (it answers HOST_HELLO, it never says
// HELLO unasked), so the numbers it sent meanwhile are dropped samples, not a fresh start.
TEST(HandDevicePty, SamplesLostAcrossAReconnectAreCounted) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  Rig rig(std::move(*pty));
  HandDevice device(rig.pty.master());
  DeviceSessionOptions o = quickOptions();
  o.timeoutsBeforeLost = 1;
  DeviceSession session(serialOpener(rig.pty.slavePath()), rig.mailbox, o);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 10000)) << session.lastError();
  device.sendSamples(0, 50);
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 50; }));
  ASSERT_TRUE(eventually([&] { return session.stats().reconnects >= 1; })) << session.lastError();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 10000)) << session.lastError();
  device.sendSamples(250, 300);
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 100; }));
  session.stop();
  EXPECT_EQ(session.stats().samplesDropped, 200u);
  EXPECT_EQ(session.stats().deviceResets, 0u);
}

// Issue 14 items 2 and 3, poll mode: poll 5's answer hides behind a valid header claiming 2,000 bytes (nothing
// more comes, the poll times out: the intact sample behind it must still be found), and two polls go unanswered
// while the device's numbering moves on (two dropped samples).
TEST(HandDevicePty, PollModeFindsTheSampleBehindAForgedHeaderAndCountsUnansweredPolls) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  Rig rig(std::move(*pty));
  HandDevice device(rig.pty.master());
  std::atomic<uint32_t> polls{0};
  device.onPoll = [&](uint32_t) -> std::vector<uint8_t> {
    const uint32_t q = polls++;
    if (q == 10 || q == 11) return {};  // lost on the wire; the sequence number is used
    std::vector<uint8_t> bytes;
    if (q == 5) {
      // A valid header (both CRCs of its own right) for a 2000-byte SAMPLE that never follows.
      std::vector<uint8_t> header = {kSync0, kSync1, kProtocolVersion, 0x03, kFlagReply, 9, 9, 9, 9, 0xD0, 0x07};
      const uint16_t crc = crc16CcittFalse(std::span<const uint8_t>(header).subspan(2));
      header.push_back(static_cast<uint8_t>(crc));
      header.push_back(static_cast<uint8_t>(crc >> 8));
      bytes = header;
    }
    const auto f = HandDevice::sampleFrame(q, true);
    bytes.insert(bytes.end(), f.begin(), f.end());
    return bytes;
  };
  DeviceSessionOptions o = quickOptions();
  o.mode = AcquisitionMode::Poll;
  DeviceSession session(serialOpener(rig.pty.slavePath()), rig.mailbox, o);
  session.start();
  ASSERT_TRUE(eventually([&] {
    rig.drain();
    return sequencesOf(rig.got).contains(30);
  })) << session.lastError();
  session.stop();
  const std::set<uint32_t> seen = sequencesOf(rig.got);
  for (uint32_t q = 0; q <= 30; ++q) EXPECT_EQ(seen.contains(q), q != 10 && q != 11) << "sequence " << q;
  const DeviceSessionStats st = session.stats();
  EXPECT_EQ(st.samplesDropped, 2u);
  EXPECT_EQ(st.truncatedFrames, 1u);
  // Poll 5's first try timed out, and so did a poll while the device kept quiet (answers run one poll behind
  // after the forged header, so the two unanswered polls cost one timeout).
  EXPECT_GE(st.timeouts, 2u);
}

// Issue 14 item 4: a frame sent twice is one sample, and the repeat is counted.
TEST(HandDevicePty, RepeatedFrameIsPublishedOnceAndCounted) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  Rig rig(std::move(*pty));
  HandDevice device(rig.pty.master());
  DeviceSession session(serialOpener(rig.pty.slavePath()), rig.mailbox, quickOptions());
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 10000)) << session.lastError();
  device.sendSamples(0, 5);
  device.send(HandDevice::sampleFrame(4));
  device.sendSamples(5, 10);
  ASSERT_TRUE(eventually([&] {
    rig.drain();
    return sequencesOf(rig.got).contains(9);
  }));
  session.stop();
  rig.drain();
  ASSERT_EQ(rig.got.size(), 10u);
  for (size_t i = 0; i < rig.got.size(); ++i) EXPECT_EQ(rig.got[i].sequence, i);
  EXPECT_EQ(session.stats().duplicateSamples, 1u);
  EXPECT_EQ(session.stats().samplesDropped, 0u);
}

// Issue 14 item 1: a DIY line-protocol device printing the docs' example banner (its baud rate) before its data:
// every data line is an 8-channel sample, none is skipped, and the device description says 8 channels.
TEST(HandDevicePty, NumericBootBannerIsNotTakenForTheLayout) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  Rig rig(std::move(*pty));
  HandDevice device(rig.pty.master());
  DeviceSessionOptions o = quickOptions();
  o.protocol = WireProtocol::Lines;
  DeviceSession session(serialOpener(rig.pty.slavePath()), rig.mailbox, o);
  session.start();
  ASSERT_TRUE(eventually([&] { return session.state() == ConnectionState::WaitingForHello; }));
  std::string text = "115200\r\n";
  for (int i = 0; i < 40; ++i) text += std::to_string(i) + ",1,2,3,4,5,6,7\r\n";
  device.sendText(text);
  ASSERT_TRUE(eventually([&] { return session.stats().samples >= 40; })) << session.lastError();
  session.stop();
  rig.drain();
  ASSERT_EQ(rig.got.size(), 40u);
  for (size_t i = 0; i < rig.got.size(); ++i) {
    EXPECT_EQ(rig.got[i].channelCount, 8);
    EXPECT_EQ(rig.got[i].counts[0], i);
  }
  ASSERT_TRUE(session.deviceInfo());
  EXPECT_EQ(session.deviceInfo()->channelCount, 8);
  EXPECT_EQ(session.banner(), std::vector<std::string>{"115200"});
  EXPECT_EQ(session.stats().parseErrors, 0u);
}

}  // namespace
}  // namespace imps::sim
