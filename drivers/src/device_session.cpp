// SPDX-License-Identifier: MIT
// The device session's I/O thread: open, handshake, poll or stream, publish, and recover from faults.
#include "drivers/device_session.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <chrono>
#include <memory>

#include "drivers/binary_protocol.h"
#include "drivers/hid_report.h"
#include "text.h"
#include "imps/clock.h"

namespace imps::drivers {

const char* toString(ConnectionState state) {
  switch (state) {
    case ConnectionState::Disconnected: return "disconnected";
    case ConnectionState::Opening: return "opening";
    case ConnectionState::WaitingForHello: return "waiting for hello";
    case ConnectionState::Streaming: return "streaming";
    case ConnectionState::Lost: return "lost";
    case ConnectionState::Reconnecting: return "reconnecting";
  }
  return "?";
}

DeviceSessionOptions sessionOptionsFor(const DeviceSpec& spec) {
  DeviceSessionOptions o;
  o.protocol = spec.protocol;
  o.mode = spec.mode;
  o.rateHz = spec.rateHz;
  o.lineOptions.expectedChannelCount = spec.channels;
  if (spec.bits != 0) o.lineBitsPerChannel = spec.bits;
  for (const auto& [key, value] : spec.simParams)
    if (key == "bits") {
      int bits = 0;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), bits);
      if (ec == std::errc() && end == value.data() + value.size() && bits >= 1 && bits <= 32)
        o.lineBitsPerChannel = bits;
    }
  if (spec.kind == DeviceKind::Hid) o.protocol = WireProtocol::HidReports;
  // A USB armature booted when it enumerated: no boot banner to wait for, and failed opens are cheap (usbOpener
  // waits for the hotplug arrival), so retry often.
  if (spec.kind == DeviceKind::Usb) {
    o.bootWaitMs = 100;
    o.reconnectIntervalMs = 100;
  }
  return o;
}

namespace {

constexpr int64_t kMs = 1'000'000;

void bump(std::atomic<uint64_t>& c, uint64_t by = 1) { c.fetch_add(by, std::memory_order_relaxed); }
void raise(std::atomic<uint64_t>& c, uint64_t to) {
  if (to > c.load(std::memory_order_relaxed)) c.store(to, std::memory_order_relaxed);
}

// Why a connection ended: the transport failed (or timeouts piled up), or stop() was called.
enum class End { Lost, Stopped };

}  // namespace

// Everything only the I/O thread touches.
struct DeviceSession::Io {
  DeviceSession& s;
  const DeviceSessionOptions& o;
  std::unique_ptr<ByteTransport> transport;
  BinaryDecoder binary;
  LineDecoder lines;
  HidReportDecoder hid;
  uint32_t commandSequence = 0;
  std::array<uint8_t, 4096> readBuffer{};
  std::vector<uint8_t> writeBuffer;
  std::string textBeforeHello;  // printable bytes skipped before the first HELLO (an Arduino's boot text)
  int consecutiveTimeouts = 0;
  bool streamingStarted = false;
  int64_t lastSampleNs = 0;  // steady time of the last published sample

  Io(DeviceSession& session) : s(session), o(session.options_), lines(session.options_.lineOptions) {}

  int64_t hostNow() const { return o.clock ? o.clock->nowNs() : steadyNowNs(); }
  bool stopping() const { return s.stopRequested_.load(std::memory_order_relaxed); }

  // Copies the decoders' cumulative counters into the session's atomics.
  void syncCounters() {
    const BinaryDecoderStats& b = binary.stats();
    const LineDecoderStats& l = lines.stats();
    const HidDecoderStats& h = hid.stats();
    Counters& c = s.counters_;
    raise(c.bytesReceived, b.bytesReceived + l.bytesReceived + h.bytes);
    raise(c.garbageBytes, b.bytesSkipped + l.bytesSkipped);
    raise(c.crcErrors, b.headerCrcErrors + b.crcErrors);
    raise(c.malformedFrames, b.malformedFrames + h.unknownReportIds + h.shortReports);
    raise(c.unknownTypes, b.unknownTypes);
    raise(c.unsupportedVersions, b.unsupportedVersions);
    raise(c.oversizeFrames, b.oversizeFrames);
    raise(c.truncatedFrames, b.truncatedFrames);
    raise(c.parseErrors, l.errors());
    raise(c.samplesDropped, b.samplesDropped + h.samplesDropped);
    raise(c.duplicateSamples, b.duplicateSamples);
    raise(c.sequenceResets, b.sequenceResets + h.sequenceResets);
  }

