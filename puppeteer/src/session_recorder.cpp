// SPDX-License-Identifier: MIT
// Recording a live device in the app (see session_recorder.h).
#include "session_recorder.h"

#include <ctime>

#include "session_calibration.h"

namespace imps::app {

IoResult<SessionRecorder> SessionRecorder::create(const std::filesystem::path& path, const drivers::DeviceInfo& device,
                                                  const calibration::Calibration* calibration,
                                                  sim::SessionWriterOptions options) {
  auto writer = sim::SessionWriter::create(path, device, options);
  if (!writer) return std::unexpected(sessionWriterError(path, writer.error()));
  SessionRecorder recorder(std::move(*writer), device);
  if (calibration) {
    if (auto r = recorder.appendCalibration(*calibration); !r) return std::unexpected(r.error());
  }
  return recorder;
}

IoResult<void> SessionRecorder::append(std::span<const drivers::Sample> samples, const drivers::DeviceInfo* latest) {
  for (const drivers::Sample& s : samples) {
    if (s.channelCount != layout_.channelCount)
      if (auto r = changeLayout(s.channelCount, latest); !r) return r;
    if (auto r = writer_.append(s, device_); !r) return std::unexpected(sessionWriterError(path(), r.error()));
  }
  return {};
}

IoResult<void> SessionRecorder::changeLayout(int channelCount, const drivers::DeviceInfo* latest) {
  drivers::DeviceInfo next =
      withChannelCount(latest && latest->channelCount == channelCount ? *latest : layout_, channelCount);
  auto index = writer_.appendLayoutChange(next, device_);
  if (!index) return std::unexpected(sessionWriterError(path(), index.error()));
  device_ = *index;
  layout_ = std::move(next);
  ++layoutChanges_;
  return {};
}

IoResult<void> SessionRecorder::appendCounters(const drivers::DeviceSessionStats& stats) {
  std::vector<sim::SessionCounter> counters;
  for (const drivers::NamedCounter& c : drivers::namedCounters(stats)) counters.push_back({c.name, c.value});
  if (auto r = writer_.appendCounters(0, counters); !r) return std::unexpected(sessionWriterError(path(), r.error()));
  return {};
}

IoResult<void> SessionRecorder::appendCalibration(const calibration::Calibration& calibration) {
  return app::appendCalibration(writer_, calibration);
}

IoResult<void> SessionRecorder::close() {
  if (auto r = writer_.close(); !r) return std::unexpected(sessionWriterError(path(), r.error()));
  return {};
}

drivers::DeviceInfo withChannelCount(drivers::DeviceInfo device, int channelCount) {
  if (device.channelCount == channelCount) return device;
  device.channelCount = channelCount;
  device.channelNames.clear();
  for (int i = 0; i < channelCount; ++i) device.channelNames.push_back("ch" + std::to_string(i));
  return device;
}

std::string countersSummary(const drivers::DeviceSessionStats& stats) {
  std::string out;
  for (const drivers::NamedCounter& c : drivers::namedCounters(stats)) {
    if (!out.empty()) out += ", ";
    out += std::string(c.label) + ": " + std::to_string(c.value);
  }
  return out;
}

std::filesystem::path newTakePath(const std::filesystem::path& dir, std::time_t when) {
  std::tm tm{};
  localtime_r(&when, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "take-%Y%m%d-%H%M%S", &tm);
  std::filesystem::path path = dir / (std::string(stamp) + ".session");
  for (int n = 2; std::filesystem::exists(path); ++n)
    path = dir / (std::string(stamp) + "-" + std::to_string(n) + ".session");
  return path;
}

}  // namespace imps::app
