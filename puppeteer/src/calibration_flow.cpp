// SPDX-License-Identifier: MIT
// Joint-offset calibration over a live sample stream (see calibration_flow.h).
#include "calibration_flow.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "imps/utf8.h"

namespace imps::app {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

// A JSON string literal (the info fields are paths and names; a serial number is whatever bytes the device sent, so
// ill-formed UTF-8 becomes U+FFFD: JSON text must be UTF-8).
std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (char c : toValidUtf8(text)) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string utcNow() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace

std::string calibrationInfoJson(const std::string& scene, const std::string& rig, const std::string& source,
                                double windowMs, size_t samples, const std::string& serialNumber) {
  std::string info = "{\"created\":" + jsonString(utcNow()) + ",\"scene\":" + jsonString(scene) +
                     ",\"rig\":" + jsonString(rig) + ",\"source\":" + jsonString(source) +
                     ",\"window_ms\":" + std::to_string(windowMs) + ",\"samples\":" + std::to_string(samples);
  if (!serialNumber.empty()) info += ",\"serial\":" + jsonString(serialNumber);
  return info + "}";
}

void CalibrationFlow::start(int64_t nowNs) {
  window_.clear();
  windowStartNs_ = nowNs + static_cast<int64_t>(options_.delayMs * 1e6);
  windowEndNs_ = windowStartNs_ + static_cast<int64_t>(options_.windowMs * 1e6);
  phase_ = options_.delayMs > 0 ? Phase::Countdown : Phase::Averaging;
}

bool CalibrationFlow::update(std::span<const drivers::Sample> samples, int64_t nowNs) {
  if (!active()) return false;
  for (const drivers::Sample& s : samples)
    if (s.arrivalTimeNs >= windowStartNs_ && s.arrivalTimeNs < windowEndNs_) window_.push_back(s);
  if (nowNs >= windowStartNs_) phase_ = Phase::Averaging;
  if (nowNs < windowEndNs_) return false;
  phase_ = Phase::Complete;
  return true;
}

void CalibrationFlow::reset() {
  window_.clear();
  phase_ = Phase::Idle;
}

std::string CalibrationFlow::progress(int64_t nowNs) const {
  char buf[128];
  if (phase_ == Phase::Countdown) {
    std::snprintf(buf, sizeof buf, "hold the calibration pose still: averaging in %.1fs",
                  std::max(0.0, double(windowStartNs_ - nowNs) * 1e-9));
  } else if (phase_ == Phase::Averaging) {
    std::snprintf(buf, sizeof buf, "calibrating: averaging %.1f of %.1fs (%zu samples)",
                  std::clamp(double(nowNs - windowStartNs_) * 1e-9, 0.0, options_.windowMs * 1e-3),
                  options_.windowMs * 1e-3, window_.size());
  } else {
    return {};
  }
  return buf;
}

std::expected<CalibrationResult, Diagnostics> calibrateWindow(
    const calibration::RigMap& rig, std::span<const drivers::Sample> window, const drivers::DeviceInfo& device,
    const Character& character, double maxNoiseDeg, std::string infoJson) {
  calibration::WindowOptions wo;
  wo.maxStdDev = maxNoiseDeg * kDegree;
  wo.device = &device;
  calibration::WindowAverage average;
  auto calibrated = calibration::calibrateOffsets(rig, window, wo, &average);
  if (!calibrated) return std::unexpected(calibrated.error());
  calibrated->info = std::move(infoJson);
  calibrated->device = device.name;
  auto cal = calibration::Calibration::create(std::move(*calibrated), &character, &device);
  if (!cal) return std::unexpected(cal.error());
  CalibrationResult result{std::move(*cal), 0.0, {}};
  for (const calibration::ChannelAverage& c : average.channels) {
    if (c.stdDevRadians / kDegree >= result.maxNoiseDeg) {
      result.maxNoiseDeg = c.stdDevRadians / kDegree;
      result.noisiestChannel = c.label;
    }
  }
  return result;
}

}  // namespace imps::app