  // Reads what arrives within waitMs and feeds the active decoder. False when the transport failed.
  bool pump(int waitMs) {
    auto n = transport->read(readBuffer, std::max(0, std::min(waitMs, o.ioWaitMs)));
    if (!n) {
      s.setError(errorText(n.error()));
      return false;
    }
    if (*n == 0) return true;
    const std::span<const uint8_t> bytes(readBuffer.data(), *n);
    if (o.protocol == WireProtocol::Binary) {
      if (!s.info_.has_value() || s.state() == ConnectionState::WaitingForHello) noteText(bytes);
      binary.feed(bytes, hostNow());
    } else if (o.protocol == WireProtocol::HidReports) {
      // A message transport: these bytes are exactly one input report.
      if (auto sample = hid.decode(bytes, hostNow())) {
        if (s.state() != ConnectionState::Streaming) connected();
        publish(*sample);
      }
    } else {
      lines.feed(bytes, hostNow());
    }
    return true;
  }

  void noteText(std::span<const uint8_t> bytes) {
    for (uint8_t b : bytes) {
      if (textBeforeHello.size() >= 4096) return;
      if (b == '\n' || b == '\r') {
        flushTextLine();
      } else if (b >= 0x20 && b < 0x7F) {
        textBeforeHello.push_back(static_cast<char>(b));
      }
    }
  }
  void flushTextLine() {
    // Keep only lines that look like text (a run of frame bytes is rarely 4+ printable characters).
    if (textBeforeHello.size() >= 4) {
      std::lock_guard lock(s.mutex_);
      if (s.banner_.size() < 32) s.banner_.push_back(textBeforeHello);
    }
    textBeforeHello.clear();
  }

  bool send(const Message& m) {
    writeBuffer.clear();
    if (auto r = appendFrame(m, writeBuffer); !r) {
      s.setError("internal: cannot encode command: " + firstMessage(r.error()));
      return false;
    }
    if (auto r = transport->write(writeBuffer, o.replyTimeoutMs); !r) {
      s.setError(errorText(r.error()));
      return false;
    }
    return true;
  }

  void publish(const Sample& sample) {
    s.mailbox_.publish(sample);
    lastSampleNs = steadyNowNs();
    bump(s.counters_.samples);
    consecutiveTimeouts = 0;
  }

  void handleDeviceError(const msg::Error& e) {
    bump(s.counters_.deviceErrors);
    s.setError("device error " + std::to_string(static_cast<int>(e.code)) + ": " + e.text);
  }

  // ---- Binary protocol

  enum class Wait { Got, Timeout, Failed };

  // Pumps until `match` accepts a message or timeoutMs passes. Samples that arrive meanwhile are published.
  template <class Match>
  Wait waitFor(int timeoutMs, Match&& match) {
    const int64_t deadline = steadyNowNs() + timeoutMs * kMs;
    for (;;) {
      while (auto m = binary.next()) {
        if (match(*m)) return Wait::Got;
        if (auto* sf = std::get_if<msg::SampleFrame>(&m->payload); sf && streamingStarted) publish(sf->sample);
        if (auto* e = std::get_if<msg::Error>(&m->payload)) handleDeviceError(*e);
      }
      syncCounters();
      if (stopping()) return Wait::Failed;
      const int64_t left = deadline - steadyNowNs();
      if (left <= 0) return Wait::Timeout;
      if (!pump(static_cast<int>((left + kMs - 1) / kMs))) return Wait::Failed;
    }
  }

