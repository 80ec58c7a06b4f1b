// SPDX-License-Identifier: MIT
// The simulated armature: boot, command answers, the sample schedule, fault injection, and its two servers.
#include "sim/simulated_armature.h"

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <numbers>
#include <type_traits>

namespace imps::sim {

using drivers::Message;
using drivers::MessageType;
using drivers::WireProtocol;
namespace msg = drivers::msg;

drivers::DeviceInfo ArmatureOptions::defaultInfo(int channels, int bits) {
  drivers::DeviceInfo info;
  info.name = "IMPS Simulated Monkey";
  info.serialNumber = "SIM0001";
  info.firmwareVersion = "sim-1";
  info.channelCount = channels;
  info.bitsPerChannel = bits;
  for (int i = 0; i < channels; ++i) info.channelNames.push_back("ch" + std::to_string(i));
  info.hasDeviceTimestamp = true;
  return info;
}

const char* toString(ArmatureMotion motion) {
  switch (motion) {
    case ArmatureMotion::Wave: return "wave";
    case ArmatureMotion::Still: return "still";
    case ArmatureMotion::Sweep: return "sweep";
  }
  return "?";
}

const char* const kSimKeys =
    "protocol, mode, rate, channels, bits, motion, period_s, noise, dropout, garbage, corrupt, banner, boot_ms, "
    "unplug_ms, replug_ms, stream_at_boot, timestamps, seed";

// ---- Spec

namespace {

bool parseMotion(std::string_view s, ArmatureMotion& out) {
  for (ArmatureMotion m : {ArmatureMotion::Wave, ArmatureMotion::Still, ArmatureMotion::Sweep})
    if (s == toString(m)) {
      out = m;
      return true;
    }
  return false;
}

template <class T>
bool parseValue(std::string_view s, T& out) {
  if constexpr (std::is_floating_point_v<T>) {
    std::string copy(s);
    char* end = nullptr;
    out = static_cast<T>(std::strtod(copy.c_str(), &end));
    return !copy.empty() && end == copy.c_str() + copy.size() && std::isfinite(out);
  } else {
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  }
}

}  // namespace

std::expected<ArmatureOptions, Diagnostics> armatureOptionsFromSpec(const drivers::DeviceSpec& spec) {
  ArmatureOptions o;
  o.protocol = spec.protocol;
  if (spec.rateHz) o.rateHz = spec.rateHz;
  int channels = 32, bits = 12;
  auto bad = [](std::string_view key, std::string_view what) {
    Diagnostics d;
    d.error({"spec"}, "sim key '" + std::string(key) + "': " + std::string(what));
    return std::unexpected(std::move(d));
  };
  for (const auto& [key, value] : spec.simParams) {
    bool ok = true;
    int64_t ms = 0;
    int flag = 0;
    if (key == "channels") ok = parseValue(value, channels) && channels >= 1 && channels <= drivers::kMaxChannels;
    else if (key == "bits") ok = parseValue(value, bits) && bits >= 1 && bits <= 32;
    else if (key == "noise") ok = parseValue(value, o.noiseCounts) && o.noiseCounts >= 0;
    else if (key == "dropout")
      ok = parseValue(value, o.dropoutProbability) && o.dropoutProbability >= 0 && o.dropoutProbability <= 1;
    else if (key == "garbage")
      ok = parseValue(value, o.garbageProbability) && o.garbageProbability >= 0 && o.garbageProbability <= 1;
    else if (key == "corrupt")
      ok = parseValue(value, o.corruptProbability) && o.corruptProbability >= 0 && o.corruptProbability <= 1;
    else if (key == "motion") ok = parseMotion(value, o.motion);
    else if (key == "period_s") ok = parseValue(value, o.motionPeriodS) && o.motionPeriodS > 0;
    else if (key == "seed") ok = parseValue(value, o.seed);
    else if (key == "banner") {
      o.bootBanner.clear();
      size_t begin = 0;
      for (;;) {
        const size_t bar = value.find('|', begin);
        o.bootBanner.push_back(value.substr(begin, bar == std::string::npos ? std::string::npos : bar - begin));
        if (bar == std::string::npos) break;
        begin = bar + 1;
      }
    } else if (key == "boot_ms" || key == "unplug_ms" || key == "replug_ms") {
      // At most a year: the value in ns, and the clock times it is added to, stay far inside int64.
      constexpr int64_t kMaxMs = int64_t{365} * 24 * 3600 * 1000;
      ok = parseValue(value, ms) && ms >= 0 && ms <= kMaxMs;
      if (!ok) return bad(key, "bad value '" + value + "': expected milliseconds from 0 to " + std::to_string(kMaxMs) +
                                   " (a year)");
      (key == "boot_ms" ? o.bootDelayNs : key == "unplug_ms" ? o.unplugAtNs : o.replugAfterNs) = ms * 1'000'000;
    } else if (key == "stream_at_boot" || key == "timestamps") {
      ok = parseValue(value, flag) && (flag == 0 || flag == 1);
      (key == "timestamps" ? o.deviceTimestamps : o.streamAtBoot) = flag == 1;
    } else {
      return bad(key, std::string("unknown (known: ") + kSimKeys + ")");
    }
    if (!ok)
      return bad(key, "bad value '" + value + "'" + (key == "motion" ? " (expected wave, still or sweep)" : ""));
  }
  o.info = ArmatureOptions::defaultInfo(channels, bits);
  o.info.hasDeviceTimestamp = o.deviceTimestamps;
  if (!spec.path.empty()) {
    auto session = readSession(spec.path);
    if (!session) return std::unexpected(session.error());
    if (session->devices.empty() || session->samples.empty()) {
      Diagnostics d;
      d.error({spec.path}, "the session has no samples to play");
      return std::unexpected(std::move(d));
    }
    o.info = session->devices.front();
    for (size_t i = 0; i < session->samples.size(); ++i)
      if (session->sampleDevice[i] == 0) o.recorded.push_back(session->samples[i]);
  }
  return o;
}

// ---- Generated motion

namespace {

// One channel of the waving performance: centre + amplitude * sin(harmonic * cycle + phase), in degrees from the
// calibration pose. Channel order and limits are examples/simple_biped.rig.json's.
struct WaveChannel {
  double centre, amplitude, harmonic, phase;
};
constexpr WaveChannel kWave[32] = {
    {0, 2, 1, 0},       // 0  Pelvis x      (limits -45..45)
    {0, 8, 1, 0.5},     // 1  Pelvis y      (-90..90): turn a little towards the wave
    {0, 2, 1, 1.6},     // 2  Pelvis z      (-45..45): weight shift
    {4, 3, 1, 0},       // 3  Spine x       (-30..60)
    {0, 3, 1, 1.6},     // 4  Spine z       (-40..40)
    {0, 4, 1, 0.3},     // 5  Neck x        (-40..50)
    {0, 6, 2, 0},       // 6  Head x        (-40..40): a nod
    {0, 15, 1, 0.8},    // 7  Head y        (-70..70): looks around
    {-8, 3, 1, 0},      // 8  L_Clavicle z  (-15..30): shoulder relaxed
    {-10, 4, 1, 0},     // 9  R_Clavicle z  (-30..15): shoulder up with the raised arm
    {0, 5, 1, 0.4},     // 10 L_UpperArm x  (-90..90)
    {0, 8, 1, 0.9},     // 11 L_UpperArm y  (-120..60)
    {-70, 5, 1, 0},     // 12 L_UpperArm z  (-90..100): arm down at the side
    {0, 5, 1, 0},       // 13 R_UpperArm x  (-90..90)
    {0, 6, 1, 0},       // 14 R_UpperArm y  (-60..120)
    {-55, 8, 1, 1.2},   // 15 R_UpperArm z  (-100..90): arm raised
    {-15, 8, 1, 0.5},   // 16 L_Forearm y   (-150..5): elbow slightly bent
    {45, 30, 2, 0},     // 17 R_Forearm y   (-5..150): the wave, twice a cycle, clear of the head
    {0, 10, 1, 0},      // 18 L_Hand z      (-70..70)
    {0, 25, 2, 0.6},    // 19 R_Hand z      (-70..70): the hand follows the wave
    {0, 4, 1, 0},       // 20 L_Thigh x     (-120..40)
    {0, 2, 1, 0},       // 21 L_Thigh y     (-45..45)
    {3, 2, 1, 1.6},     // 22 L_Thigh z     (-30..60)
    {0, 4, 1, 3.1},     // 23 R_Thigh x     (-120..40)
    {0, 2, 1, 0},       // 24 R_Thigh y     (-45..45)
    {-3, 2, 1, 1.6},    // 25 R_Thigh z     (-60..30)
    {6, 5, 1, 0},       // 26 L_Calf x      (-5..150): knees soft
    {6, 5, 1, 3.1},     // 27 R_Calf x      (-5..150)
    {0, 3, 1, 0},       // 28 L_Foot x      (-45..45)
    {0, 2, 1, 0},       // 29 L_Foot y      (-30..30)
    {0, 3, 1, 3.1},     // 30 R_Foot x      (-45..45)
    {0, 2, 1, 0},       // 31 R_Foot y      (-30..30)
};

double waveDegrees(int channel, double cycle) {
  if (channel >= 32) return 10.0 * std::sin(cycle + 0.7 * channel);
  const WaveChannel& w = kWave[channel];
  return w.centre + w.amplitude * std::sin(w.harmonic * cycle + w.phase);
}

}  // namespace

// ---- The device model

SimulatedArmature::SimulatedArmature(ArmatureOptions options) : options_(std::move(options)), rng_(options_.seed) {}

void SimulatedArmature::powerOn(int64_t nowNs) {
  powered_ = true;
  booted_ = false;
  if (firstPowerOnNs_ < 0) firstPowerOnNs_ = nowNs;
  powerOnNs_ = nowNs;
  streaming_ = false;
  streamIndex_ = 0;
  nextSequence_ = 0;
  commands_.reset();
  pendingReplies_.clear();
  pendingPolls_.clear();
  ++stats_.powerOns;
}

bool SimulatedArmature::unplugged(int64_t nowNs) const {
  if (options_.unplugAtNs < 0 || firstPowerOnNs_ < 0) return false;
  const int64_t gone = firstPowerOnNs_ + options_.unplugAtNs;
  if (nowNs < gone) return false;
  return options_.replugAfterNs < 0 || nowNs < gone + options_.replugAfterNs;
}

drivers::Sample SimulatedArmature::poseAt(uint64_t index, int64_t deviceTimeNs) const {
  drivers::Sample s;
  const int channels = options_.info.channelCount;
  s.channelCount = static_cast<uint16_t>(channels);
  s.sequence = static_cast<uint32_t>(index);
  s.deviceTimeNs = deviceTimeNs;
  const int bits = options_.info.bitsPerChannel;
  const double maxCount = std::ldexp(1.0, bits) - 1;
  if (!options_.recorded.empty()) {
    const size_t n = options_.recorded.size();
    const drivers::Sample& r = options_.recorded[options_.loop ? index % n : std::min<size_t>(index, n - 1)];
    for (int i = 0; i < channels; ++i) {
      s.counts[i] = static_cast<uint32_t>(std::min<double>(r.counts[i], maxCount));
      s.flags[i] = r.flags[i];
    }
    return s;
  }
  const double t = static_cast<double>(deviceTimeNs) * 1e-9;
  const double cycle = 2 * std::numbers::pi * t / options_.motionPeriodS;
  const double countsPerDegree = std::ldexp(1.0, bits) / 360.0;
  for (int i = 0; i < channels; ++i) {
    double counts = std::ldexp(1.0, bits - 1);  // mid-scale: the calibration pose
    if (options_.motion == ArmatureMotion::Sweep)
      counts = maxCount * (0.5 + 0.4 * std::sin(cycle + 0.7 * i));
    else if (options_.motion == ArmatureMotion::Wave)
      counts += countsPerDegree * waveDegrees(i, cycle);
    s.counts[i] = static_cast<uint32_t>(std::clamp(std::round(counts), 0.0, maxCount));
  }
  return s;
}

void SimulatedArmature::emitMessage(const Message& m, std::vector<uint8_t>& out) {
  const size_t before = out.size();
  (void)drivers::appendFrame(m, out);  // the model only builds valid messages
  stats_.bytesSent += out.size() - before;
}

void SimulatedArmature::emitSample(int64_t deviceTimeNs, bool reply, std::vector<uint8_t>& out) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const uint64_t index = nextSequence_++;
  ++stats_.samplesTaken;
  if (options_.dropoutProbability > 0 && unit(rng_) < options_.dropoutProbability) {
    ++stats_.samplesDropped;
    return;
  }
  if (options_.garbageProbability > 0 && unit(rng_) < options_.garbageProbability) {
    for (size_t i = 0; i < options_.garbageBurstBytes; ++i) out.push_back(static_cast<uint8_t>(rng_()));
    stats_.garbageBytes += options_.garbageBurstBytes;
    stats_.bytesSent += options_.garbageBurstBytes;
  }
  drivers::Sample s = poseAt(index, deviceTimeNs);
  if (options_.noiseCounts > 0) {
    const double maxCount = std::ldexp(1.0, options_.info.bitsPerChannel) - 1;
    std::uniform_real_distribution<double> noise(-options_.noiseCounts, options_.noiseCounts);
    for (int i = 0; i < s.channelCount; ++i)
      s.counts[i] = static_cast<uint32_t>(std::clamp(std::round(s.counts[i] + noise(rng_)), 0.0, maxCount));
  }
  const size_t begin = out.size();
  if (options_.protocol == WireProtocol::Binary) {
    s.deviceTimeNs = options_.deviceTimestamps ? deviceTimeNs / 1000 * 1000 : 0;
    emitMessage(drivers::sampleMessage(s, static_cast<uint8_t>(options_.info.bitsPerChannel),
                                       options_.deviceTimestamps, options_.channelFlags,
                                       reply ? drivers::kFlagReply : uint8_t{0}),
                out);
  } else {
    std::string line;
    if (options_.deviceTimestamps) line = "t=" + std::to_string(deviceTimeNs / 1000) + ",";
    for (int i = 0; i < s.channelCount; ++i) {
      line += std::to_string(s.counts[i]);
      line += i + 1 < s.channelCount ? "," : "\r\n";
    }
    out.insert(out.end(), line.begin(), line.end());
    stats_.bytesSent += line.size();
  }
  if (options_.corruptProbability > 0 && unit(rng_) < options_.corruptProbability) {
    const size_t size = out.size() - begin;
    const size_t at =
        begin + static_cast<size_t>(rng_() % (options_.protocol == WireProtocol::Binary ? size : size - 2));
    // Binary: flip one bit (the CRC must catch it). Lines: a letter makes the line malformed, never another number.
    if (options_.protocol == WireProtocol::Binary) out[at] ^= static_cast<uint8_t>(1u << (rng_() % 8));
    else out[at] = 'x';
    ++stats_.samplesCorrupted;
  }
  ++stats_.samplesSent;
}

