// SPDX-License-Identifier: MIT
// Tests for drivers/osc_receiver over loopback UDP, fed by the sender and by hand: every frame arrives in order; gaps,
// reordering, duplicates, lateness and malformed datagrams are counted and survived; silence loses the source and
// the next frame brings it back; a DIY sender's raw channels reach the pose mailbox.
#include "drivers/osc_receiver.h"
#include "drivers/osc_sender.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <lo/lo.h>

#include <atomic>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "eventually.h"
#include "osc_bytes.h"

namespace imps::drivers {
namespace {

// A plain UDP socket sending hand-made datagrams to the receiver (bytes no OSC library would produce).
class RawSender {
 public:
  explicit RawSender(uint16_t port) : fd_(socket(AF_INET, SOCK_DGRAM, 0)) {
    to_.sin_family = AF_INET;
    to_.sin_port = htons(port);
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  }
  ~RawSender() { ::close(fd_); }
  void send(const std::vector<uint8_t>& bytes) {
    ASSERT_EQ(sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to_), sizeof to_),
              ssize_t(bytes.size()));
  }

 private:
  int fd_;
  sockaddr_in to_{};
};

OscPose poseWithFrame(uint32_t frame, int64_t sentNs = 0) {
  OscPose p;
  p.frame = frame;
  p.sentTimeNs = sentNs;
  std::strcpy(p.joints[0].name.data(), "Head");
  p.joints[0].w = 1.0f;
  p.jointCount = 1;
  return p;
}

// Collects every accepted pose's frame counter (the onPose hook runs on the I/O thread).
struct Collected {
  std::mutex mutex;
  std::vector<uint32_t> frames;
  size_t size() {
    std::lock_guard lock(mutex);
    return frames.size();
  }
};

std::unique_ptr<OscReceiver> openReceiver(PoseMailbox& mailbox, Collected* collected = nullptr,
                                          OscReceiverOptions options = {}) {
  options.host = "127.0.0.1";
  if (collected) {
    options.onPose = [collected](const OscPose& p) {
      std::lock_guard lock(collected->mutex);
      collected->frames.push_back(p.frame);
    };
  }
  auto r = OscReceiver::open(std::move(options), mailbox);
  EXPECT_TRUE(r) << r.error().str();
  if (!r) return nullptr;
  (*r)->start();
  return std::move(*r);
}

std::string target(const OscReceiver& r) { return "osc.udp://127.0.0.1:" + std::to_string(r.port()); }

