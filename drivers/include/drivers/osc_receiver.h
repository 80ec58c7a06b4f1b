// SPDX-License-Identifier: MIT
// An OSC pose source (`--device osc.udp://:PORT`, docs/osc.md): a UDP socket read on its own I/O thread, datagrams
// decoded by drivers/osc_codec.h. Pose frames go to a newest-value buffer, raw channels to the PoseMailbox like
// any device's samples; ordering, lateness, loss and malformed packets are counted as for devices.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "imps/clock.h"
#include "drivers/device_session.h"
#include "drivers/latest_value.h"
#include "drivers/osc_codec.h"
#include "drivers/pose_mailbox.h"

namespace imps::drivers {

struct OscReceiverOptions {
  std::string host;   // the numeric IPv4 address to listen on; "" = every interface
  uint16_t port = 0;  // 0: an ephemeral port (tests; port() says which)
  int ioWaitMs = 20;  // longest single wait for a datagram: bounds how long stop() takes
  // Streaming with no packet for this long is a timeout; timeoutsBeforeLost in a row make the source Lost (the
  // last pose stays). The next packet makes it Streaming again (a reconnect).
  int sampleTimeoutMs = 1000;
  int timeoutsBeforeLost = 3;
  // A frame is late when its transit (arrival minus the sender's send time) exceeds the smallest transit seen so
  // far by more than this. The two clocks need not agree: only differences of transit count.
  int64_t lateNs = 20'000'000;
  // Host clock for arrival times (null: steadyNowNs); must outlive the receiver and be safe to read from its thread.
  Clock* clock = nullptr;
  // Called on the I/O thread with every pose frame accepted (in order), after it is published. For monitors,
  // tests and benchmarks; must be quick and must not call back into the receiver.
  std::function<void(const OscPose&)> onPose;
};

// Counters since start(); each read atomically, not one consistent snapshot.
struct OscReceiverStats {
  ConnectionState state = ConnectionState::Disconnected;
  uint64_t packets = 0;     // datagrams read
  uint64_t bytes = 0;
  uint64_t poses = 0;       // pose frames accepted (published)
  uint64_t samples = 0;     // raw-channel samples accepted (published to the mailbox)
  uint64_t ignored = 0;     // well-formed OSC without an /imps/ frame (another program's traffic)
  uint64_t malformed = 0;   // datagrams that failed to decode (lastError() says why); the stream goes on
  uint64_t outOfOrder = 0;  // frames older than (or equal to) the newest accepted one: discarded
  uint64_t late = 0;        // frames accepted but late (OscReceiverOptions::lateNs)
  uint64_t dropped = 0;     // frame counters skipped over (never arrived before a newer one)
  uint64_t senderRestarts = 0;  // frame counter jumps of more than 2^20 either way: a new stream, not a gap
  uint64_t timeouts = 0;
  uint64_t connections = 0;  // times the state reached Streaming
  uint64_t reconnects = 0;   // of which after a loss
  int64_t lastTransitNs = 0;  // arrival minus the sender's send time, last pose (meaningful on one host)
};

// Owns the socket and the I/O thread. Thread-safety as DeviceSession: construct, start(), stop() and destroy from
// one controlling thread; stats(), state(), lastError() and port() from any thread; takePose() from one consumer
// thread (the frame loop). The mailbox is not owned, must outlive the receiver, and gets only raw-channel samples.
class OscReceiver {
 public:
  // Binds the socket now, so a busy port or a bad address is reported at once, as an IoError naming
  // "osc.udp://HOST:PORT" (errorText: "osc.udp://HOST:PORT: error: …"; a host that is not a numeric IPv4
  // address has code EINVAL).
  static IoResult<std::unique_ptr<OscReceiver>> open(OscReceiverOptions options, PoseMailbox& channels);
  ~OscReceiver();  // stop(), closes the socket
  OscReceiver(const OscReceiver&) = delete;
  OscReceiver& operator=(const OscReceiver&) = delete;

  void start();  // starts the I/O thread (no-op when running); the state becomes WaitingForHello
  void stop();   // joins within about ioWaitMs; the state becomes Disconnected

  // The newest pose frame accepted since the last call, into `out`; false (and `out` untouched) when none.
  bool takePose(OscPose& out) { return poses_.take(out); }

  uint16_t port() const { return port_; }
  ConnectionState state() const { return state_.load(std::memory_order_acquire); }
  OscReceiverStats stats() const;
  std::string lastError() const;  // the latest malformed packet's decode error, or why the source was lost; "" none
  // Blocks until state() == wanted or timeoutMs passes; returns whether it was reached.
  bool waitForState(ConnectionState wanted, int timeoutMs) const;

 private:
  OscReceiver(int fd, uint16_t port, OscReceiverOptions options, PoseMailbox& channels);
  void run();
  bool handle(std::span<const uint8_t> packet, int64_t arrivalNs);  // true when a frame was accepted
  bool accept(uint32_t frame, int64_t arrivalNs, int64_t sentNs);
  void setState(ConnectionState s);

  int fd_ = -1;
  uint16_t port_ = 0;
  OscReceiverOptions options_;
  PoseMailbox& mailbox_;
  LatestValue<OscPose> poses_;
  std::thread thread_;
  std::atomic<bool> stopRequested_{false};
  std::atomic<ConnectionState> state_{ConnectionState::Disconnected};
  // I/O thread only.
  std::unique_ptr<OscPose> pose_;  // decode target (large: kept off the stack)
  Sample sample_;
  bool haveFrame_ = false;
  uint32_t newestFrame_ = 0;
  uint32_t unframedSequence_ = 0;
  int64_t minTransitNs_ = INT64_MAX;
  bool everConnected_ = false;

  struct Counters {
    std::atomic<uint64_t> packets{0}, bytes{0}, poses{0}, samples{0}, ignored{0}, malformed{0}, outOfOrder{0},
        late{0}, dropped{0}, senderRestarts{0}, timeouts{0}, connections{0}, reconnects{0};
    std::atomic<int64_t> lastTransitNs{0};
  };
  Counters counters_;
  mutable std::mutex mutex_;  // guards lastError_, pairs with stateChanged_
  mutable std::condition_variable stateChanged_;
  std::string lastError_;
};

}  // namespace imps::drivers