void SimulatedArmature::receive(std::span<const uint8_t> bytes, int64_t nowNs) {
  if (options_.protocol != WireProtocol::Binary || !powered_ || unplugged(nowNs) || bytes.empty()) return;
  if (!booted_ && nowNs < powerOnNs_ + options_.bootDelayNs) {
    ++stats_.commandsIgnored;
    return;
  }
  // Samples due before these bytes arrived go out first, so a STOP_STREAM cannot swallow them.
  if (booted_) emitDueSamples(nowNs, pendingReplies_);
  commands_.feed(bytes, nowNs);
  while (auto m = commands_.next()) {
    ++stats_.commands;
    const uint32_t seq = m->sequence;
    std::vector<uint8_t>& out = pendingReplies_;
    switch (m->type()) {
      case MessageType::HostHello:
        emitMessage(Message{seq, drivers::kFlagReply, msg::Hello{drivers::kProtocolVersion, options_.info}}, out);
        break;
      case MessageType::GetInfo:
        emitMessage(Message{seq, drivers::kFlagReply, msg::Info{options_.info}}, out);
        break;
      case MessageType::Poll:
        pendingPolls_.push_back(*m);
        break;
      case MessageType::StartStream: {
        const uint16_t rate = std::get<msg::StartStream>(m->payload).rateHz;
        if (rate > options_.maxRateHz) {
          emitMessage(Message{seq, drivers::kFlagReply,
                              msg::Error{MessageType::StartStream, drivers::ErrorCode::BadRate,
                                         "rate above " + std::to_string(options_.maxRateHz) + " Hz"}},
                      out);
          break;
        }
        emitMessage(Message{seq, drivers::kFlagReply, msg::Ack{MessageType::StartStream}}, out);
        streaming_ = true;
        streamRateHz_ = rate;
        streamStartNs_ = nowNs;
        streamIndex_ = 0;
        break;
      }
      case MessageType::StopStream:
        emitMessage(Message{seq, drivers::kFlagReply, msg::Ack{MessageType::StopStream}}, out);
        streaming_ = false;
        break;
      default:
        emitMessage(Message{seq, drivers::kFlagReply,
                            msg::Error{m->type(), drivers::ErrorCode::UnknownCommand, "not a host command"}},
                    out);
    }
  }
}

