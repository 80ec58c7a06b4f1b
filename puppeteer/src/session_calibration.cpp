// SPDX-License-Identifier: MIT
// Calibrations stored in recorded sessions (see session_calibration.h).
#include "session_calibration.h"

namespace imps::app {

IoError sessionWriterError(const std::filesystem::path& path, const Diagnostics& error) {
  if (error.all().empty()) return IoError{path.string(), "cannot write"};
  return IoError{error.all().front().loc.file, error.all().front().message};
}

IoResult<void> appendCalibration(sim::SessionWriter& writer, const calibration::Calibration& c) {
  auto r = writer.appendCalibration(c.toJson());
  if (!r) return std::unexpected(sessionWriterError(writer.path(), r.error()));
  return {};
}

bool isBvhChannelMapping(std::string_view json) {
  return json.find("\"source\":\"bvh\"") != std::string_view::npos &&
         json.find("\"version\"") == std::string_view::npos;
}

std::expected<std::optional<calibration::Calibration>, Diagnostics> calibrationForSample(
    const sim::Session& session, size_t sampleIndex, const Character* character, const std::string& sessionName) {
  const sim::SessionCalibration* found = nullptr;
  size_t number = 0;
  for (size_t i = 0; i < session.calibrations.size(); ++i) {
    if (session.calibrations[i].firstSample > sampleIndex || isBvhChannelMapping(session.calibrations[i].json))
      continue;
    if (!found || session.calibrations[i].firstSample >= found->firstSample) {
      found = &session.calibrations[i];
      number = i;
    }
  }
  if (!found) return std::optional<calibration::Calibration>{};
  const drivers::DeviceInfo* device = nullptr;
  if (sampleIndex < session.sampleDevice.size() && session.sampleDevice[sampleIndex] < session.devices.size())
    device = &session.devices[session.sampleDevice[sampleIndex]];
  else if (!session.devices.empty())
    device = &session.devices[0];
  auto cal = calibration::Calibration::parse(found->json, sessionName + " calibration #" + std::to_string(number),
                                             character, device, session.devices);
  if (!cal) return std::unexpected(cal.error());
  return std::optional<calibration::Calibration>(std::move(*cal));
}

}  // namespace imps::app
