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
#include "drivers/sample.h"
#include "sim/session_file.h"

namespace imps::app {

// One take. Created when the device has described itself; the frame loop appends the samples it drains from the
// pose mailbox's in-order queue. Not thread-safe: one owner. Movable.
class SessionRecorder {
 public:
  // Creates `path` (an existing file is an error: recordings never overwrite) for `device`, and records
  // `calibration` (may be null) as in force from the first sample on. Errors are the writer's "path: error: …".
  static std::expected<SessionRecorder, std::string> create(const std::filesystem::path& path,
                                                            const drivers::DeviceInfo& device,
                                                            const calibration::Calibration* calibration,
                                                            sim::SessionWriterOptions options = {});

  // Appends samples in order. Samples whose channel count differs from the device's (a different device came back
  // on reconnect) are skipped and counted, as `puppeteer record` does. Write errors are returned (the take is
  // then unusable: stop it).
  std::expected<void, std::string> append(std::span<const drivers::Sample> samples);
  // Records `calibration` as in force from the next sample on (a re-calibration during the take).
  std::expected<void, std::string> appendCalibration(const calibration::Calibration& calibration);
  // Flushes, writes the END record and closes the file.
  std::expected<void, std::string> close();

  uint64_t samples() const { return writer_.samplesWritten(); }
  uint64_t skipped() const { return skipped_; }
  const std::filesystem::path& path() const { return writer_.path(); }

 private:
  explicit SessionRecorder(sim::SessionWriter writer, int channelCount)
      : writer_(std::move(writer)), channelCount_(channelCount) {}
  sim::SessionWriter writer_;
  int channelCount_ = 0;
  uint64_t skipped_ = 0;
};

// A new take's file name in `dir`: "take-YYYYMMDD-HHMMSS.session" (local time `when`), with "-2", "-3" … appended
// when that file already exists.
std::filesystem::path newTakePath(const std::filesystem::path& dir, std::time_t when);

}  // namespace imps::app
