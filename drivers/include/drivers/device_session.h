// SPDX-License-Identifier: MIT
// A live connection to one armature: the I/O thread, the connection state machine, the handshake, poll and stream
// modes, timeouts and reconnects. Every decoded Sample goes to a PoseMailbox. State machine in docs/devices.md.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "imps/clock.h"
#include "drivers/byte_transport.h"
#include "drivers/device_spec.h"
#include "drivers/line_protocol.h"
#include "drivers/pose_mailbox.h"
#include "drivers/sample.h"

namespace imps::drivers {

// disconnected → opening → waiting for hello → streaming → lost → reconnecting → waiting for hello → …
enum class ConnectionState : uint8_t {
  Disconnected,     // not started, or stopped
  Opening,          // trying to open the transport for the first time (retried every reconnectIntervalMs)
  WaitingForHello,  // open; binary: boot banner / HELLO / GET_INFO / START_STREAM; lines: waiting for a sample line;
                    // HID: waiting for the first input report
  Streaming,        // samples are flowing (stream mode) or being polled (poll mode)
  Lost,             // the connection dropped (read error, node vanished, repeated timeouts); the last pose stays
  Reconnecting,     // trying to open the transport again
};
const char* toString(ConnectionState state);

struct DeviceSessionOptions {
  WireProtocol protocol = WireProtocol::Binary;
  AcquisitionMode mode = AcquisitionMode::Stream;  // binary only; the line protocol always streams
  // Stream mode: the rate asked for with START_STREAM (0: 100 Hz). Poll mode: polls per second (0: as fast as the
  // device answers, one poll outstanding).
  uint16_t rateHz = 0;
  // After opening, how long to wait for the device's own HELLO (an Arduino reboots when its port opens and needs
  // about 1.5 s) before asking with HOST_HELLO.
  int bootWaitMs = 2500;
  int replyTimeoutMs = 500;  // per command attempt
  int commandAttempts = 3;   // HOST_HELLO / GET_INFO / START_STREAM / POLL tries before giving up
  // Streaming with no sample for this long is a timeout (counted); binary re-sends START_STREAM.
  int sampleTimeoutMs = 1000;
  // Consecutive timeouts after which the connection counts as lost and is reopened.
  int timeoutsBeforeLost = 3;
  int reconnectIntervalMs = 500;  // wait between open attempts
  int ioWaitMs = 20;              // longest single read wait: bounds how long stop() takes
  LineDecoderOptions lineOptions;  // line protocol decoder settings
  int lineBitsPerChannel = 32;     // line protocol: the bits DeviceInfo reports (lines carry none; spec key bits)
  // Host clock for Sample::arrivalTimeNs (null: steadyNowNs, as PoseMailbox); must outlive the session and be
  // safe to read from its I/O thread. Timeouts use the steady clock.
  Clock* clock = nullptr;
};

// Options from a parsed spec (protocol, mode, rate, channel count, line bits: a sim: spec's `bits` too, so a
// simulated line device is what it simulates); other fields keep their defaults.
DeviceSessionOptions sessionOptionsFor(const DeviceSpec& spec);

// Counters since construction (they survive reconnects). Each field is read atomically; the set is not one
// consistent snapshot.
struct DeviceSessionStats {
  ConnectionState state = ConnectionState::Disconnected;
  uint64_t bytesReceived = 0;
  uint64_t samples = 0;          // published to the mailbox
  uint64_t garbageBytes = 0;     // bytes skipped by the decoder while resynchronising (plus overlong lines)
  uint64_t crcErrors = 0;        // binary: header + frame CRC failures
  uint64_t malformedFrames = 0;  // binary: good CRC, bad payload; HID: unknown report IDs and short reports
  uint64_t unknownTypes = 0;     // binary: good CRC, message type unknown to this version (skipped)
  uint64_t unsupportedVersions = 0;  // binary: good CRC, another protocol version (skipped)
  uint64_t oversizeFrames = 0;   // binary: a header claiming more than 2048 payload bytes
  uint64_t truncatedFrames = 0;  // binary: a frame that never completed before a timeout (bytes behind it rescanned)
  uint64_t parseErrors = 0;      // lines: malformed, mismatched-count and overlong lines
  uint64_t samplesDropped = 0;   // sequence numbers missing, across timeouts, polls and reconnects (binary, HID)
  uint64_t duplicateSamples = 0; // binary: a sample repeating the previous sequence number (published once)
  uint64_t sequenceResets = 0;   // binary, HID: the sequence went backwards without a HELLO
  uint64_t timeouts = 0;         // commands unanswered and streams gone quiet
  uint64_t deviceErrors = 0;     // ERROR messages from the device
  uint64_t deviceResets = 0;     // unsolicited HELLO (the device rebooted): the only restart of sequence tracking
  uint64_t layoutChanges = 0;    // lines: the channel count re-locked while streaming (deviceInfo() follows it)
  uint64_t connections = 0;      // times the state reached Streaming
  uint64_t reconnects = 0;       // of which after a loss
  uint64_t openFailures = 0;
};

// One counter of DeviceSessionStats with a stable name (as stored in session files) and a label for people.
struct NamedCounter {
  const char* name;   // camelCase, e.g. "crcErrors"; never renamed (session files store it)
  const char* label;  // e.g. "CRC errors"
  uint64_t value;
};
// The fault and link counters of `stats` (not state, bytesReceived, samples or connections), in a fixed order:
// what `record` prints, `info` shows from the session file and the HUD lists when non-zero.
std::vector<NamedCounter> namedCounters(const DeviceSessionStats& stats);
// The label for a counter name, or nullptr for a name this build does not know (a newer writer's).
const char* counterLabel(std::string_view name);

// Owns one device's I/O thread. Thread-safety: construct, start(), stop() and destroy from one controlling
// thread; state(), stats(), deviceInfo(), lastError(), banner(), warnings() and waitForState() may be called
// from any thread at any time. The hot path (state(), stats(), and the mailbox) takes no locks; deviceInfo(),
// lastError(), banner() and warnings() take a short mutex and copy — call them from UI code, not per sample.
// The consumer is never blocked: samples reach it only through the PoseMailbox (wait-free). The mailbox is not
// owned and must outlive the session; the session is its only producer.
class DeviceSession {
 public:
  DeviceSession(TransportOpener opener, PoseMailbox& mailbox, DeviceSessionOptions options = {});
  ~DeviceSession();  // stop()
  DeviceSession(const DeviceSession&) = delete;
  DeviceSession& operator=(const DeviceSession&) = delete;

