// SPDX-License-Identifier: MIT
// The live device pose source: device session → pose mailbox → joints; recording and re-calibration.
#include "viewer_live.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <utility>

#include "cli.h"
#include "imps/clock.h"

namespace imps::app {
namespace {
drivers::PoseMailboxOptions mailboxOptions() {
  drivers::PoseMailboxOptions o;
  o.queueCapacity = 1 << 14;  // 16 s at 1 kHz for the recorder and the calibration window
  return o;
}
}  // namespace

LivePoseSource::LivePoseSource(drivers::TransportOpener opener, const drivers::DeviceSessionOptions& options,
                               const Character& character, std::string spec, std::optional<SampleMapper> calibration,
                               LiveSourceOptions live)
    : character_(character),
      spec_(std::move(spec)),
      live_(std::move(live)),
      mailbox_(mailboxOptions()),
      map_(std::move(calibration)),
      flow_(live_.calibrate) {
  batch_.reserve(1024);
  session_ = std::make_unique<drivers::DeviceSession>(std::move(opener), mailbox_, options);
  session_->start();
  rateWindowStartNs_ = steadyNowNs();
  if (!live_.recordPath.empty()) startRecording(live_.recordPath);
}

LivePoseSource::~LivePoseSource() {
  session_->stop();
  finish();
}

void LivePoseSource::say(std::string message) {
  std::printf("puppeteer: %s\n", message.c_str());
  std::fflush(stdout);
  message_ = std::move(message);
}

// Prints the device's problem to stderr each time a new one appears (the HUD may be off or the window hidden).
void LivePoseSource::reportProblems() {
  const drivers::ConnectionState state = session_->state();
  if (state == drivers::ConnectionState::Streaming) return;
  std::string error = session_->lastError();
  if (error.empty() || error == reportedError_) return;
  std::fprintf(stderr, "puppeteer: device %s: %s: %s\n", spec_.c_str(), drivers::toString(state), error.c_str());
  reportedError_ = std::move(error);
}

bool LivePoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  reportProblems();
  if (!device_) {
    // The channel names arrive with the handshake; build the by-name map once (deviceInfo() takes a mutex: not
    // per frame once known).
    device_ = session_->deviceInfo();
    if (!device_) return false;
    if (!map_) {
      sim::Session names;
      names.devices.push_back(*device_);
      map_.emplace(names, character_);
    }
    deviceName_ = device_->name.empty() ? "device" : device_->name;
  }

  // Every sample, in order: the recording and the calibration window.
  batch_.clear();
  mailbox_.drain(batch_);
  gotSample_ = gotSample_ || !batch_.empty();
  // The description as it is now: a line-protocol device's layout may have changed since the handshake.
  const std::optional<drivers::DeviceInfo> latest =
      recordingWanted_ && !batch_.empty() ? session_->deviceInfo() : std::nullopt;
  if (recordingWanted_ && !recorder_ && !batch_.empty()) {
    auto created = SessionRecorder::create(
        recordPath_, withChannelCount(latest ? *latest : *device_, batch_.front().channelCount), calibration());
    if (created) {
      recorder_.emplace(std::move(*created));
      recordStartNs_ = countersWrittenNs_ = steadyNowNs();
    } else {
      recordingWanted_ = false;
      say("recording failed: " + drivers::errorText(created.error()));
    }
  }
  if (recorder_) {
    auto r = recorder_->append(batch_, latest ? &*latest : nullptr);
    if (r && steadyNowNs() - countersWrittenNs_ >= 1'000'000'000) {
      r = recorder_->appendCounters(session_->stats());  // a crash keeps the counts of the last second
      countersWrittenNs_ = steadyNowNs();
    }
    if (!r) {
      recorder_.reset();
      recordingWanted_ = false;
      say("recording stopped: " + drivers::errorText(r.error()));
    }
  }
  if (flow_.active() && flow_.update(batch_, steadyNowNs())) finishCalibration();