int64_t SimulatedArmature::nextDueNs() const {
  if (!powered_) return INT64_MAX;
  if (!booted_) return powerOnNs_ + options_.bootDelayNs;
  if (!pendingReplies_.empty() || !pendingPolls_.empty()) return 0;
  if (streaming_)
    return streamStartNs_ + static_cast<int64_t>(std::llround(static_cast<double>(streamIndex_) * 1e9 / streamRateHz_));
  return INT64_MAX;
}

void SimulatedArmature::produce(int64_t nowNs, std::vector<uint8_t>& out) {
  if (!powered_ || unplugged(nowNs)) return;
  // ---- Boot: banner, then HELLO (binary) or the start of the line stream.
  if (!booted_) {
    const int64_t bootDone = powerOnNs_ + options_.bootDelayNs;
    if (nowNs < bootDone) return;
    booted_ = true;
    for (const std::string& line : options_.bootBanner) {
      out.insert(out.end(), line.begin(), line.end());
      out.push_back('\r');
      out.push_back('\n');
      stats_.bytesSent += line.size() + 2;
    }
    if (options_.protocol == WireProtocol::Binary)
      emitMessage(Message{0, 0, msg::Hello{drivers::kProtocolVersion, options_.info}}, out);
    if (options_.protocol == WireProtocol::Lines || options_.streamAtBoot) {
      streaming_ = true;
      streamRateHz_ = options_.rateHz;
      streamStartNs_ = bootDone;
      streamIndex_ = 0;
    }
  }
  // ---- Answers, then polled samples, then the samples due on the stream schedule.
  out.insert(out.end(), pendingReplies_.begin(), pendingReplies_.end());
  pendingReplies_.clear();
  for (size_t i = 0; i < pendingPolls_.size(); ++i) emitSample(nowNs - powerOnNs_, true, out);
  pendingPolls_.clear();
  emitDueSamples(nowNs, out);
}

