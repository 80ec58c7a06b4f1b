// Recording a live device in the app (see session_recorder.h).
#include "session_recorder.h"

#include <ctime>

#include "session_calibration.h"

namespace imps::app {

std::expected<SessionRecorder, std::string> SessionRecorder::create(const std::filesystem::path& path,
                                                                    const drivers::DeviceInfo& device,
                                                                    const calibration::Calibration* calibration,
                                                                    sim::SessionWriterOptions options) {
  auto writer = sim::SessionWriter::create(path, device, options);
  if (!writer) return std::unexpected(writer.error());
  SessionRecorder recorder(std::move(*writer), device.channelCount);
  if (calibration) {
    if (auto r = recorder.appendCalibration(*calibration); !r) return std::unexpected(r.error());
  }
  return recorder;
}

std::expected<void, std::string> SessionRecorder::append(std::span<const drivers::Sample> samples) {
  for (const drivers::Sample& s : samples) {
    if (s.channelCount != channelCount_) {
      ++skipped_;
      continue;
    }
    if (auto r = writer_.append(s); !r) return r;
  }
  return {};
}

std::expected<void, std::string> SessionRecorder::appendCalibration(const calibration::Calibration& calibration) {
  return app::appendCalibration(writer_, calibration);
}

std::expected<void, std::string> SessionRecorder::close() { return writer_.close(); }

std::filesystem::path newTakePath(const std::filesystem::path& dir, std::time_t when) {
  std::tm tm{};
  localtime_r(&when, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "take-%Y%m%d-%H%M%S", &tm);
  std::filesystem::path path = dir / (std::string(stamp) + ".session");
  for (int n = 2; std::filesystem::exists(path); ++n) path = dir / (std::string(stamp) + "-" + std::to_string(n) + ".session");
  return path;
}

}  // namespace imps::app