  if (!mailbox_.latest(sample_)) return false;
  map_->apply(0, sample_, skeleton);
  if (arrivalNs) *arrivalNs = sample_.arrivalTimeNs;
  return true;
}

void LivePoseSource::startRecording(std::string path) {
  recordPath_ = std::move(path);
  recordingWanted_ = true;
}

std::string LivePoseSource::stopRecording() {
  recordingWanted_ = false;
  if (!recorder_) return "recording stopped: no samples arrived, nothing was written";
  // What the device sent up to now.
  batch_.clear();
  mailbox_.drain(batch_);
  const std::optional<drivers::DeviceInfo> latest = session_->deviceInfo();
  auto appended = recorder_->append(batch_, latest ? &*latest : nullptr);
  const drivers::DeviceSessionStats stats = session_->stats();
  if (appended) appended = recorder_->appendCounters(stats);
  const double seconds = double(steadyNowNs() - recordStartNs_) * 1e-9;
  const uint64_t samples = recorder_->samples(), layoutChanges = recorder_->layoutChanges();
  const std::string path = recorder_->path().string();
  auto closed = recorder_->close();
  recorder_.reset();
  if (!appended) return "recording failed: " + drivers::errorText(appended.error());
  if (!closed) return "recording failed: " + drivers::errorText(closed.error());
  char buf[96];
  std::snprintf(buf, sizeof buf, "recorded %llu samples (%.1f s) to ", static_cast<unsigned long long>(samples),
                seconds);
  std::string message = buf + path;
  if (layoutChanges) message += " (" + std::to_string(layoutChanges) + " channel-layout change(s) recorded)";
  return message + "; " + countersSummary(stats);
}

std::string LivePoseSource::toggleRecording() {
  if (recordingWanted_) return stopRecording();
  startRecording(newTakePath(live_.recordDir, std::time(nullptr)).string());
  return "recording to " + recordPath_;
}

std::string LivePoseSource::recalibrate() {
  if (flow_.active()) {
    flow_.reset();
    return "re-calibration cancelled";
  }
  if (!device_) return "re-calibration: the device has not described itself yet";
  if (!calibration() && live_.rigPath.empty())
    return "re-calibration needs a rig map: start with --calibration FILE or --rig RIG --calibration-out FILE";
  if (live_.calibrationOut.empty() && live_.calibrationPath.empty())
    return "re-calibration: nowhere to save it: pass --calibration-out FILE";
  flow_.start(steadyNowNs());
  char buf[96];
  std::snprintf(buf, sizeof buf,
                "re-calibrating: hold the calibration pose still (averaging %.0f ms in %.1fs; k cancels)",
                live_.calibrate.windowMs, live_.calibrate.delayMs * 1e-3);
  return buf;
}

void LivePoseSource::finishCalibration() {
  // The rig map: the calibration in force (its offsets are replaced), else --rig against this device.
  std::optional<calibration::RigMap> rig;
  std::string rigName;
  if (const calibration::Calibration* c = calibration()) {
    rig = c->rigMap();
    rigName = live_.calibrationPath.empty() ? "the calibration in force" : live_.calibrationPath;
  } else {
    Diagnostics warnings;
    auto read = calibration::readRigMapFile(live_.rigPath, {&character_, &*device_, false}, &warnings);
    if (!read) {
      flow_.reset();
      say("re-calibration failed: " + read.error().str());
      return;
    }
    rig = std::move(*read);
    rigName = live_.rigPath;
  }
  const std::vector<drivers::Sample>& window = flow_.window();
  auto result = calibrateWindow(*rig, window, *device_, character_, live_.calibrate.maxNoiseDeg,
                                calibrationInfoJson(live_.scenePath, rigName, spec_, live_.calibrate.windowMs,
                                                    window.size(), device_->serialNumber));
  const size_t samples = window.size();
  flow_.reset();
  if (!result) {
    std::string message = "calibration rejected (" + std::to_string(samples) + " samples): ";
    const std::vector<Diagnostic>& problems = result.error().all();
    message += problems.empty() ? "unknown reason" : problems.front().message;
    if (problems.size() > 1) message += " (+" + std::to_string(problems.size() - 1) + " more)";
    say(message + "; hold still and press k again");
    for (size_t i = 1; i < problems.size(); ++i) std::printf("  %s\n", problems[i].message.c_str());
    return;
  }
  const std::string out = live_.calibrationOut.empty() ? live_.calibrationPath : live_.calibrationOut;
  if (auto saved = result->calibration.save(out); !saved) {
    say("calibration not saved: " + saved.error().message + " (not applied)");
    return;
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, "calibrated %zu channels from %zu samples (noise at most %.3f deg), saved ",
                result->calibration.rigMap().channels.size(), samples, result->maxNoiseDeg);
  std::string message = buf + out;
  if (recorder_) {
    if (auto r = recorder_->appendCalibration(result->calibration); !r)
      message += "; not recorded: " + drivers::errorText(r.error());
  }
  map_.emplace(std::move(result->calibration), std::filesystem::path(out).filename().string());
  live_.calibrationPath = out;
  say(message);
}

