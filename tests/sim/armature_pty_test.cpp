// SPDX-License-Identifier: MIT
// The simulated armature on a plain pseudo-terminal (the path `puppeteer sim --pty` serves) under the real drivers
// (SerialTransport's termios path, DeviceSession, PoseMailbox): a 1 kHz × 64-channel stream arrives whole, in order
// and byte-exact. Behaviour, not speed: the assertions count and compare samples and never time anything, so a
// loaded machine makes the test slower, not red. The timing figures are bench/soak_bench.cpp's.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include "drivers/device_session.h"
#include "drivers/serial_transport.h"
#include "imps/clock.h"
#include "sim/pseudo_terminal.h"
#include "sim/simulated_armature.h"

namespace imps::sim {
namespace {

using namespace imps::drivers;

// The steady clock, until freeze(): from then on time stands still for the armature, so no further sample falls
// due while its server keeps writing what was already produced. That ends the stream at an exact sample.
class FreezableClock final : public Clock {
 public:
  int64_t nowNs() override { return std::min(steadyNowNs(), frozenAt_.load(std::memory_order_acquire)); }
  void sleepUntilNs(int64_t timeNs) override {  // in real time, so a frozen clock cannot block the server
    const int64_t left = timeNs - nowNs();
    if (left > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(left));
  }
  void freeze() { frozenAt_.store(steadyNowNs(), std::memory_order_release); }

 private:
  std::atomic<int64_t> frozenAt_{INT64_MAX};
};

TEST(ArmaturePty, Stream1kHz64ChannelsEverySampleInOrderByteExact) {
  auto pty = PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();

  // 4096 distinct poses using every bit of 16-bit counts, with some channels flagged.
  ArmatureOptions o;
  o.info = ArmatureOptions::defaultInfo(64, 16);
  o.channelFlags = true;
  uint64_t x = 12345;
  for (int q = 0; q < 4096; ++q) {
    Sample& s = o.recorded.emplace_back();
    s.channelCount = 64;
    for (int c = 0; c < 64; ++c) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      s.counts[c] = static_cast<uint32_t>(x >> 48);
      s.flags[c] = (q + c) % 29 == 0 ? ChannelFlag::Outlier : (q + c) % 31 == 0 ? ChannelFlag::NotConnected
                                                                                 : ChannelFlag::Valid;
    }
  }
  const std::vector<Sample> poses = o.recorded;
  FreezableClock clock;
  ArmatureFdServer server(SimulatedArmature(std::move(o)), pty->master(), clock);
  server.start();

  PoseMailboxOptions mo;
  mo.queueCapacity = 1 << 15;  // 32 s at 1 kHz: no overflow even if this thread is starved for seconds
  PoseMailbox mailbox(mo);
  DeviceSessionOptions so;
  so.rateHz = 1000;
  so.bootWaitMs = 300;         // the boot HELLO went out before the port was opened: ask with HOST_HELLO soon
  so.replyTimeoutMs = 2000;    // generous: only speed would change, never the result
  so.sampleTimeoutMs = 10000;  // a stall on a loaded machine must not look like a silent device
  DeviceSession session(serialOpener(pty->slavePath()), mailbox, so);
  session.start();
  ASSERT_TRUE(session.waitForState(ConnectionState::Streaming, 20000)) << session.lastError();

  // About 2 s of stream, drained as a recorder would; then stop the armature's time and collect everything sent.
  std::vector<Sample> got;
  const auto streamEnd = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < streamEnd) {
    mailbox.drain(got);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  clock.freeze();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the server produces the last samples due
  const auto giveUp = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < giveUp && (got.size() < server.samplesSent() || got.empty())) {
    mailbox.drain(got);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  session.stop();
  server.stop();
  mailbox.drain(got);

  // Every sample the armature sent, exactly once, in order from power-on, with its counts and flags intact.
  const uint64_t sent = server.samplesSent();
  EXPECT_GE(sent, 1000u);  // 2 s at 1 kHz; the armature catches up on every sample due, however loaded
  ASSERT_EQ(got.size(), sent);
  for (size_t i = 0; i < got.size(); ++i) {
    const Sample& s = got[i];
    ASSERT_EQ(s.sequence, i);
    ASSERT_EQ(s.channelCount, 64) << "sample " << i;
    const Sample& want = poses[i % poses.size()];
    for (int c = 0; c < 64; ++c) {
      ASSERT_EQ(s.counts[c], want.counts[c]) << "sample " << i << " channel " << c;
      ASSERT_EQ(s.flags[c], want.flags[c]) << "sample " << i << " channel " << c;
    }
    if (i > 0) {
      ASSERT_GT(s.deviceTimeNs, got[i - 1].deviceTimeNs) << "sample " << i;
      ASSERT_GE(s.arrivalTimeNs, got[i - 1].arrivalTimeNs) << "sample " << i;
    }
  }
  const DeviceSessionStats st = session.stats();
  EXPECT_EQ(st.samples, sent);
  EXPECT_EQ(st.samplesDropped, 0u);
  EXPECT_EQ(st.crcErrors, 0u);
  EXPECT_EQ(st.garbageBytes, 0u);
  EXPECT_EQ(st.malformedFrames, 0u);
  EXPECT_EQ(st.reconnects, 0u);
  EXPECT_EQ(mailbox.stats().queueOverflows, 0u);
  EXPECT_EQ(server.bytesDropped(), 0u);
}

}  // namespace
}  // namespace imps::sim