  // Sends a command and waits for its answer (matching type, and sequence unless it is a Sample), retrying.
  // nullopt when unanswered after every attempt or the transport failed (`failed` tells which).
  std::optional<Message> command(Payload payload, MessageType answer, bool& failed) {
    failed = false;
    for (int attempt = 0; attempt < std::max(1, o.commandAttempts); ++attempt) {
      const uint32_t seq = commandSequence++;
      if (!send(Message{seq, 0, payload})) {
        failed = true;
        return std::nullopt;
      }
      std::optional<Message> got;
      const Wait w = waitFor(o.replyTimeoutMs, [&](const Message& m) {
        const bool isReply = (m.flags & kFlagReply) != 0;
        if (!isReply) return false;
        if (m.type() == MessageType::Error && m.sequence == seq) {
          got = m;
          return true;
        }
        if (m.type() != answer) return false;
        if (answer != MessageType::Sample && m.sequence != seq) return false;
        got = m;
        return true;
      });
      if (w == Wait::Got) return got;
      if (w == Wait::Failed) {
        failed = true;
        return std::nullopt;
      }
      bump(s.counters_.timeouts);
      // A frame that has not completed by now never will (in poll mode nothing more comes): rescan behind it.
      binary.resync();
    }
    return std::nullopt;
  }

  // HELLO (waiting for the boot announcement first), GET_INFO, then START_STREAM in stream mode. False: lost.
  bool handshakeBinary() {
    s.setState(ConnectionState::WaitingForHello);
    streamingStarted = false;
    std::optional<DeviceInfo> info;
    Wait w = waitFor(o.bootWaitMs, [&](const Message& m) {
      if (auto* h = std::get_if<msg::Hello>(&m.payload)) info = h->info;
      return info.has_value();
    });
    flushTextLine();
    if (w == Wait::Failed) return false;
    // A HELLO unasked after a loss: the device rebooted (on the first open an Arduino always does).
    if (info && everConnected) bump(s.counters_.deviceResets);
    bool failed = false;
    if (!info) {
      auto hello = command(msg::HostHello{}, MessageType::Hello, failed);
      if (hello) {
        if (auto* h = std::get_if<msg::Hello>(&hello->payload)) info = h->info;
      }
      if (!info) {
        if (!failed) s.setError("no HELLO from the device (is it an IMPS armature? try protocol=lines)");
        return false;
      }
    }
    // GET_INFO is the authoritative description; HELLO's copy is the fallback.
    if (auto reply = command(msg::GetInfo{}, MessageType::Info, failed)) {
      if (auto* i = std::get_if<msg::Info>(&reply->payload)) info = i->info;
    } else if (failed) {
      return false;
    }
    {
      std::lock_guard lock(s.mutex_);
      s.info_ = info;
    }
    if (o.mode == AcquisitionMode::Stream) {
      const uint16_t rate = o.rateHz ? o.rateHz : 100;
      auto reply = command(msg::StartStream{rate}, MessageType::Ack, failed);
      if (!reply) {
        if (!failed) s.setError("the device did not acknowledge START_STREAM");
        return false;
      }
      if (auto* e = std::get_if<msg::Error>(&reply->payload)) {
        handleDeviceError(*e);
        return false;
      }
    }
    streamingStarted = true;
    return true;
  }