  // Starts the I/O thread (no-op when running).
  void start();
  // Asks the I/O thread to finish, sends STOP_STREAM when streaming, closes the transport and joins; the state
  // becomes Disconnected. Returns within about ioWaitMs + one write timeout.
  void stop();

  ConnectionState state() const { return state_.load(std::memory_order_acquire); }
  DeviceSessionStats stats() const;
  // The device's description from the last HELLO/INFO (synthesised for the line protocol); nullopt before the
  // first handshake. Kept while lost.
  std::optional<DeviceInfo> deviceInfo() const;
  std::string lastError() const;          // the latest open/read/protocol problem, "" when none
  std::vector<std::string> banner() const;  // lines protocol: the boot banner lines; binary: text seen before HELLO
  std::vector<std::string> warnings() const;  // the transport's warnings (e.g. FTDI latency)

  // Blocks the caller until state() == wanted or timeoutMs passes; returns whether the state was reached.
  bool waitForState(ConnectionState wanted, int timeoutMs) const;

 private:
  struct Io;  // the I/O thread's private state (transport, decoders)
  void run();
  void setState(ConnectionState s);
  void setError(std::string message);

  TransportOpener opener_;
  PoseMailbox& mailbox_;
  DeviceSessionOptions options_;
  std::thread thread_;
  std::atomic<bool> stopRequested_{false};
  std::atomic<ConnectionState> state_{ConnectionState::Disconnected};

  struct Counters {
    std::atomic<uint64_t> bytesReceived{0}, samples{0}, garbageBytes{0}, crcErrors{0}, malformedFrames{0},
        unknownTypes{0}, unsupportedVersions{0}, oversizeFrames{0}, truncatedFrames{0}, parseErrors{0},
        samplesDropped{0}, duplicateSamples{0}, sequenceResets{0}, timeouts{0}, deviceErrors{0}, deviceResets{0},
        layoutChanges{0}, connections{0}, reconnects{0}, openFailures{0};
  };
  Counters counters_;

  mutable std::mutex mutex_;  // guards the fields below and pairs with stateChanged_
  mutable std::condition_variable stateChanged_;
  std::optional<DeviceInfo> info_;
  std::string lastError_;
  std::vector<std::string> banner_;
  std::vector<std::string> warnings_;

  friend struct Io;
};

}  // namespace imps::drivers