TEST(OscStream, EveryFrameReachesTwoReceiversInOrder) {
  PoseMailbox m1, m2;
  Collected c1, c2;
  auto r1 = openReceiver(m1, &c1), r2 = openReceiver(m2, &c2);
  ASSERT_TRUE(r1 && r2);
  constexpr uint32_t kFrames = 300;
  {
    auto sender = OscPoseSender::open({target(*r1), target(*r2)}, 512);  // room for every frame: none dropped
    ASSERT_TRUE(sender) << sender.error().str();
    OscPose p = poseWithFrame(0);
    for (uint32_t i = 0; i < kFrames; ++i) {
      p.sampleTimeNs = 1000 + i;
      p.joints[0].x = float(i);
      EXPECT_TRUE((*sender)->send(p));
    }
    ASSERT_TRUE((*sender)->flush(10'000));
    EXPECT_EQ((*sender)->stats().sent, 2 * kFrames);  // flush() returned only once every frame had gone
    EXPECT_EQ((*sender)->stats().dropped, 0u);
    EXPECT_EQ((*sender)->stats().sendErrors, 0u);
  }
  for (auto* c : {&c1, &c2}) {
    ASSERT_TRUE(eventually([&] { return c->size() == kFrames; })) << c->size();
    std::lock_guard lock(c->mutex);
    for (uint32_t i = 0; i < kFrames; ++i) ASSERT_EQ(c->frames[i], i);
  }
  for (auto* r : {r1.get(), r2.get()}) {
    const OscReceiverStats s = r->stats();
    EXPECT_EQ(s.poses, kFrames);
    EXPECT_EQ(s.dropped + s.outOfOrder + s.malformed, 0u);
    EXPECT_EQ(s.state, ConnectionState::Streaming);
    EXPECT_GE(s.lastTransitNs, 0);  // one host: the send time is on this clock
    OscPose newest;
    ASSERT_TRUE(r->takePose(newest));
    EXPECT_EQ(newest.frame, kFrames - 1);
    EXPECT_EQ(newest.sampleTimeNs, 1000 + kFrames - 1);
    EXPECT_EQ(newest.joints[0].x, float(kFrames - 1));
    EXPECT_FALSE(r->takePose(newest));  // nothing newer
  }
}

TEST(OscStream, GapsReorderingAndDuplicatesAreCountedAndOnlyNewerFramesApplied) {
  PoseMailbox mailbox;
  Collected c;
  auto r = openReceiver(mailbox, &c);
  ASSERT_TRUE(r);
  RawSender raw(r->port());
  for (uint32_t f : {0u, 1u, 3u, 2u, 4u, 4u, 7u}) raw.send(encodeOscPose(poseWithFrame(f)));
  ASSERT_TRUE(eventually([&] { return r->stats().packets == 7; }));
  const OscReceiverStats s = r->stats();
  EXPECT_EQ(s.poses, 5u);       // 0 1 3 4 7
  EXPECT_EQ(s.outOfOrder, 2u);  // 2 after 3, the second 4
  EXPECT_EQ(s.dropped, 3u);     // 2 (missing when 3 came), 5 and 6
  std::lock_guard lock(c.mutex);
  EXPECT_EQ(c.frames, (std::vector<uint32_t>{0, 1, 3, 4, 7}));
}

TEST(OscStream, ASenderRestartIsANewStreamNotAHugeGap) {
  PoseMailbox mailbox;
  auto r = openReceiver(mailbox);
  ASSERT_TRUE(r);
  RawSender raw(r->port());
  for (uint32_t f : {5'000'000u, 5'000'001u, 0u, 1u}) raw.send(encodeOscPose(poseWithFrame(f)));
  ASSERT_TRUE(eventually([&] { return r->stats().packets == 4; }));
  const OscReceiverStats s = r->stats();
  EXPECT_EQ(s.poses, 4u);
  EXPECT_EQ(s.senderRestarts, 1u);
  EXPECT_EQ(s.dropped + s.outOfOrder, 0u);
}

TEST(OscStream, MalformedDatagramsAreCountedAndTheStreamGoesOn) {
  PoseMailbox mailbox;
  Collected c;
  auto r = openReceiver(mailbox, &c);
  ASSERT_TRUE(r);
  RawSender raw(r->port());
  const std::vector<std::vector<uint8_t>> garbage = {
      {1, 2, 3},                                           // not a multiple of 4
      {'#', 'b', 'u', 'n', 'd', 'l', 'e', 0, 0, 0, 0, 0},  // a bundle without its time tag
      std::vector<uint8_t>(4096, 0x2F),                    // an address without its NUL
      OscBytes().str("/imps/joint/Head").str(",ffff").f32(1).f32(0).f32(0).f32(0).bytes,  // no frame
  };
  uint32_t frame = 0;
  for (const auto& g : garbage) {
    raw.send(encodeOscPose(poseWithFrame(frame++)));
    raw.send(g);
  }
  raw.send(encodeOscPose(poseWithFrame(frame++)));
  ASSERT_TRUE(eventually([&] { return r->stats().packets == 2 * garbage.size() + 1; }));
  const OscReceiverStats s = r->stats();
  EXPECT_EQ(s.malformed, garbage.size());
  EXPECT_EQ(s.poses, frame);
  EXPECT_EQ(s.dropped + s.outOfOrder, 0u);
  EXPECT_EQ(s.state, ConnectionState::Streaming);
  EXPECT_EQ(r->lastError(), "osc:byte 0: error: joints or root without /imps/frame");
  // Another program's traffic on the port is neither a frame nor a fault.
  lo_address a = lo_address_new("127.0.0.1", std::to_string(r->port()).c_str());
  ASSERT_GT(lo_send(a, "/1/fader1", "f", 0.5f), 0);
  lo_address_free(a);
  ASSERT_TRUE(eventually([&] { return r->stats().ignored == 1; }));
  EXPECT_EQ(r->stats().malformed, garbage.size());
}

TEST(OscStream, LateFramesAreCountedFromTransitDifferences) {
  PoseMailbox mailbox;
  struct AtomicClock final : Clock {  // set by the test, read on the receiver's thread
    std::atomic<int64_t> now{0};
    int64_t nowNs() override { return now.load(); }
    void sleepUntilNs(int64_t) override {}
  } clock;
  auto& now = clock.now;
  OscReceiverOptions o;
  o.lateNs = 20'000'000;
  o.clock = &clock;
  auto r = openReceiver(mailbox, nullptr, o);
  ASSERT_TRUE(r);
  RawSender raw(r->port());
  // The sender's clock is 5 s ahead of ours: only the transit's growth matters.
  const int64_t offset = 5'000'000'000;
  const int64_t transits[] = {2'000'000, 1'000'000, 20'000'000, 22'000'000, 1'500'000};  // the 4th is late
  for (uint32_t i = 0; i < 5; ++i) {
    const int64_t sent = offset + int64_t(i) * 10'000'000;
    now = sent - offset + transits[i];
    raw.send(encodeOscPose(poseWithFrame(i, sent)));
    ASSERT_TRUE(eventually([&] { return r->stats().packets == i + 1; }));
  }
  const OscReceiverStats s = r->stats();
  EXPECT_EQ(s.poses, 5u);
  EXPECT_EQ(s.late, 1u);
  EXPECT_EQ(s.lastTransitNs, transits[4] - offset);
}

TEST(OscStream, SilenceLosesTheSourceKeepingThePoseAndTheNextFrameReconnects) {
  PoseMailbox mailbox;
  OscReceiverOptions o;
  o.sampleTimeoutMs = 30;
  o.timeoutsBeforeLost = 2;
  auto r = openReceiver(mailbox, nullptr, o);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->state(), ConnectionState::WaitingForHello);
  RawSender raw(r->port());
  raw.send(encodeOscPose(poseWithFrame(0)));
  ASSERT_TRUE(eventually([&] { return r->stats().connections == 1; }));  // Streaming, perhaps only briefly
  ASSERT_TRUE(r->waitForState(ConnectionState::Lost, 10'000));
  EXPECT_GE(r->stats().timeouts, 2u);
  EXPECT_NE(r->lastError().find("no OSC frames for 60 ms"), std::string::npos) << r->lastError();
  OscPose kept;
  ASSERT_TRUE(r->takePose(kept));  // the last pose is still there to show
  EXPECT_EQ(kept.frame, 0u);
  raw.send(encodeOscPose(poseWithFrame(1)));
  ASSERT_TRUE(eventually([&] { return r->stats().connections == 2; }));
  const OscReceiverStats s = r->stats();
  EXPECT_EQ(s.connections, 2u);
  EXPECT_EQ(s.reconnects, 1u);
  EXPECT_EQ(s.dropped, 0u);
}

TEST(OscStream, DiyRawChannelsReachThePoseMailboxInArrivalOrder) {
  PoseMailboxOptions mo;
  mo.queueCapacity = 16;
  PoseMailbox mailbox(mo);
  auto r = openReceiver(mailbox);
  ASSERT_TRUE(r);
  lo_address a = lo_address_new("127.0.0.1", std::to_string(r->port()).c_str());
  for (int i = 0; i < 3; ++i) ASSERT_GT(lo_send(a, "/imps/channels", "iii", 100 + i, 2048, 4095), 0);
  lo_address_free(a);
  ASSERT_TRUE(eventually([&] { return r->stats().samples == 3; }));
  std::vector<Sample> samples;
  mailbox.drain(samples);
  ASSERT_EQ(samples.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(samples[i].sequence, i);
    EXPECT_EQ(samples[i].channelCount, 3);
    EXPECT_EQ(samples[i].counts[0], 100 + i);
    EXPECT_EQ(samples[i].counts[2], 4095u);
    EXPECT_GT(samples[i].arrivalTimeNs, 0);
  }
  EXPECT_EQ(r->stats().poses, 0u);
}

TEST(OscStream, SenderQueueOverflowDropsFramesTheReceiverSeesAsGaps) {
  PoseMailbox mailbox;
  Collected c;
  auto r = openReceiver(mailbox, &c);
  ASSERT_TRUE(r);
  constexpr uint64_t kOffered = 2000;
  OscSenderStats st;
  {
    auto sender = OscPoseSender::open({target(*r)}, 2);  // a tiny queue: a burst overflows it
    ASSERT_TRUE(sender) << sender.error().str();
    const OscPose p = poseWithFrame(0);
    uint64_t queued = 0;
    for (uint64_t i = 0; i < kOffered; ++i) queued += (*sender)->send(p) ? 1 : 0;
    ASSERT_TRUE(eventually([&] { return (*sender)->stats().sent == queued; }));
    st = (*sender)->stats();
    EXPECT_EQ(st.offered, kOffered);
    EXPECT_EQ(st.sent + st.dropped, kOffered);
    EXPECT_GT(st.dropped, 0u);  // 2000 frames offered back to back into 2 places
  }
  // Every datagram sent has landed (or been lost by the kernel) once the receiver has been quiet a while.
  uint64_t packets = 0;
  ASSERT_TRUE(eventually([&] {
    const uint64_t now = r->stats().packets;
    const bool quiet = now == packets && now > 0;
    packets = now;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    return quiet;
  }));
  const OscReceiverStats s = r->stats();
  std::lock_guard lock(c.mutex);
  ASSERT_FALSE(c.frames.empty());
  EXPECT_EQ(c.frames.front(), 0u);
  for (size_t i = 1; i < c.frames.size(); ++i) ASSERT_LT(c.frames[i - 1], c.frames[i]);
  EXPECT_EQ(s.outOfOrder, 0u);
  const uint32_t last = c.frames.back();
  EXPECT_EQ(s.poses + s.dropped, uint64_t(last) + 1);
  // With nothing lost by the kernel, the receiver's gaps are exactly the sender's drops before the last frame.
  if (s.poses == st.sent) {
    EXPECT_EQ(s.dropped, st.dropped - (kOffered - 1 - last));
  }
}

TEST(OscStream, ReceiverOpenErrorsAreReported) {
  PoseMailbox mailbox;
  auto first = openReceiver(mailbox);
  ASSERT_TRUE(first);
  OscReceiverOptions busy;
  busy.host = "127.0.0.1";
  busy.port = first->port();
  auto second = OscReceiver::open(busy, mailbox);
  ASSERT_FALSE(second);
  EXPECT_NE(second.error().str().find("cannot listen"), std::string::npos) << second.error().str();
  OscReceiverOptions named;
  named.host = "localhost";
  auto bad = OscReceiver::open(named, mailbox);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().str().find("numeric IPv4 address"), std::string::npos) << bad.error().str();
}

}  // namespace
}  // namespace imps::drivers
