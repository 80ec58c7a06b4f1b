// SPDX-License-Identifier: MIT
// Recorded sessions: an append-only, crash-safe file of raw Samples (format in docs/session-format.md), its
// reader with a recovery report, and a replayer that plays a recorded session against an injectable clock.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <expected>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/sample.h"
#include "imps/clock.h"
#include "imps/diagnostic.h"
#include "sim/sample_table.h"

namespace imps::sim {

using drivers::DeviceInfo;
using drivers::Sample;

// The largest record payload the format allows (docs/session-format.md); a reader treats a longer length as corruption.
inline constexpr uint32_t kMaxRecordPayloadBytes = 64u << 20;

// ---------------------------------------------------------------------------------------------------------------
// The in-memory session

// A calibration JSON blob as recorded, and the index (into Session::samples) of the first sample it applies to.
struct SessionCalibration {
  uint64_t firstSample = 0;
  std::string json;
  bool operator==(const SessionCalibration&) const = default;
};

// A timestamped label the operator dropped during recording ("take 3", "clap").
struct SessionMarker {
  uint64_t firstSample = 0;  // number of samples recorded before the marker
  int64_t timeNs = 0;        // on the host's steady clock (the arrivalTimeNs timeline)
  std::string label;
  bool operator==(const SessionMarker&) const = default;
};

// How a session's channels map onto a BVH skeleton (written when a BVH clip is converted to a session).
struct SessionSkeleton {
  std::string bvh;                    // a complete BVH file with zero frames: HIERARCHY + MOTION header
  double positionUnitsPerCount = 0;   // BVH length units per encoder count for position channels
  bool operator==(const SessionSkeleton&) const = default;
};

// Device `device` is the armature of device `previous` with a new channel layout (a line-protocol device whose
// channel count re-locked mid-take), in force from sample index `firstSample` on: one armature, not two.
struct SessionLayoutChange {
  uint16_t device = 0;
  uint16_t previous = 0;
  uint64_t firstSample = 0;  // number of samples recorded before the change
  bool operator==(const SessionLayoutChange&) const = default;
};

// One counter of the device link while recording (names as drivers::namedCounters() gives them: "crcErrors", …).
struct SessionCounter {
  std::string name;
  uint64_t value = 0;
  bool operator==(const SessionCounter&) const = default;
};
// The link's counters for one device, as last recorded (a later COUNTERS record replaces an earlier one).
struct SessionCounters {
  uint16_t device = 0;
  std::vector<SessionCounter> values;
  bool operator==(const SessionCounters&) const = default;
};

// What the reader could and could not use. A file cut off by a crash is not an error: it reads back up to its last
// whole record, and this report says what was lost.
struct SessionRecovery {
  bool closedCleanly = false;  // an END record was found (the writer was closed, not killed)
  bool truncated = false;      // the file ends inside a record
  bool corrupt = false;        // a record failed its CRC or its contents are invalid
  uint64_t fileBytes = 0;      // size of the input
  uint64_t bytesUsed = 0;      // bytes up to the end of the last good record (or the END record)
  uint64_t bytesIgnored = 0;   // fileBytes - bytesUsed
  uint64_t recordsRead = 0;    // good records, header excluded
  uint64_t unknownRecords = 0; // good records of types this reader does not know (skipped, see versioning rules)
  std::string message;         // "file: warning: ..." with the byte offset; empty when the file is whole
};

// A whole recorded session. samples[i] came from devices[sampleDevice[i]].
struct Session {
  uint16_t formatVersion = 0;
  std::vector<DeviceInfo> devices;            // index = device number in SAMPLE records
  SampleTable samples;                        // in recording order; counts/flags beyond channelCount are zero
  std::vector<uint16_t> sampleDevice;         // same length as samples
  std::vector<SessionCalibration> calibrations;
  std::vector<SessionMarker> markers;
  std::vector<std::string> notes;
  std::optional<SessionSkeleton> skeleton;
  std::vector<SessionLayoutChange> layoutChanges;
  std::vector<SessionCounters> counters;  // at most one per device, the last one recorded
  SessionRecovery recovery;
};

// ---------------------------------------------------------------------------------------------------------------
// Writing

struct SessionWriterOptions {
  // append() flushes by itself once this many samples are buffered (0: never by count).
  size_t flushEverySamples = 256;
  // ...or once this long has passed since the last flush, checked at each append() (0: never by time).
  int64_t flushEveryNs = 100'000'000;
  // Call fdatasync() after every flush, so a power cut (not only a crash of this process) keeps the data.
  bool syncOnFlush = false;
  // Clock for flushEveryNs; nullptr means a SteadyClock. Not owned; must outlive the writer.
  Clock* clock = nullptr;
};

// Appends a session to a new file. The file is created (an existing file is an error, never overwritten), the
// header and DEVICE_INFO records are written and flushed at once; afterwards bytes are only ever appended. Records
// are buffered and written with one write() per flush, so after a crash the file reads back up to the last flush.
// Not thread-safe: one recording thread owns the writer. Movable, not copyable.
// Every method fails with one error at the file's path (printed "path: error: ..."), whether the system refused
// (create, write, fsync: the reason in the system's words) or the call was wrong (a bad DeviceInfo, a sample of
// the wrong size, a closed writer); a recorder reports both alike, as an output that could not be written.
class SessionWriter {
 public:
  // Creates `path` for a session of one or more devices (several when an armature has more than kMaxChannels
  // channels, or a rig combines armatures). Errors: the file exists or is not writable, a bad DeviceInfo.
  static std::expected<SessionWriter, Diagnostics> create(const std::filesystem::path& path,
                                                          std::span<const DeviceInfo> devices,
                                                          SessionWriterOptions options = {});
  static std::expected<SessionWriter, Diagnostics> create(const std::filesystem::path& path, const DeviceInfo& device,
                                                          SessionWriterOptions options = {});

