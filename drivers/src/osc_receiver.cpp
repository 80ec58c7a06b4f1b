// SPDX-License-Identifier: MIT
// The OSC pose source's I/O thread: read datagrams, decode, order, publish; count every fault.
#include "drivers/osc_receiver.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <vector>

#include "text.h"
#include "imps/clock.h"

namespace imps::drivers {
namespace {

constexpr int64_t kMs = 1'000'000;
// A frame-counter jump larger than this either way is a new stream (the sender restarted), not a gap.
constexpr int64_t kRestartJump = int64_t(1) << 20;

void bump(std::atomic<uint64_t>& c, uint64_t by = 1) {
  c.store(c.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

}  // namespace

IoResult<std::unique_ptr<OscReceiver>> OscReceiver::open(OscReceiverOptions options, PoseMailbox& channels) {
  const std::string name = cat("osc.udp://", options.host, ":", options.port);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(options.port);
  address.sin_addr.s_addr = htonl(INADDR_ANY);
  if (!options.host.empty() && inet_pton(AF_INET, options.host.c_str(), &address.sin_addr) != 1)
    return std::unexpected(
        IoError{name, "expected a numeric IPv4 address to listen on (or none: osc.udp://:PORT)", EINVAL});
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::unexpected(IoError::fromErrno(name, "cannot create a UDP socket", errno));
  // Room for bursts: a 1 kHz stream of ~1 KB bundles queues a second's worth while the I/O thread is descheduled.
  const int bufferBytes = 1 << 20;
  setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bufferBytes, sizeof bufferBytes);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int e = errno;
    ::close(fd);
    IoError error = IoError::fromErrno(name, "cannot listen", e);
    if (e == EADDRINUSE) error.message += " (another program receives on this port)";
    return std::unexpected(std::move(error));
  }
  socklen_t length = sizeof address;
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length);
  return std::unique_ptr<OscReceiver>(new OscReceiver(fd, ntohs(address.sin_port), std::move(options), channels));
}

OscReceiver::OscReceiver(int fd, uint16_t port, OscReceiverOptions options, PoseMailbox& channels)
    : fd_(fd), port_(port), options_(std::move(options)), mailbox_(channels), pose_(std::make_unique<OscPose>()) {}

OscReceiver::~OscReceiver() {
  stop();
  ::close(fd_);
}

void OscReceiver::start() {
  if (thread_.joinable()) return;
  stopRequested_.store(false);
  setState(ConnectionState::WaitingForHello);
  thread_ = std::thread([this] { run(); });
}

void OscReceiver::stop() {
  if (!thread_.joinable()) return;
  stopRequested_.store(true);
  thread_.join();
  setState(ConnectionState::Disconnected);
}

void OscReceiver::setState(ConnectionState s) {
  {
    std::lock_guard lock(mutex_);
    state_.store(s, std::memory_order_release);
  }
  stateChanged_.notify_all();
}

void OscReceiver::run() {
  std::vector<uint8_t> buffer(kMaxOscPacket + 1);
  int64_t lastPacket = steadyNowNs();
  int consecutiveTimeouts = 0;
  while (!stopRequested_.load(std::memory_order_relaxed)) {
    pollfd p{fd_, POLLIN, 0};
    // Every datagram waiting (at most 64 per wake-up, so the silence check below still runs under a flood).
    for (int i = 0; i < 64 && (i > 0 || poll(&p, 1, options_.ioWaitMs) > 0); ++i) {
      // MSG_TRUNC: the datagram's real length, so an oversize one is reported, not decoded cut short.
      const ssize_t n = recv(fd_, buffer.data(), buffer.size(), MSG_TRUNC | MSG_DONTWAIT);
      if (n < 0) break;
      const int64_t arrival = options_.clock ? options_.clock->nowNs() : steadyNowNs();
      if (!handle(std::span(buffer.data(), std::min(size_t(n), buffer.size())), arrival)) continue;
      lastPacket = steadyNowNs();
      consecutiveTimeouts = 0;
      if (state() != ConnectionState::Streaming) {
        bump(counters_.connections);
        if (everConnected_) bump(counters_.reconnects);
        everConnected_ = true;
        setState(ConnectionState::Streaming);
      }
    }
    // Silence: a timeout each sampleTimeoutMs; enough of them in a row lose the source (the last pose stays).
    if (state() == ConnectionState::Streaming && steadyNowNs() - lastPacket >= options_.sampleTimeoutMs * kMs) {
      bump(counters_.timeouts);
      lastPacket = steadyNowNs();
      if (++consecutiveTimeouts >= options_.timeoutsBeforeLost) {
        {
          std::lock_guard lock(mutex_);
          lastError_ = cat("no OSC frames for ", options_.sampleTimeoutMs * options_.timeoutsBeforeLost, " ms");
        }
        setState(ConnectionState::Lost);
      }
    }
  }
}