  // Streams or polls until the connection is lost or stop() is called.
  End runBinary() {
    for (;;) {
      if (!handshakeBinary()) return stopping() ? End::Stopped : End::Lost;
      connected();
      bool rehandshake = false;
      int64_t nextPoll = steadyNowNs();
      while (!rehandshake) {
        if (stopping()) return End::Stopped;
        if (o.mode == AcquisitionMode::Poll) {
          if (o.rateHz) {
            const int64_t wait = nextPoll - steadyNowNs();
            if (wait > 0 && !pump(static_cast<int>(wait / kMs) + 1)) return End::Lost;
            nextPoll = std::max(nextPoll + 1'000'000'000 / o.rateHz, steadyNowNs() - 100 * kMs);
          }
          bool failed = false;
          auto reply = command(msg::Poll{}, MessageType::Sample, failed);
          if (failed) return stopping() ? End::Stopped : End::Lost;
          if (!reply) {
            if (++consecutiveTimeouts >= o.timeoutsBeforeLost) {
              s.setError("the device stopped answering POLL");
              return End::Lost;
            }
            continue;
          }
          if (auto* sf = std::get_if<msg::SampleFrame>(&reply->payload)) publish(sf->sample);
          else if (auto* e = std::get_if<msg::Error>(&reply->payload)) handleDeviceError(*e);
          syncCounters();
          continue;
        }
        // Stream mode: everything arriving is handled in waitFor; a HELLO means the device rebooted.
        const Wait w = waitFor(o.sampleTimeoutMs, [&](const Message& m) {
          return m.type() == MessageType::Hello && (m.flags & kFlagReply) == 0;
        });
        if (w == Wait::Failed) return stopping() ? End::Stopped : End::Lost;
        if (w == Wait::Got) {
          bump(s.counters_.deviceResets);
          binary.reset();
          rehandshake = true;
          continue;
        }
        // A whole sampleTimeout without a HELLO: were there samples? waitFor only returns on timeout.
        if (steadyNowNs() - lastSampleNs >= o.sampleTimeoutMs * kMs) {
          bump(s.counters_.timeouts);
          binary.resync();
          if (++consecutiveTimeouts >= o.timeoutsBeforeLost) {
            s.setError("no samples for " + std::to_string(o.sampleTimeoutMs * o.timeoutsBeforeLost) + " ms");
            return End::Lost;
          }
          bool failed = false;
          auto reply = command(msg::StartStream{o.rateHz ? o.rateHz : uint16_t{100}}, MessageType::Ack, failed);
          if (failed) return stopping() ? End::Stopped : End::Lost;
          lastSampleNs = steadyNowNs();
        }
      }
    }
  }

  // ---- Line protocol

  End runLines() {
    s.setState(ConnectionState::WaitingForHello);
    int64_t lastSample = steadyNowNs();
    bool haveSample = false;
    for (;;) {
      if (stopping()) return End::Stopped;
      if (!pump(o.ioWaitMs)) return End::Lost;
      while (auto sample = lines.next()) {
        if (!haveSample) {
          haveSample = true;
          DeviceInfo info;
          info.name = lines.banner().empty() ? "line-protocol armature" : lines.banner().front();
          info.channelCount = sample->channelCount;
          info.bitsPerChannel = o.lineBitsPerChannel;
          for (int i = 0; i < info.channelCount; ++i) info.channelNames.push_back("ch" + std::to_string(i));
          info.hasDeviceTimestamp = sample->deviceTimeNs != 0;
          layoutChannels = info.channelCount;
          {
            std::lock_guard lock(s.mutex_);
            s.info_ = info;
            s.banner_ = lines.banner();
          }
          connected();
        }
        if (sample->channelCount != layoutChannels) followLayout(sample->channelCount);
        publish(*sample);
        lastSample = steadyNowNs();
      }
      syncCounters();
      if (silenceLost(lastSample, haveSample, "sample lines")) return End::Lost;
    }
  }

  // The line decoder re-locked to a new channel count: the description follows before its first sample is
  // published, so a recorder that sees the new count finds it in deviceInfo().
  int layoutChannels = 0;
  void followLayout(int channels) {
    layoutChannels = channels;
    bump(s.counters_.layoutChanges);
    std::lock_guard lock(s.mutex_);
    if (!s.info_) return;
    s.info_->channelCount = channels;
    s.info_->channelNames.clear();
    for (int i = 0; i < channels; ++i) s.info_->channelNames.push_back("ch" + std::to_string(i));
  }

  // Stream protocols without a handshake (lines, HID reports): before the first sample the device may take a while
  // to boot; afterwards each sampleTimeoutMs of silence is a timeout, and timeoutsBeforeLost in a row lose the
  // connection. `lastSample` is the last sample's time (restarted at each timeout). True when lost.
  bool silenceLost(int64_t& lastSample, bool haveSample, const char* what) {
    const int64_t limit = (haveSample ? o.sampleTimeoutMs : o.bootWaitMs + o.sampleTimeoutMs) * kMs;
    if (steadyNowNs() - lastSample < limit) return false;
    bump(s.counters_.timeouts);
    lastSample = steadyNowNs();
    if (++consecutiveTimeouts < o.timeoutsBeforeLost) return false;
    s.setError(cat("no ", what, " for ", o.sampleTimeoutMs * o.timeoutsBeforeLost, " ms"));
    return true;
  }

  // ---- HID input reports

  // No handshake: the transport read the description and layout when it opened. Streaming from the first
  // sample on; silence is a timeout as for the line protocol.
  End runHid() {
    const HidDeviceDescription* d = transport->hidDescription();
    if (!d) {
      s.setError("internal: HID reports need a HID transport (hid: spec)");
      return End::Lost;
    }
    // The same device back (same layout): keep sequence tracking so reports lost while away count as dropped.
    if (!(hid.layout() == d->layout)) hid.setLayout(d->layout);
    {
      std::lock_guard lock(s.mutex_);
      s.info_ = d->info;
    }
    s.setState(ConnectionState::WaitingForHello);
    int64_t lastSample = steadyNowNs();
    for (;;) {
      if (stopping()) return End::Stopped;
      const uint64_t before = s.counters_.samples.load(std::memory_order_relaxed);
      if (!pump(o.ioWaitMs)) return End::Lost;
      syncCounters();
      if (s.counters_.samples.load(std::memory_order_relaxed) != before) lastSample = steadyNowNs();
      if (silenceLost(lastSample, s.state() == ConnectionState::Streaming, "HID input reports")) return End::Lost;
    }
  }

  bool everConnected = false;
  void connected() {
    consecutiveTimeouts = 0;
    lastSampleNs = steadyNowNs();
    bump(s.counters_.connections);
    if (everConnected) bump(s.counters_.reconnects);
    everConnected = true;
    s.setState(ConnectionState::Streaming);
  }
};

DeviceSession::DeviceSession(TransportOpener opener, PoseMailbox& mailbox, DeviceSessionOptions options)
    : opener_(std::move(opener)), mailbox_(mailbox), options_(std::move(options)) {}

DeviceSession::~DeviceSession() { stop(); }

void DeviceSession::start() {
  if (thread_.joinable()) return;
  stopRequested_.store(false);
  thread_ = std::thread([this] { run(); });
}

void DeviceSession::stop() {
  if (!thread_.joinable()) return;
  stopRequested_.store(true);
  thread_.join();
  setState(ConnectionState::Disconnected);
}

void DeviceSession::setState(ConnectionState s) {
  {
    std::lock_guard lock(mutex_);
    state_.store(s, std::memory_order_release);
  }
  stateChanged_.notify_all();
}

void DeviceSession::setError(std::string message) {
  std::lock_guard lock(mutex_);
  lastError_ = std::move(message);
}

void DeviceSession::run() {
  Io io(*this);
  bool wasConnected = false;
  while (!stopRequested_.load()) {
    // ---- Open (or reopen) the transport.
    setState(wasConnected ? ConnectionState::Reconnecting : ConnectionState::Opening);
    auto transport = opener_();
    if (!transport) {
      bump(counters_.openFailures);
      setError(errorText(transport.error()));
      if (wasConnected) setState(ConnectionState::Lost);
      const int64_t until = steadyNowNs() + options_.reconnectIntervalMs * kMs;
      while (!stopRequested_.load() && steadyNowNs() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    io.transport = std::move(*transport);
    {
      std::lock_guard lock(mutex_);
      warnings_ = io.transport->warnings();
      banner_.clear();
    }
    // A fresh connection: nothing from before may join what comes now. Sequence tracking goes on (samples lost
    // while disconnected are counted) unless the device says HELLO unasked: it rebooted.
    io.binary.discard();
    io.lines.reset();
    io.textBeforeHello.clear();
    io.consecutiveTimeouts = 0;

    const End end = options_.protocol == WireProtocol::Binary       ? io.runBinary()
                    : options_.protocol == WireProtocol::HidReports ? io.runHid()
                                                                    : io.runLines();
    io.syncCounters();
    if (end == End::Stopped) {
      if (options_.protocol == WireProtocol::Binary && io.streamingStarted &&
          options_.mode == AcquisitionMode::Stream)
        io.send(Message{io.commandSequence++, 0, msg::StopStream{}});
      io.transport.reset();
      break;
    }
    // ---- Lost: keep the last pose (the mailbox keeps it), close, and retry after a pause.
    io.transport.reset();
    wasConnected = wasConnected || io.everConnected;
    setState(ConnectionState::Lost);
    const int64_t until = steadyNowNs() + options_.reconnectIntervalMs * kMs;
    while (!stopRequested_.load() && steadyNowNs() < until) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  setState(ConnectionState::Disconnected);
}

DeviceSessionStats DeviceSession::stats() const {
  DeviceSessionStats out;
  auto get = [](const std::atomic<uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  out.state = state();
  out.bytesReceived = get(counters_.bytesReceived);
  out.samples = get(counters_.samples);
  out.garbageBytes = get(counters_.garbageBytes);
  out.crcErrors = get(counters_.crcErrors);
  out.malformedFrames = get(counters_.malformedFrames);
  out.unknownTypes = get(counters_.unknownTypes);
  out.unsupportedVersions = get(counters_.unsupportedVersions);
  out.oversizeFrames = get(counters_.oversizeFrames);
  out.truncatedFrames = get(counters_.truncatedFrames);
  out.parseErrors = get(counters_.parseErrors);
  out.samplesDropped = get(counters_.samplesDropped);
  out.duplicateSamples = get(counters_.duplicateSamples);
  out.sequenceResets = get(counters_.sequenceResets);
  out.timeouts = get(counters_.timeouts);
  out.deviceErrors = get(counters_.deviceErrors);
  out.deviceResets = get(counters_.deviceResets);
  out.layoutChanges = get(counters_.layoutChanges);
  out.connections = get(counters_.connections);
  out.reconnects = get(counters_.reconnects);
  out.openFailures = get(counters_.openFailures);
  return out;
}

std::vector<NamedCounter> namedCounters(const DeviceSessionStats& st) {
  return {
      {"samplesDropped", "dropped by the device link", st.samplesDropped},
      {"duplicateSamples", "repeated samples (stored once)", st.duplicateSamples},
      {"timeouts", "timeouts", st.timeouts},
      {"reconnects", "reconnects", st.reconnects},
      {"deviceResets", "device reboots", st.deviceResets},
      {"sequenceResets", "sequence restarts without a reboot", st.sequenceResets},
      {"crcErrors", "CRC errors", st.crcErrors},
      {"malformedFrames", "malformed frames", st.malformedFrames},
      {"unknownTypes", "frames of unknown type", st.unknownTypes},
      {"unsupportedVersions", "frames of another protocol version", st.unsupportedVersions},
      {"oversizeFrames", "oversize frames", st.oversizeFrames},
      {"truncatedFrames", "frames that never completed", st.truncatedFrames},
      {"garbageBytes", "garbage bytes", st.garbageBytes},
      {"parseErrors", "line parse errors", st.parseErrors},
      {"layoutChanges", "channel-count changes", st.layoutChanges},
      {"deviceErrors", "device ERROR reports", st.deviceErrors},
      {"openFailures", "failed opens", st.openFailures},
  };
}

const char* counterLabel(std::string_view name) {
  for (const NamedCounter& c : namedCounters({}))
    if (name == c.name) return c.label;
  return nullptr;
}

std::optional<DeviceInfo> DeviceSession::deviceInfo() const {
  std::lock_guard lock(mutex_);
  return info_;
}
std::string DeviceSession::lastError() const {
  std::lock_guard lock(mutex_);
  return lastError_;
}
std::vector<std::string> DeviceSession::banner() const {
  std::lock_guard lock(mutex_);
  return banner_;
}
std::vector<std::string> DeviceSession::warnings() const {
  std::lock_guard lock(mutex_);
  return warnings_;
}

bool DeviceSession::waitForState(ConnectionState wanted, int timeoutMs) const {
  std::unique_lock lock(mutex_);
  return stateChanged_.wait_for(lock, std::chrono::milliseconds(timeoutMs), [&] { return state() == wanted; });
}

}  // namespace imps::drivers
