// SPDX-License-Identifier: MIT
// The OSC pose sender (drivers/src/osc_sender.cpp) against plain UDP sockets on 127.0.0.1 (no OSC library on the
// receiving side): each target gets every queued frame as the bundle encodeOscPose describes, byte for byte, with
// frame counters 0, 1, 2 … stamped in send order and sentTimeNs stamped when sent; a full queue drops frames and
// counts them (send() says so, the counters skip them); the destructor sends what is queued; target URLs are
// checked. Overflow is provoked by a burst into a two-frame queue, and every assertion about it is an invariant
// that holds however the sender thread is scheduled.
#include "drivers/osc_sender.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "drivers/sample.h"
#include "imps/clock.h"

namespace imps::drivers {
namespace {

// A UDP socket bound to an ephemeral port on 127.0.0.1.
class UdpSink {
 public:
  UdpSink() : fd_(socket(AF_INET, SOCK_DGRAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(bind(fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0);
    socklen_t len = sizeof a;
    getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    const int buffer = 4 << 20;  // as much as the kernel allows: a burst should not be lost here
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
  }
  ~UdpSink() { ::close(fd_); }
  UdpSink(const UdpSink&) = delete;
  UdpSink& operator=(const UdpSink&) = delete;

  std::string url() const { return "osc.udp://127.0.0.1:" + std::to_string(port_); }
  // The next datagram, or empty when none comes within boundMs (generous by default: the assertion is on the bytes).
  std::vector<uint8_t> receive(int boundMs = 10'000) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, boundMs) != 1) return {};
    std::vector<uint8_t> buffer(65536);
    const ssize_t n = recv(fd_, buffer.data(), buffer.size(), 0);
    buffer.resize(n > 0 ? size_t(n) : 0);
    return buffer;
  }

 private:
  int fd_;
  uint16_t port_ = 0;
};

OscPose posed(float angle) {
  OscPose p;
  p.sampleTimeNs = 123456789;
  p.jointCount = 2;
  std::strcpy(p.joints[0].name.data(), "Hips");
  std::strcpy(p.joints[1].name.data(), "LeftKnee");
  p.joints[1].w = std::cos(angle / 2);
  p.joints[1].x = std::sin(angle / 2);
  p.hasRoot = true;
  p.root = {0.5f, 1.0f, -0.25f};
  return p;
}

OscPose decoded(const std::vector<uint8_t>& datagram) {
  OscPose pose;
  Sample channels;
  auto result = decodeOscPacket(datagram, 0, pose, channels);
  EXPECT_TRUE(result.has_value()) << (result ? "" : result.error().str());
  EXPECT_EQ(result ? result->kind : OscPacketKind::Ignored, OscPacketKind::Pose);
  return pose;
}

TEST(OscSender, EveryTargetGetsEveryFrameAsItsBundleWithCountersInOrder) {
  UdpSink a, b;
  constexpr uint32_t kFrames = 16;
  const int64_t before = steadyNowNs();
  {
    auto sender = OscPoseSender::open({a.url(), b.url()}, kFrames);  // room for every frame
    ASSERT_TRUE(sender) << sender.error().str();
    EXPECT_EQ((*sender)->targets(), (std::vector<std::string>{a.url(), b.url()}));
    for (uint32_t i = 0; i < kFrames; ++i) {
      OscPose p = posed(0.1f * float(i));
      p.frame = 999;  // the sender's counter replaces it
      ASSERT_TRUE((*sender)->send(p)) << i;
    }
    ASSERT_TRUE((*sender)->flush(10'000));
    const OscSenderStats st = (*sender)->stats();
    EXPECT_EQ(st.offered, kFrames);
    EXPECT_EQ(st.sent, 2u * kFrames) << "counted per target";
    EXPECT_EQ(st.dropped, 0u);
    EXPECT_EQ(st.sendErrors, 0u);
    EXPECT_EQ((*sender)->lastError(), "");
  }
  const int64_t after = steadyNowNs();
  for (UdpSink* sink : {&a, &b}) {
    int64_t lastSent = before;
    for (uint32_t i = 0; i < kFrames; ++i) {
      const std::vector<uint8_t> datagram = sink->receive();
      ASSERT_FALSE(datagram.empty()) << "frame " << i << " never arrived";
      const OscPose got = decoded(datagram);
      EXPECT_EQ(got.frame, i) << "counters 0, 1, 2 … in send order";
      EXPECT_GE(got.sentTimeNs, lastSent) << "stamped when sent, in order";
      EXPECT_LE(got.sentTimeNs, after);
      lastSent = got.sentTimeNs;
      // Byte for byte the bundle encodeOscPose describes for the pose with its counter and send time.
      OscPose expected = posed(0.1f * float(i));
      expected.frame = i;
      expected.sentTimeNs = got.sentTimeNs;
      EXPECT_EQ(datagram, encodeOscPose(expected)) << "frame " << i;
    }
  }
}

TEST(OscSender, AFullQueueDropsAndCountsFramesAndTheirCountersAreSkipped) {
  UdpSink sink;
  constexpr uint32_t kOffered = 400;
  std::set<uint32_t> queued;
  OscSenderStats st;
  std::vector<uint32_t> received;
  std::atomic<size_t> expected{SIZE_MAX};  // set once the sender has sent everything
  std::jthread reader([&] {
    // Reads until every datagram sent has come, or the socket stays quiet for the bound after the last send.
    for (int quiet = 0; received.size() < expected.load() && quiet < 40;) {
      const std::vector<uint8_t> d = sink.receive(50);
      if (d.empty()) {
        quiet += expected.load() == SIZE_MAX ? 0 : 1;
        continue;
      }
      quiet = 0;
      received.push_back(decoded(d).frame);
    }
  });
  {
    auto sender = OscPoseSender::open({sink.url()}, 2);  // a burst overflows two places
    ASSERT_TRUE(sender) << sender.error().str();
    uint64_t refused = 0;
    for (uint32_t i = 0; i < kOffered; ++i) {
      if ((*sender)->send(posed(0.0f)))
        queued.insert(i);
      else
        ++refused;
    }
    ASSERT_TRUE((*sender)->flush(10'000));
    st = (*sender)->stats();
    EXPECT_EQ(st.offered, kOffered);
    EXPECT_EQ(st.dropped, refused) << "send() returns false exactly for the dropped frames";
    EXPECT_EQ(st.sent + st.dropped, kOffered);
    EXPECT_EQ(st.sent, queued.size());
    expected = st.sent;
  }
  reader.join();
  // The counters of dropped frames are used anyway: what arrives is a subset of the queued counters, in order.
  for (size_t k = 0; k < received.size(); ++k) {
    EXPECT_TRUE(queued.count(received[k])) << "frame " << received[k] << " was dropped yet arrived";
    if (k > 0) {
      EXPECT_LT(received[k - 1], received[k]);
    }
  }
  // Loopback UDP may still lose a datagram in the kernel; when it lost none, what arrived is exactly what was queued.
  if (received.size() == queued.size()) {
    EXPECT_EQ(std::set<uint32_t>(received.begin(), received.end()), queued);
  }
}

TEST(OscSender, TheDestructorSendsWhatIsQueued) {
  UdpSink sink;
  constexpr uint32_t kFrames = 32;
  {
    auto sender = OscPoseSender::open({sink.url()}, kFrames);
    ASSERT_TRUE(sender) << sender.error().str();
    for (uint32_t i = 0; i < kFrames; ++i) ASSERT_TRUE((*sender)->send(posed(0.0f)));
    // No flush: destruction itself must send them.
  }
  for (uint32_t i = 0; i < kFrames; ++i) {
    const std::vector<uint8_t> datagram = sink.receive();
    ASSERT_FALSE(datagram.empty()) << "frame " << i << " was not sent before the sender stopped";
    EXPECT_EQ(decoded(datagram).frame, i);
  }
}

TEST(OscSender, TargetUrlsAreChecked) {
  EXPECT_TRUE(checkOscTargetUrl("osc.udp://127.0.0.1:9000"));
  EXPECT_TRUE(checkOscTargetUrl("osc.udp://render-2.local:9000/"));
  auto scheme = checkOscTargetUrl("udp://127.0.0.1:9000");
  ASSERT_FALSE(scheme);
  EXPECT_EQ(scheme.error().str(), "osc:1:1: error: expected osc.udp://HOST:PORT\n");
  auto port = checkOscTargetUrl("osc.udp://127.0.0.1:99999");
  ASSERT_FALSE(port);
  EXPECT_EQ(port.error().str(), "osc:1:21: error: expected a port in 1..65535\n");
  EXPECT_EQ(port.error().all().front().loc.column, 21);
  EXPECT_FALSE(checkOscTargetUrl("osc.udp://:9000"));  // a target needs a host
  EXPECT_FALSE(checkOscTargetUrl("osc.udp://host"));
  EXPECT_FALSE(checkOscTargetUrl("osc.udp://127.0.0.1:0"));
}

TEST(OscSender, OpenRefusesTheFirstBadUrlNamingIt) {
  UdpSink sink;
  auto sender = OscPoseSender::open({sink.url(), "osc.tcp://127.0.0.1:9000", "also bad"});
  ASSERT_FALSE(sender);
  EXPECT_EQ(sender.error().str(), "osc.tcp://127.0.0.1:9000: osc:1:1: error: expected osc.udp://HOST:PORT\n");
}

}  // namespace
}  // namespace imps::drivers