void SimulatedArmature::emitDueSamples(int64_t nowNs, std::vector<uint8_t>& out) {
  while (streaming_ && streamRateHz_ > 0) {
    const int64_t due =
        streamStartNs_ + static_cast<int64_t>(std::llround(static_cast<double>(streamIndex_) * 1e9 / streamRateHz_));
    if (due > nowNs) break;
    emitSample(due - powerOnNs_, false, out);
    ++streamIndex_;
  }
}

// ---- In-process transport

SimulatedTransport::SimulatedTransport(std::shared_ptr<SimulatedArmature> armature, Clock& clock)
    : armature_(std::move(armature)), clock_(clock) {}

IoResult<size_t> SimulatedTransport::read(std::span<uint8_t> out, int timeoutMs) {
  if (pendingPos_ == pending_.size()) {
    pending_.clear();
    pendingPos_ = 0;
    int64_t now = clock_.nowNs();
    if (armature_->unplugged(now)) return std::unexpected(IoError{"sim", "the device was unplugged", ENODEV});
    armature_->produce(now, pending_);
    if (pending_.empty() && timeoutMs > 0) {
      const int64_t wake = std::min(armature_->nextDueNs(), now + int64_t{timeoutMs} * 1'000'000);
      clock_.sleepUntilNs(std::max(wake, now));
      now = clock_.nowNs();
      if (armature_->unplugged(now)) return std::unexpected(IoError{"sim", "the device was unplugged", ENODEV});
      armature_->produce(now, pending_);
    }
  }
  const size_t n = std::min(out.size(), pending_.size() - pendingPos_);
  std::copy_n(pending_.begin() + static_cast<std::ptrdiff_t>(pendingPos_), n, out.begin());
  pendingPos_ += n;
  return n;
}

