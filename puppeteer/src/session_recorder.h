// SPDX-License-Identifier: MIT
// Recording a live device in the app: every raw sample, in order, with the device description and the calibration in
// force, into an append-only, crash-safe session file (sim::SessionWriter, the same writer `puppeteer record` uses).
#pragma once

#include <cstdint>
#include <ctime>
#include <expected>
#include <filesystem>
#include <span>
#include <string>

#include "calibration/calibration.h"
#include "drivers/device_session.h"
#include "drivers/sample.h"
#include "imps/io_error.h"
#include "sim/session_file.h"

namespace imps::app {

// One take. Created when the device has described itself; the frame loop appends the samples it drains from the
// pose mailbox's in-order queue. Not thread-safe: one owner. Movable.
class SessionRecorder {
 public:
  // Creates `path` (an existing file is an error: recordings never overwrite) for `device`, and records
  // `calibration` (may be null) as in force from the first sample on. Errors are the writer's, as an IoError naming
  // `path` (drivers::errorText prints "path: error: …").
  static IoResult<SessionRecorder> create(const std::filesystem::path& path, const drivers::DeviceInfo& device,
                                          const calibration::Calibration* calibration,
                                          sim::SessionWriterOptions options = {});

  // Appends samples in order. A sample whose channel count differs from the layout in force (a line-protocol
  // device re-locked to another count, or another device came back on reconnect) starts a new layout: a LAYOUT
  // record declares it (docs/session-format.md) and the samples go on under it, none is dropped. `latest`
  // describes the new layout when its channel count matches (DeviceSession::deviceInfo() follows the decoder);
  // otherwise the previous description is kept with channels named ch0, ch1, … Write errors are returned (the
  // take is then unusable: stop it).
  IoResult<void> append(std::span<const drivers::Sample> samples, const drivers::DeviceInfo* latest = nullptr);
  // Records the device link's counters (drivers::namedCounters) as they are now; the last call before close()
  // is what `puppeteer info` shows. Call it every second or so, so a crash keeps recent counts.
  IoResult<void> appendCounters(const drivers::DeviceSessionStats& stats);
  // Records `calibration` as in force from the next sample on (a re-calibration during the take).
  IoResult<void> appendCalibration(const calibration::Calibration& calibration);
  // Flushes, writes the END record and closes the file.
  IoResult<void> close();

  uint64_t samples() const { return writer_.samplesWritten(); }
  uint64_t layoutChanges() const { return layoutChanges_; }
  const std::filesystem::path& path() const { return writer_.path(); }

 private:
  explicit SessionRecorder(sim::SessionWriter writer, const drivers::DeviceInfo& device)
      : writer_(std::move(writer)), layout_(device) {}
  IoResult<void> changeLayout(int channelCount, const drivers::DeviceInfo* latest);
  sim::SessionWriter writer_;
  drivers::DeviceInfo layout_;  // the layout in force
  uint16_t device_ = 0;         // its device index in the file
  uint64_t layoutChanges_ = 0;
};

// `device` with `channelCount` channels: unchanged when it already has that many, else its channels renamed ch0,
// ch1, … (a line-protocol device's layout changed).
drivers::DeviceInfo withChannelCount(drivers::DeviceInfo device, int channelCount);

// Every counter of the device link (drivers::namedCounters), "label: value" joined by ", ", for the summaries of
// `puppeteer record` and of a take in the live app.
std::string countersSummary(const drivers::DeviceSessionStats& stats);

// A new take's file name in `dir`: "take-YYYYMMDD-HHMMSS.session" (local time `when`), with "-2", "-3" … appended
// when that file already exists.
std::filesystem::path newTakePath(const std::filesystem::path& dir, std::time_t when);

}  // namespace imps::app