  SessionWriter(SessionWriter&& other) noexcept;
  SessionWriter& operator=(SessionWriter&& other) noexcept;
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;
  // Flushes and writes the END record; errors are lost (call close() to see them).
  ~SessionWriter();

  // Buffers one sample of device `device`. The sample's channelCount must equal that device's channelCount and be
  // <= kMaxChannels. May flush (see SessionWriterOptions); flush errors are returned.
  std::expected<void, Diagnostics> append(const Sample& sample, uint16_t device = 0);
  // Buffers a calibration JSON blob (stored verbatim); it applies from the next appended sample on.
  std::expected<void, Diagnostics> appendCalibration(std::string_view json);
  // Buffers a marker at `timeNs` (host steady clock).
  std::expected<void, Diagnostics> appendMarker(int64_t timeNs, std::string_view label);
  // Buffers a free-text note.
  std::expected<void, Diagnostics> appendNote(std::string_view text);
  // Declares a new device (DEVICE_INFO) that continues device `previous` with another channel layout (LAYOUT), for
  // the samples appended from now on; returns its device index. Errors: a bad DeviceInfo, no such device.
  std::expected<uint16_t, Diagnostics> appendLayoutChange(const DeviceInfo& device, uint16_t previous);
  // Buffers a LAYOUT record alone: device `device`, already declared, continues device `previous` (< device).
  // For copying a session whose devices were all declared up front (saveSession).
  std::expected<void, Diagnostics> appendLayout(uint16_t device, uint16_t previous);
  // Buffers the link's counters for `device` (COUNTERS); a later call supersedes an earlier one for readers.
  std::expected<void, Diagnostics> appendCounters(uint16_t device, std::span<const SessionCounter> counters);
  size_t deviceCount() const { return devices_.size(); }
  // Buffers the BVH skeleton the channels map onto (see SessionSkeleton).
  std::expected<void, Diagnostics> appendSkeleton(const SessionSkeleton& skeleton);
  // Writes everything buffered with one write() (and fdatasync() if syncOnFlush).
  std::expected<void, Diagnostics> flush();
  // Flushes, appends the END record, syncs and closes. Further calls are errors.
  std::expected<void, Diagnostics> close();

