// SPDX-License-Identifier: MIT
// The whole device path under a sustained 1 kHz × 64-channel stream (issue 4): a simulated armature on a
// pseudo-terminal (served as `puppeteer sim --pty` serves it) → SerialTransport (termios) → the DeviceSession's I/O
// thread → PoseMailbox → a 60 FPS consumer that takes the newest pose and drains the in-order queue each frame.
// Reports drops, memory (RSS) and sample ages as counters; figures and how to read them: docs/devices.md,
// "Performance". Durations: IMPS_SOAK_SECONDS (default 10) and IMPS_AGE_SECONDS (default 5).
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "drivers/device_session.h"
#include "drivers/pose_mailbox.h"
#include "drivers/serial_transport.h"
#include "imps/clock.h"
#include "sim/pseudo_terminal.h"
#include "sim/simulated_armature.h"

namespace {

using namespace imps;
using drivers::Sample;

constexpr int kChannels = 64;
constexpr int kBits = 16;
constexpr uint16_t kRateHz = 1000;
constexpr size_t kQueueCapacity = 8192;  // 8 s at 1 kHz; the consumer drains every frame (16.7 ms)
constexpr size_t kPoses = 4096;          // distinct poses the armature cycles through

double envSeconds(const char* name, double fallback) {
  const char* text = std::getenv(name);
  if (!text || !*text) return fallback;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  return end && *end == '\0' && v > 0 ? v : fallback;
}

// Resident set size of this process in KiB (/proc/self/statm), read without allocating.
int64_t rssKiB() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  char text[128];
  const ssize_t n = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  if (n <= 0) return -1;
  text[n] = '\0';
  long long size = 0, resident = 0;
  if (std::sscanf(text, "%lld %lld", &size, &resident) != 2) return -1;
  return resident * ::sysconf(_SC_PAGESIZE) / 1024;
}

double loadAverage1() {
  double load[1] = {-1};
  return ::getloadavg(load, 1) == 1 ? load[0] : -1;
}

double processCpuSeconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
  return seconds(u.ru_utime) + seconds(u.ru_stime);
}


// The simulator's clock: the steady clock, remembering its first reading and able to stand still.
// ArmatureFdServer powers the armature on at its clock's first reading, and device times count from power-on, so
// firstReadingNs() + Sample::deviceTimeNs is the steady time a sample was due on the device. freeze() stops time
// for the armature (no sample falls due afterwards) while its server keeps writing what it has produced, which
// ends the stream at an exact sample so "sent" and "received" can be compared.
class SoakClock final : public imps::Clock {
 public:
  int64_t nowNs() override {
    const int64_t t = std::min(steadyNowNs(), frozenAt_.load(std::memory_order_acquire));
    if (first_.load(std::memory_order_relaxed) < 0) {
      int64_t unset = -1;
      first_.compare_exchange_strong(unset, t);
    }
    return t;
  }
  // Sleeps for the time left in real time, so a frozen clock never blocks its caller for good.
  void sleepUntilNs(int64_t timeNs) override {
    const int64_t left = timeNs - nowNs();
    if (left > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(left));
  }
  void freeze() { frozenAt_.store(steadyNowNs(), std::memory_order_release); }
  int64_t firstReadingNs() const { return first_.load(std::memory_order_relaxed); }

 private:
  std::atomic<int64_t> first_{-1};
  std::atomic<int64_t> frozenAt_{INT64_MAX};
};

// Latencies at 1 µs resolution up to 65.535 ms, one overflow bucket above, the exact maximum kept. Allocated (and
// touched) once, so recording during the soak never allocates and never grows the resident set.
class LatencyHistogram {
 public:
  void add(int64_t ns) {
    if (ns < 0) {
      ++negatives_;
      ns = 0;
    }
    ++buckets_[std::min<size_t>(static_cast<size_t>(ns / 1000), kBuckets)];
    ++count_;
    max_ = std::max(max_, ns);
  }
  uint64_t count() const { return count_; }
  uint64_t negatives() const { return negatives_; }
  double maxUs() const { return static_cast<double>(max_) * 1e-3; }
  // The q-quantile (0..1) in µs, as the lower edge of its 1 µs bucket (the maximum when it lies in the overflow).
  double quantileUs(double q) const {
    if (count_ == 0) return 0;
    const uint64_t rank = std::max<uint64_t>(1, static_cast<uint64_t>(q * static_cast<double>(count_) + 0.999999));
    uint64_t seen = 0;
    for (size_t b = 0; b < kBuckets; ++b) {
      seen += buckets_[b];
      if (seen >= rank) return static_cast<double>(b);
    }
    return maxUs();
  }

