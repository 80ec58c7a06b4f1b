// SPDX-License-Identifier: MIT
// The simulated armature: one device model that plays a pose stream (generated motion or recorded samples) and
// speaks the drivers' wire protocols from the device side, with optional faults (noise, dropouts, garbage,
// corrupted frames, a boot banner, an unplug). Served in-process (SimulatedTransport, the `sim:` device spec) or
// on a pseudo-terminal master (ArmatureFdServer: a `--pty` or a umockdev-mocked /dev/ttyACM0).
#pragma once

#include <atomic>
#include <cstdint>
#include <expected>
#include <functional>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "drivers/binary_protocol.h"
#include "drivers/byte_transport.h"
#include "drivers/device_spec.h"
#include "drivers/sample.h"
#include "sim/session_file.h"

namespace imps::sim {

// Generated motion (docs/devices.md, "The simulator"). Angles are counts from mid-scale, 2^bits counts per turn,
// so mid-scale is the calibration pose of the bundled calibration (examples/simple_biped.calibration.json).
enum class ArmatureMotion : uint8_t {
  // A waving performance of the 32-channel biped armature (channel layout of examples/simple_biped.rig.json): the
  // right arm raised and waving, the left arm at the side, a gentle sway; every channel stays within that rig
  // map's limits. Channels beyond 32 swing ±10°.
  Wave,
  Still,  // every channel at mid-scale: the calibration pose, held (calibrate against it)
  Sweep,  // every channel swings over 10%..90% of its range, phase-shifted by channel (a stress test, not a pose)
};

// "wave", "still", "sweep".
const char* toString(ArmatureMotion motion);

// What the device is and how it misbehaves. Times are nanoseconds since the device powered on.
struct ArmatureOptions {
  drivers::DeviceInfo info = defaultInfo(32, 12);
  drivers::WireProtocol protocol = drivers::WireProtocol::Binary;
  // Poses: these samples' counts in order (looping when `loop`), or, when empty, generated `motion` repeating
  // every motionPeriodS.
  std::vector<drivers::Sample> recorded;
  bool loop = true;
  ArmatureMotion motion = ArmatureMotion::Wave;
  double motionPeriodS = 2.0;
  // Lines per second (line protocol), or the rate when streamAtBoot (binary).
  double rateHz = 100;
  bool streamAtBoot = false;    // binary: start streaming without waiting for START_STREAM
  uint16_t maxRateHz = 2000;    // START_STREAM above this is refused with ERROR code 3
  bool deviceTimestamps = true; // binary: samples carry device time; lines: print `t=` in µs
  bool channelFlags = false;    // binary: samples carry per-channel flags (all valid)
  double noiseCounts = 0;       // uniform noise of ± this many counts on every reading
  double dropoutProbability = 0;   // a sample is taken (its sequence number used) but never sent
  double garbageProbability = 0;   // before a sample, a burst of garbageBurstBytes random bytes
  size_t garbageBurstBytes = 16;
  double corruptProbability = 0;   // one byte of a sample frame/line is flipped
  std::vector<std::string> bootBanner;  // text lines printed at boot (before HELLO / before the first line)
  int64_t bootDelayNs = 0;              // silence after power-on (an Arduino's bootloader)
  int64_t unplugAtNs = -1;              // the device vanishes at this time after its first power-on (-1: never)
  int64_t replugAfterNs = -1;           // ...and comes back this long after vanishing (-1: never)
  uint64_t seed = 1;                    // for noise, dropouts, garbage, corruption: same seed, same bytes

  // A DeviceInfo "IMPS Simulated Monkey" with `channels` channels of `bits` bits and device timestamps.
  static drivers::DeviceInfo defaultInfo(int channels, int bits);
};

// Parses the `sim:` part of a device spec into options: spec.path (a session file to play; "" = generated motion),
// spec.protocol, spec.rateHz and the simulator keys (kSimKeys): channels, bits, motion (wave, still, sweep),
// period_s, noise, dropout, garbage, corrupt, banner (text; `|` separates lines), boot_ms, unplug_ms, replug_ms,
// stream_at_boot (0/1), timestamps (0/1), seed. Errors are diagnostics: a bad key gives one at "spec" naming the
// key ("spec: error: sim key 'x': …"; an unknown key lists every key a sim: spec takes, the spec's own (protocol,
// mode, rate) included); a session file that cannot be read or has no samples gives the reader's, at its path.
std::expected<ArmatureOptions, Diagnostics> armatureOptionsFromSpec(const drivers::DeviceSpec& spec);
// Every key a `sim:` spec takes, comma-separated, as the unknown-key error lists them.
extern const char* const kSimKeys;

struct ArmatureStats {
  uint64_t samplesTaken = 0;    // sequence numbers used (sent + dropped)
  uint64_t samplesSent = 0;
  uint64_t samplesDropped = 0;  // dropouts
  uint64_t garbageBytes = 0;
  uint64_t samplesCorrupted = 0;
  uint64_t commands = 0;        // host commands decoded
  uint64_t commandsIgnored = 0; // commands during boot (the bootloader does not listen)
  uint64_t bytesSent = 0;
  uint64_t powerOns = 0;
};

// The device model, driven by explicit times so tests are deterministic. Not thread-safe: one thread drives it.
class SimulatedArmature {
 public:
  explicit SimulatedArmature(ArmatureOptions options);