IoResult<void> SimulatedTransport::write(std::span<const uint8_t> bytes, int) {
  const int64_t now = clock_.nowNs();
  if (armature_->unplugged(now)) return std::unexpected(IoError{"sim", "the device was unplugged", ENODEV});
  armature_->receive(bytes, now);
  return {};
}

std::string SimulatedTransport::description() const {
  return "simulated armature (" + armature_->options().info.name + ", " +
         std::to_string(armature_->options().info.channelCount) + " channels)";
}

drivers::TransportOpener simulatedOpener(ArmatureOptions options, Clock& clock) {
  auto armature = std::make_shared<SimulatedArmature>(std::move(options));
  return [armature, &clock]() -> IoResult<std::unique_ptr<drivers::ByteTransport>> {
    const int64_t now = clock.nowNs();
    if (armature->unplugged(now)) return std::unexpected(IoError{"sim", "the device is unplugged", ENODEV});
    armature->powerOn(now);
    return std::unique_ptr<drivers::ByteTransport>(new SimulatedTransport(armature, clock));
  };
}

// ---- Pseudo-terminal server

ArmatureFdServer::ArmatureFdServer(SimulatedArmature armature, int masterFd, Clock& clock, Hooks hooks)
    : armature_(std::move(armature)), fd_(masterFd), clock_(clock), hooks_(std::move(hooks)) {}