 private:
  static constexpr size_t kBuckets = 65536;
  std::vector<uint32_t> buckets_ = std::vector<uint32_t>(kBuckets + 1, 0);
  uint64_t count_ = 0, negatives_ = 0;
  int64_t max_ = 0;
};

// A fixed table of poses with every bit of every 16-bit channel in play, and some channels flagged, so the consumer
// can check each received sample byte for byte against poses[sequence % kPoses].
std::vector<Sample> makePoses() {
  std::vector<Sample> poses(kPoses);
  uint64_t x = 0x9E3779B97F4A7C15ull;
  for (size_t q = 0; q < kPoses; ++q) {
    poses[q].channelCount = kChannels;
    for (int c = 0; c < kChannels; ++c) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      poses[q].counts[c] = static_cast<uint32_t>(x >> 48);
      poses[q].flags[c] = (q + static_cast<size_t>(c)) % 29 == 0   ? drivers::ChannelFlag::Outlier
                          : (q + static_cast<size_t>(c)) % 31 == 0 ? drivers::ChannelFlag::NotConnected
                                                                   : drivers::ChannelFlag::Valid;
    }
  }
  return poses;
}

struct StreamRun {
  std::string error;  // why the pipeline could not run at all ("" when it ran)
  double seconds = 0, warmupSeconds = 0;
  // Samples.
  uint64_t sent = 0, received = 0;  // by the armature; drained by the consumer, in order
  uint64_t consumerGaps = 0, outOfOrder = 0, valueMismatches = 0;
  drivers::DeviceSessionStats session;
  drivers::PoseMailboxStats mailbox;
  uint64_t uartOverrunBytes = 0;  // bytes the simulator's pty server had to discard (the host fell behind)
  bool drainedToTheEnd = false;   // after the stream was stopped, everything sent reached the consumer
  // Memory, KiB; growth per minute after warm-up by least squares over one reading per second.
  int64_t rssBefore = 0, rssStart = 0, rssWarm = 0, rssEnd = 0, rssMax = 0;
  double rssSlopeKiBPerMin = 0;
  // Ages (recorded after warm-up only).
  LatencyHistogram transport;    // device due time -> arrival (host read): the transport (incl. the simulator's timer)
  LatencyHistogram newestAge;    // arrival -> taken by the frame loop as the newest pose
  LatencyHistogram newestTotal;  // device due time -> taken as the newest pose
  LatencyHistogram queueAge;     // arrival -> drained by the consumer
  uint64_t frames = 0, framesWithoutNewPose = 0;
  double cpuPercent = 0, load1Start = 0, load1End = 0;

  // Sent but never delivered to the consumer (the breakdown above says where they went).
  uint64_t dropped() const { return sent > received ? sent - received : 0; }
  // The soak's property: every sample sent arrived once, in order, with no loss anywhere on the way.
  bool zeroDrops() const {
    return dropped() == 0 && session.samplesDropped == 0 && mailbox.queueOverflows == 0 && consumerGaps == 0 &&
           outOfOrder == 0 && uartOverrunBytes == 0 && drainedToTheEnd;
  }
};