std::string LivePoseSource::takeMessage() { return std::exchange(message_, std::string()); }

std::string LivePoseSource::finish() {
  if (finished_) return {};
  finished_ = true;
  if (!gotSample_) {
    const std::string error = session_->lastError();
    std::fprintf(stderr, "puppeteer: error: no samples from %s: %s\n", spec_.c_str(),
                 error.empty() ? "the device never started streaming" : error.c_str());
  }
  if (!recordingWanted_) return {};
  return stopRecording();
}

int LivePoseSource::exitCode() const { return gotSample_ ? kExitOk : kExitIoError; }

void LivePoseSource::describe(HudInfo& info) {
  const drivers::DeviceSessionStats st = session_->stats();
  const int64_t now = steadyNowNs();
  if (now - rateWindowStartNs_ >= 500'000'000) {
    rateHz_ = double(st.samples - rateWindowStartCount_) / (double(now - rateWindowStartNs_) * 1e-9);
    rateWindowStartNs_ = now, rateWindowStartCount_ = st.samples;
  }
  info.source = (deviceName_.empty() ? std::string("device") : deviceName_) + " (" + spec_ + ")";
  if (map_) info.mapping = map_->describe();
  info.state = drivers::toString(st.state);
  if (map_ && map_->mappedJoints() == 0) info.state += ", no channel names a joint: nothing moves";
  // Not streaming because something failed (an open, the link) is a problem to see at once; the first open and
  // wait of a device that has not failed yet are not.
  info.lastError = session_->lastError();
  info.problem = st.state != drivers::ConnectionState::Streaming &&
                 (st.state == drivers::ConnectionState::Lost || st.state == drivers::ConnectionState::Reconnecting ||
                  !info.lastError.empty());
  if (!info.problem) info.lastError.clear();
  info.sampleRateHz = rateHz_;
  info.dropped = st.samplesDropped;
  info.corrupt = st.crcErrors + st.malformedFrames + st.unknownTypes + st.unsupportedVersions + st.oversizeFrames +
                 st.truncatedFrames + st.parseErrors;
  info.faults.clear();
  for (const drivers::NamedCounter& c : drivers::namedCounters(st)) {
    if (c.value == 0) continue;
    if (!info.faults.empty()) info.faults += ", ";
    info.faults += std::string(c.label) + ": " + std::to_string(c.value);
  }
  const drivers::PoseMailboxStats ms = mailbox_.stats();
  info.overwritten = ms.overwritten;
  info.sampleAgeMs = gotSample_ ? double(ms.lastAgeNs) * 1e-6 : -1.0;  // no sample yet: no age to show
  info.recording = recordingWanted_;
  info.recordSeconds = recorder_ ? double(now - recordStartNs_) * 1e-9 : 0.0;
  info.recordSamples = recorder_ ? recorder_->samples() : 0;
  info.recordPath = recordPath_;
  info.calibrationProgress = flow_.progress(now);
}

}  // namespace imps::app