ArmatureFdServer::~ArmatureFdServer() { stop(); }

void ArmatureFdServer::start() {
  if (thread_.joinable()) return;
  stop_.store(false);
  thread_ = std::thread([this] { run(); });
}

void ArmatureFdServer::stop() {
  if (!thread_.joinable()) return;
  stop_.store(true);
  thread_.join();
}

void ArmatureFdServer::run() {
  constexpr size_t kMaxBuffered = 256 * 1024;
  std::vector<uint8_t> out;
  size_t outPos = 0;
  uint8_t in[1024];
  auto setNonBlocking = [](int fd) {
    if (fd >= 0) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  };
  setNonBlocking(fd_);
  armature_.powerOn(clock_.nowNs());
  powerOns_.store(1, std::memory_order_relaxed);
  while (!stop_.load(std::memory_order_relaxed)) {
    const int64_t now = clock_.nowNs();
    // ---- Unplug and replug.
    if (!unplugged_.load(std::memory_order_relaxed) && armature_.unplugged(now)) {
      unplugged_.store(true, std::memory_order_relaxed);
      out.clear();
      outPos = 0;
      if (hooks_.onUnplug) hooks_.onUnplug();
      fd_ = -1;
    }
    if (unplugged_.load(std::memory_order_relaxed)) {
      if (!armature_.unplugged(now) && hooks_.onReplug) {
        fd_ = hooks_.onReplug();
        if (fd_ >= 0) {
          setNonBlocking(fd_);
          unplugged_.store(false, std::memory_order_relaxed);
          armature_.powerOn(now);
          powerOns_.fetch_add(1, std::memory_order_relaxed);
        }
      }
      clock_.sleepUntilNs(now + 2'000'000);
      continue;
    }
    // ---- Wait for host bytes, room to write, or the next due sample (at most 5 ms, so stop() is prompt).
    const int64_t due = armature_.nextDueNs();
    const int64_t waitNs = std::clamp<int64_t>(due - now, 0, 5'000'000);
    pollfd p{fd_, static_cast<short>(POLLIN | (outPos < out.size() ? POLLOUT : 0)), 0};
    const int ready = ::poll(&p, 1, static_cast<int>((waitNs + 999'999) / 1'000'000));
    if (ready > 0 && (p.revents & POLLIN)) {
      const ssize_t n = ::read(fd_, in, sizeof in);
      if (n > 0) armature_.receive(std::span<const uint8_t>(in, static_cast<size_t>(n)), clock_.nowNs());
      else if (n < 0 && errno == EIO) clock_.sleepUntilNs(clock_.nowNs() + 2'000'000);  // no slave open yet
    } else if (ready > 0 && (p.revents & POLLHUP)) {
      // No process has the terminal open: nothing to serve, do not spin.
      clock_.sleepUntilNs(clock_.nowNs() + 2'000'000);
    }
    armature_.produce(clock_.nowNs(), out);
    samplesSent_.store(armature_.stats().samplesSent, std::memory_order_relaxed);
    // ---- Write what the terminal takes; beyond the buffer limit the oldest bytes are lost (a UART overrun).
    while (outPos < out.size()) {
      const ssize_t n = ::write(fd_, out.data() + outPos, out.size() - outPos);
      if (n <= 0) break;
      outPos += static_cast<size_t>(n);
    }
    if (outPos == out.size()) {
      out.clear();
      outPos = 0;
    } else if (out.size() - outPos > kMaxBuffered) {
      const size_t drop = out.size() - outPos - kMaxBuffered;
      bytesDropped_.fetch_add(drop, std::memory_order_relaxed);
      outPos += drop;
    }
    if (outPos > kMaxBuffered) {
      out.erase(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(outPos));
      outPos = 0;
    }
  }
}

}  // namespace imps::sim