// Runs the pipeline for `seconds` (plus start-up and a final drain) with a consumer taking the newest pose and
// draining the queue every 1/frameHz seconds. Ages and the memory slope count from `warmupSeconds` on.
void runStream(StreamRun& r, double seconds, double warmupSeconds, double frameHz) {
  r.seconds = seconds;
  r.warmupSeconds = warmupSeconds;
  const std::vector<Sample> poses = makePoses();
  std::vector<Sample> batch(kQueueCapacity);  // touched now, so a large drain later does not grow the RSS
  batch.clear();
  r.rssBefore = rssKiB();

  // ---- The armature on a pseudo-terminal, as `puppeteer sim --pty` serves it.
  auto pty = sim::PseudoTerminal::open();
  if (!pty) {
    r.error = pty.error().str();
    return;
  }
  sim::ArmatureOptions ao;
  ao.info = sim::ArmatureOptions::defaultInfo(kChannels, kBits);
  ao.recorded = poses;
  ao.deviceTimestamps = true;
  ao.channelFlags = true;
  SoakClock clock;
  auto server = std::make_unique<sim::ArmatureFdServer>(sim::SimulatedArmature(std::move(ao)), pty->master(), clock);
  server->start();

  // ---- The drivers on the slave end.
  drivers::PoseMailboxOptions mo;
  mo.queueCapacity = kQueueCapacity;
  drivers::PoseMailbox mailbox(mo);
  drivers::DeviceSessionOptions so;
  so.rateHz = kRateHz;
  so.bootWaitMs = 300;  // the pty server's boot HELLO went out before the port was opened: ask at once
  auto session = std::make_unique<drivers::DeviceSession>(drivers::serialOpener(pty->slavePath()), mailbox, so);
  session->start();
  if (!session->waitForState(drivers::ConnectionState::Streaming, 10000)) {
    r.error = "the session never reached streaming: " + session->lastError();
    session.reset();
    server.reset();
    return;
  }
  const int64_t deviceEpoch = clock.firstReadingNs();

  // ---- The consumer: one frame loop that takes the newest pose and drains the queue (as a recorder would).
  Sample newest;
  uint64_t expected = 0;  // the next sequence number (the armature counts from 0 at power-on)
  bool measuring = false;
  auto consume = [&](int64_t frameNs) {
    if (frameNs > 0) ++r.frames;
    if (mailbox.latest(newest)) {
      const int64_t take = steadyNowNs();
      if (measuring) {
        r.newestAge.add(take - newest.arrivalTimeNs);
        r.newestTotal.add(take - (deviceEpoch + newest.deviceTimeNs));
      }
    } else if (frameNs > 0) {
      ++r.framesWithoutNewPose;
    }
    batch.clear();
    mailbox.drain(batch, kQueueCapacity);
    const int64_t take = steadyNowNs();
    for (const Sample& s : batch) {
      if (s.sequence != static_cast<uint32_t>(expected)) {
        if (s.sequence > expected) r.consumerGaps += s.sequence - expected;
        else ++r.outOfOrder;
      }
      expected = static_cast<uint64_t>(s.sequence) + 1;
      const Sample& want = poses[s.sequence % kPoses];
      const bool same = s.channelCount == kChannels &&
                        std::equal(s.counts.begin(), s.counts.begin() + kChannels, want.counts.begin()) &&
                        std::equal(s.flags.begin(), s.flags.begin() + kChannels, want.flags.begin());
      if (!same) ++r.valueMismatches;
      if (measuring) {
        r.transport.add(s.arrivalTimeNs - (deviceEpoch + s.deviceTimeNs));
        r.queueAge.add(take - s.arrivalTimeNs);
      }
    }
    r.received += batch.size();
  };

  const int64_t framePeriod = static_cast<int64_t>(1e9 / frameHz);
  const int64_t t0 = steadyNowNs();
  const int64_t warmEnd = t0 + static_cast<int64_t>(warmupSeconds * 1e9);
  const int64_t end = t0 + static_cast<int64_t>(seconds * 1e9);
  r.rssStart = rssKiB();
  r.rssMax = r.rssStart;
  r.load1Start = loadAverage1();
  double cpuStart = 0;
  double n = 0, st = 0, sr = 0, stt = 0, str = 0;  // least squares of RSS (KiB) against time (min)
  int64_t nextRss = warmEnd;
  int64_t next = t0;
  for (;;) {
    next += framePeriod;
    std::this_thread::sleep_until(std::chrono::steady_clock::time_point(std::chrono::nanoseconds(next)));
    const int64_t now = steadyNowNs();
    if (now >= end) break;
    next = std::max(next, now - framePeriod);  // after a stall, carry on at the frame rate rather than catch up
    consume(now);
    if (!measuring && now >= warmEnd) {
      measuring = true;
      cpuStart = processCpuSeconds();
    }
    if (now >= nextRss) {
      const int64_t rss = rssKiB();
      if (r.rssWarm == 0) r.rssWarm = rss;
      r.rssMax = std::max(r.rssMax, rss);
      const double t = static_cast<double>(now - warmEnd) / 60e9, v = static_cast<double>(rss);
      n += 1, st += t, sr += v, stt += t * t, str += t * v;
      nextRss += 1'000'000'000;
    }
  }
  r.rssEnd = rssKiB();
  r.rssMax = std::max(r.rssMax, r.rssEnd);
  const double measuredSeconds = std::max(1e-9, static_cast<double>(steadyNowNs() - warmEnd) * 1e-9);
  r.cpuPercent = 100 * (processCpuSeconds() - cpuStart) / measuredSeconds;
  r.load1End = loadAverage1();
  if (n >= 2 && n * stt - st * st > 0) r.rssSlopeKiBPerMin = (n * str - st * sr) / (n * stt - st * st);

  // ---- Stop the stream at an exact sample, then let everything in flight reach the consumer.
  measuring = false;
  clock.freeze();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the server produces its last due samples
  const int64_t giveUp = steadyNowNs() + 10'000'000'000;
  while (steadyNowNs() < giveUp) {
    consume(0);
    if (r.received == server->samplesSent() && mailbox.stats().drained == session->stats().samples) {
      r.drainedToTheEnd = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  session->stop();
  server->stop();
  consume(0);
  r.sent = server->samplesSent();
  r.uartOverrunBytes = server->bytesDropped();
  r.session = session->stats();
  r.mailbox = mailbox.stats();
  session.reset();
  server.reset();
}

void reportAges(benchmark::State& state, const StreamRun& r) {
  auto put = [&](const char* name, const LatencyHistogram& h) {
    const std::string p(name);
    state.counters[p + "_p50_us"] = h.quantileUs(0.5);
    state.counters[p + "_p99_us"] = h.quantileUs(0.99);
    state.counters[p + "_max_us"] = h.maxUs();
  };
  put("transport", r.transport);
  put("newest_age", r.newestAge);
  put("newest_total", r.newestTotal);
  put("queue_age", r.queueAge);
}

void printAges(const char* name, const StreamRun& r) {
  auto line = [](const char* what, const LatencyHistogram& h) {
    std::fprintf(stderr, "  %-44s median %7.0f  p99 %7.0f  max %8.0f µs  (n=%llu%s)\n", what, h.quantileUs(0.5),
                 h.quantileUs(0.99), h.maxUs(), static_cast<unsigned long long>(h.count()),
                 h.negatives() ? ", some negative: device epoch wrong?" : "");
  };
  std::fprintf(stderr,
               "%s: ages after %.0f s warm-up (load %.2f → %.2f, process CPU %.1f%% of a core; %llu frames, %llu "
               "without a new pose)\n",
               name, r.warmupSeconds, r.load1Start, r.load1End, r.cpuPercent,
               static_cast<unsigned long long>(r.frames), static_cast<unsigned long long>(r.framesWithoutNewPose));
  line("transport (device due → host read)", r.transport);
  line("newest pose (host read → frame loop take)", r.newestAge);
  line("newest pose (device due → frame loop take)", r.newestTotal);
  line("queue (host read → drained)", r.queueAge);
}

// Soak: sustained stream, every sample accounted for and checked, memory flat. Fails (SkipWithError) on any drop,
// any value mismatch, or more than kFlatKiB of RSS growth after warm-up.
void BM_Soak1kHz64ch(benchmark::State& state) {
  constexpr int64_t kFlatKiB = 512;
  const double seconds = envSeconds("IMPS_SOAK_SECONDS", 10);
  StreamRun r;
  for (auto _ : state) runStream(r, seconds, std::min(5.0, seconds / 5), 60);
  if (!r.error.empty()) {
    state.SkipWithError(r.error.c_str());
    return;
  }
  const bool zeroDrops = r.zeroDrops();
  const bool flat = r.rssEnd - r.rssWarm <= kFlatKiB;
  state.counters["seconds"] = seconds;
  state.counters["samples_sent"] = static_cast<double>(r.sent);
  state.counters["samples_received"] = static_cast<double>(r.received);
  state.counters["dropped"] = static_cast<double>(r.dropped());
  state.counters["seq_gaps"] = static_cast<double>(r.session.samplesDropped);
  state.counters["queue_overflows"] = static_cast<double>(r.mailbox.queueOverflows);
  state.counters["crc_errors"] = static_cast<double>(r.session.crcErrors);
  state.counters["value_mismatches"] = static_cast<double>(r.valueMismatches);
  state.counters["rss_start_KiB"] = static_cast<double>(r.rssStart);
  state.counters["rss_warm_KiB"] = static_cast<double>(r.rssWarm);
  state.counters["rss_end_KiB"] = static_cast<double>(r.rssEnd);
  state.counters["rss_growth_KiB_per_min"] = r.rssSlopeKiBPerMin;
  state.counters["zero_drops"] = zeroDrops ? 1 : 0;
  state.counters["flat_memory"] = flat ? 1 : 0;
  state.counters["cpu_pct"] = r.cpuPercent;
  state.counters["load1"] = r.load1End;
  reportAges(state, r);

  std::fprintf(stderr,
               "BM_Soak1kHz64ch: %.0f s: sent %llu, received %llu in order, dropped %llu (sequence gaps %llu, queue "
               "overflows %llu, consumer gaps %llu, out of order %llu, UART overrun bytes %llu), value mismatches "
               "%llu, CRC errors %llu, garbage bytes %llu, timeouts %llu, reconnects %llu\n",
               seconds, static_cast<unsigned long long>(r.sent), static_cast<unsigned long long>(r.received),
               static_cast<unsigned long long>(r.dropped()), static_cast<unsigned long long>(r.session.samplesDropped),
               static_cast<unsigned long long>(r.mailbox.queueOverflows),
               static_cast<unsigned long long>(r.consumerGaps), static_cast<unsigned long long>(r.outOfOrder),
               static_cast<unsigned long long>(r.uartOverrunBytes), static_cast<unsigned long long>(r.valueMismatches),
               static_cast<unsigned long long>(r.session.crcErrors),
               static_cast<unsigned long long>(r.session.garbageBytes),
               static_cast<unsigned long long>(r.session.timeouts),
               static_cast<unsigned long long>(r.session.reconnects));
  std::fprintf(stderr,
               "  RSS KiB: before %lld, start %lld, after warm-up %lld, end %lld, max %lld; growth after warm-up %lld "
               "KiB (slope %.1f KiB/min) -> %s; %s\n",
               static_cast<long long>(r.rssBefore), static_cast<long long>(r.rssStart),
               static_cast<long long>(r.rssWarm), static_cast<long long>(r.rssEnd), static_cast<long long>(r.rssMax),
               static_cast<long long>(r.rssEnd - r.rssWarm), r.rssSlopeKiBPerMin, flat ? "flat" : "GROWING",
               zeroDrops ? "0 dropped" : "SAMPLES LOST");
  printAges("BM_Soak1kHz64ch", r);

  if (!zeroDrops) state.SkipWithError("samples were dropped (see the line on stderr)");
  else if (r.valueMismatches) state.SkipWithError("received samples differ from the ones sent");
  else if (!flat) state.SkipWithError("memory grew after warm-up");
}
BENCHMARK(BM_Soak1kHz64ch)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// Sample age at consumption on the same stream, for a consumer running at `frame_hz` (60: a frame loop; 1000: a
// consumer polling as often as samples come, which shows the hand-off itself).
void BM_SampleAge1kHz64ch(benchmark::State& state) {
  const double seconds = envSeconds("IMPS_AGE_SECONDS", 5);
  const double frameHz = static_cast<double>(state.range(0));
  StreamRun r;
  for (auto _ : state) runStream(r, seconds, std::min(2.0, seconds / 5), frameHz);
  if (!r.error.empty()) {
    state.SkipWithError(r.error.c_str());
    return;
  }
  reportAges(state, r);
  state.counters["samples"] = static_cast<double>(r.transport.count());
  state.counters["load1"] = r.load1End;
  const std::string name = "BM_SampleAge1kHz64ch/frame_hz:" + std::to_string(state.range(0));
  printAges(name.c_str(), r);
  if (!r.zeroDrops()) state.SkipWithError("samples were dropped");
}
BENCHMARK(BM_SampleAge1kHz64ch)
    ->ArgName("frame_hz")
    ->Arg(60)
    ->Arg(1000)
    ->Iterations(1)
    ->Unit(benchmark::kSecond)
    ->UseRealTime();

}  // namespace