bool OscReceiver::handle(std::span<const uint8_t> packet, int64_t arrivalNs) {
  bump(counters_.packets);
  bump(counters_.bytes, packet.size());
  auto decoded = packet.size() > kMaxOscPacket
                     ? std::expected<OscDecoded, Diagnostics>(
                           diagnosticError({"osc:byte 0"}, cat("a datagram larger than ", kMaxOscPacket, " bytes")))
                     : decodeOscPacket(packet, arrivalNs, *pose_, sample_);
  if (!decoded) {
    bump(counters_.malformed);
    std::lock_guard lock(mutex_);
    lastError_ = firstError(decoded.error());
    return false;
  }
  switch (decoded->kind) {
    case OscPacketKind::Ignored:
      bump(counters_.ignored);
      return false;
    case OscPacketKind::Pose:
      if (!accept(pose_->frame, arrivalNs, pose_->sentTimeNs)) return false;
      poses_.publish(*pose_);
      bump(counters_.poses);
      if (options_.onPose) options_.onPose(*pose_);
      return true;
    case OscPacketKind::Channels:
      if (decoded->hasFrame) {
        if (!accept(sample_.sequence, arrivalNs, 0)) return false;
      } else {
        sample_.sequence = unframedSequence_++;  // no counter to order by: the order of arrival
      }
      mailbox_.publish(sample_);
      bump(counters_.samples);
      return true;
  }
  return false;
}

// Ordering and lateness of a framed packet; false when it is discarded (out of order).
bool OscReceiver::accept(uint32_t frame, int64_t arrivalNs, int64_t sentNs) {
  if (haveFrame_) {
    const int64_t step = int32_t(frame - newestFrame_);
    if (step > kRestartJump || step < -kRestartJump) {
      bump(counters_.senderRestarts);
      minTransitNs_ = INT64_MAX;
    } else if (step <= 0) {
      bump(counters_.outOfOrder);
      return false;
    } else if (step > 1) {
      bump(counters_.dropped, uint64_t(step - 1));
    }
  }
  haveFrame_ = true;
  newestFrame_ = frame;
  if (sentNs != 0) {
    const int64_t transit = arrivalNs - sentNs;
    counters_.lastTransitNs.store(transit, std::memory_order_relaxed);
    if (transit < minTransitNs_) minTransitNs_ = transit;
    if (transit - minTransitNs_ > options_.lateNs) bump(counters_.late);
  }
  return true;
}

OscReceiverStats OscReceiver::stats() const {
  auto get = [](const std::atomic<uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  OscReceiverStats s;
  s.state = state();
  s.packets = get(counters_.packets);
  s.bytes = get(counters_.bytes);
  s.poses = get(counters_.poses);
  s.samples = get(counters_.samples);
  s.ignored = get(counters_.ignored);
  s.malformed = get(counters_.malformed);
  s.outOfOrder = get(counters_.outOfOrder);
  s.late = get(counters_.late);
  s.dropped = get(counters_.dropped);
  s.senderRestarts = get(counters_.senderRestarts);
  s.timeouts = get(counters_.timeouts);
  s.connections = get(counters_.connections);
  s.reconnects = get(counters_.reconnects);
  s.lastTransitNs = counters_.lastTransitNs.load(std::memory_order_relaxed);
  return s;
}

std::string OscReceiver::lastError() const {
  std::lock_guard lock(mutex_);
  return lastError_;
}

bool OscReceiver::waitForState(ConnectionState wanted, int timeoutMs) const {
  std::unique_lock lock(mutex_);
  return stateChanged_.wait_for(lock, std::chrono::milliseconds(timeoutMs), [&] { return state() == wanted; });
}

}  // namespace imps::drivers