  uint64_t samplesWritten() const { return samples_; }  // appended so far, flushed or not
  uint64_t bytesFlushed() const { return flushed_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  SessionWriter() = default;
  std::expected<void, Diagnostics> appendRecord(uint16_t type, std::span<const uint8_t> payload);
  std::expected<void, Diagnostics> writeAll(std::span<const uint8_t> bytes);
  std::expected<void, Diagnostics> usable() const;
  Clock& clock() const;

  std::filesystem::path path_;
  int fd_ = -1;
  SessionWriterOptions options_;
  std::vector<DeviceInfo> devices_;
  std::vector<uint8_t> buffer_;   // records not yet written
  std::vector<uint8_t> scratch_;  // one record's payload, reused
  size_t bufferedSamples_ = 0;
  uint64_t samples_ = 0;
  uint64_t flushed_ = 0;
  int64_t lastFlushNs_ = 0;
  bool closed_ = false;
};

// ---------------------------------------------------------------------------------------------------------------
// Reading

// Reads a whole session file. Fails (one error at the path, printed "path: error: ...") only when nothing can be
// trusted: unreadable file, bad magic, unsupported version, header cut short. An unreadable file is bad input here
// like a corrupt one (the commands exit 1 for both). Truncated or corrupt records end the read cleanly; see
// Session::recovery.
std::expected<Session, Diagnostics> readSession(const std::filesystem::path& path);
// The same from bytes in memory; `name` stands for the file in messages. Never reads outside `bytes`.
std::expected<Session, Diagnostics> readSessionBytes(std::span<const uint8_t> bytes,
                                                     std::string_view name = "<memory>");

// Writes an in-memory session (devices, skeleton, notes, then samples interleaved with calibrations and markers at
// their recorded sample indices, then END) to `path` atomically: a temporary file beside it is written and synced,
// then renamed over the target. Used to save converted sessions. Fails with one error at `path` (a session whose
// parts disagree, or the writer's or the save's failure, naming `path`, never the temporary file).
std::expected<void, Diagnostics> saveSession(const std::filesystem::path& path, const Session& session);

// CRC-32C (Castagnoli, reflected, init and final xor 0xFFFFFFFF), as used by the record headers.
// crc32c("123456789") == 0xE3069283.
uint32_t crc32c(std::span<const uint8_t> bytes, uint32_t crc = 0);

// ---------------------------------------------------------------------------------------------------------------
// Replaying

// Receives replayed samples, as it would receive them from a live device session.
class SampleConsumer {
 public:
  virtual ~SampleConsumer() = default;
  // Called once per sample in recording order. Return false to stop the replay.
  virtual bool consume(uint16_t device, const Sample& sample) = 0;
};

struct ReplayOptions {
  // Playback rate: 1 real time, 2 twice as fast, 0.5 half speed; 0 (or less) as fast as possible.
  double speed = 1.0;
  // Which recorded timestamps set the schedule. Device time falls back to arrival time for devices without one.
  enum class Timebase { Arrival, Device } timebase = Timebase::Arrival;
  // When true, each delivered sample's arrivalTimeNs is set to the replay clock's time at delivery, as a live
  // device session would stamp it; the recorded value stays in the Session. When false (default) the samples
  // delivered are bit-identical to the samples recorded.
  bool rewriteArrivalTime = false;
  // Longest single sleep; between sleeps stop() is noticed. Keeps a paused-looking replay responsive.
  int64_t maxSleepNs = 50'000'000;
};

// Plays a Session's samples to a consumer with their recorded timing (VRPN's file connection is the model): the
// sample at position p is due at start + (t[p] - t[first]) / speed, where start is the clock's time when run()
// begins and first is the position run() begins at. Samples whose timestamps go backwards are delivered at once.
// The Session and Clock are not owned and must outlive the replay. run() is for one thread; stop() may be called
// from any thread.
class SessionReplay {
 public:
  SessionReplay(const Session& session, Clock& clock, ReplayOptions options = {});

  // Delivers samples from position() to the end (or until the consumer returns false or stop() is called);
  // returns the number delivered. position() afterwards is the first sample not delivered.
  size_t run(SampleConsumer& consumer);
  size_t run(const std::function<bool(uint16_t device, const Sample& sample)>& consume);
  void stop() { stopRequested_.store(true, std::memory_order_relaxed); }

  // Moves to sample `index` (clamped to the end); the next run() starts its schedule there.
  void seek(size_t index);
  size_t position() const { return position_; }
  // Recorded timestamp (per the timebase) of sample `index`.
  int64_t recordedTimeNs(size_t index) const;

 private:
  const Session& session_;
  Clock& clock_;
  ReplayOptions options_;
  size_t position_ = 0;
  std::atomic<bool> stopRequested_{false};
};

}  // namespace imps::sim