  // (Re)boots the device at host time nowNs: sequence numbers restart at 0, streaming stops (unless
  // streamAtBoot), the banner and HELLO are sent after bootDelayNs.
  void powerOn(int64_t nowNs);
  // Host → device bytes (binary protocol commands); answers go out with the next produce(). Ignored by line
  // devices and while booting.
  void receive(std::span<const uint8_t> bytes, int64_t nowNs);
  // Appends to `out` every byte the device sends up to nowNs (boot output, answers, samples due by then).
  void produce(int64_t nowNs, std::vector<uint8_t>& out);
  // The next time produce() would have something new (INT64_MAX when idle until a command arrives).
  int64_t nextDueNs() const;
  // Whether the device is absent at nowNs (unplugAtNs / replugAfterNs, relative to the first power-on).
  bool unplugged(int64_t nowNs) const;
  bool poweredOn() const { return powered_; }
  bool streaming() const { return streaming_; }

  // The reading of sample number `index` at device time `deviceTimeNs`, before noise.
  drivers::Sample poseAt(uint64_t index, int64_t deviceTimeNs) const;
  const ArmatureStats& stats() const { return stats_; }
  const ArmatureOptions& options() const { return options_; }

 private:
  void emitSample(int64_t deviceTimeNs, bool reply, std::vector<uint8_t>& out);
  void emitMessage(const drivers::Message& m, std::vector<uint8_t>& out);
  void emitDueSamples(int64_t nowNs, std::vector<uint8_t>& out);
  void answer(const drivers::Message& command);

  ArmatureOptions options_;
  std::mt19937_64 rng_;
  drivers::BinaryDecoder commands_;
  std::vector<uint8_t> pendingReplies_;
  std::vector<drivers::Message> pendingPolls_;  // POLLs to answer with a sample at the next produce()
  bool powered_ = false;
  bool booted_ = false;
  int64_t firstPowerOnNs_ = -1;
  int64_t powerOnNs_ = 0;
  bool streaming_ = false;
  double streamRateHz_ = 0;
  int64_t streamStartNs_ = 0;
  uint64_t streamIndex_ = 0;  // samples emitted since streamStartNs_
  uint64_t nextSequence_ = 0;
  ArmatureStats stats_;
};

// In-process transport (the `sim:` device spec): a ByteTransport whose far end is a SimulatedArmature on a Clock.
// read() sleeps on the clock until bytes are due (at most its timeout); write() goes to the armature. After the
// unplug time every call fails, as a vanished serial port does. One thread at a time, like every transport.
class SimulatedTransport final : public drivers::ByteTransport {
 public:
  // `armature` is shared with the opener (it persists across reconnects, as a physical device does).
  SimulatedTransport(std::shared_ptr<SimulatedArmature> armature, Clock& clock);
  // Errors name "sim" (errorText: "sim: error: the device was unplugged").
  IoResult<size_t> read(std::span<uint8_t> out, int timeoutMs) override;
  IoResult<void> write(std::span<const uint8_t> bytes, int timeoutMs) override;
  std::string description() const override;

 private:
  std::shared_ptr<SimulatedArmature> armature_;
  Clock& clock_;
  std::vector<uint8_t> pending_;
  size_t pendingPos_ = 0;
};

// A TransportOpener for the `sim:` spec: every open powers the armature on again (an Arduino reboots when its
// port opens); opening fails while the armature is unplugged. The clock must outlive the opener.
drivers::TransportOpener simulatedOpener(ArmatureOptions options, Clock& clock);

// Serves an armature on the master end of a pseudo-terminal (a `--pty`, or umockdev's /dev/ttyACM0) from its own
// thread: host bytes read from the master go to receive(), produce() output is written to it. Output the host
// does not read is buffered up to 256 KiB, then dropped (counted), as a UART overruns. At the unplug time the
// server stops serving and calls onUnplug (e.g. remove the umockdev device); at replug it calls onReplug, which
// returns the new master fd (or -1 to stay unplugged), and powers the armature on again.
class ArmatureFdServer {
 public:
  struct Hooks {
    std::function<void()> onUnplug;
    std::function<int()> onReplug;
  };
  // Takes no ownership of masterFd (the caller closes it after stop()). The clock must be thread-safe
  // (SteadyClock); the armature is owned.
  ArmatureFdServer(SimulatedArmature armature, int masterFd, Clock& clock, Hooks hooks = {});
  ~ArmatureFdServer();  // stop()
  ArmatureFdServer(const ArmatureFdServer&) = delete;
  ArmatureFdServer& operator=(const ArmatureFdServer&) = delete;

  void start();  // powers the armature on and starts serving
  void stop();
  // Copies of the armature's counters, safe from any thread.
  uint64_t samplesSent() const { return samplesSent_.load(std::memory_order_relaxed); }
  uint64_t bytesDropped() const { return bytesDropped_.load(std::memory_order_relaxed); }
  uint64_t powerOns() const { return powerOns_.load(std::memory_order_relaxed); }
  bool unplugged() const { return unplugged_.load(std::memory_order_relaxed); }

 private:
  void run();

  SimulatedArmature armature_;
  int fd_;
  Clock& clock_;
  Hooks hooks_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> samplesSent_{0}, bytesDropped_{0}, powerOns_{0};
  std::atomic<bool> unplugged_{false};
};

}  // namespace imps::sim
