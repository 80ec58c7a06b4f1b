// SPDX-License-Identifier: MIT
// Joint-offset calibration as a flow over a live sample stream, shared by `puppeteer calibrate` and the live app's
// `k` key: a countdown while the performer gets into the calibration pose, a window of samples, then the calibration
// library's calibrateOffsets (average, reject a noisy window, set offsets) and Calibration::create.
// Workflow in docs/calibration.md; the maths in calibration/offset_calibration.h.
#pragma once

#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <vector>

#include "calibration/calibration.h"
#include "calibration/offset_calibration.h"
#include "calibration/rig_map.h"
#include "drivers/sample.h"
#include "imps/character.h"

namespace imps::app {

struct CalibrationFlowOptions {
  double delayMs = 3000;     // countdown after the key, to get into the pose
  double windowMs = 500;     // how long to average
  double maxNoiseDeg = 0.5;  // reject the window when a channel's standard deviation exceeds this
};

// The calibration's "info" object as `puppeteer calibrate` writes it: when (UTC), the scene, the rig, the sample
// source, the window and its sample count, and the device's serial number when it has one. A JSON object's text.
std::string calibrationInfoJson(const std::string& scene, const std::string& rig, const std::string& source,
                                double windowMs, size_t samples, const std::string& serialNumber);

// The window collector. Times are on the samples' arrivalTimeNs clock (std::chrono::steady_clock). Not
// thread-safe: the frame loop owns it.
class CalibrationFlow {
 public:
  enum class Phase { Idle, Countdown, Averaging, Complete };
  explicit CalibrationFlow(CalibrationFlowOptions options = {}) : options_(options) {}

  // Starts (or restarts) the countdown at `nowNs`; the window covers [now + delay, now + delay + window).
  void start(int64_t nowNs);
  // Feeds the samples drained since the last call (in order) and advances the phase; returns true exactly once, when
  // the window has closed (phase() is then Complete and window() holds its samples).
  bool update(std::span<const drivers::Sample> samples, int64_t nowNs);
  // Back to Idle, dropping the window.
  void reset();

  Phase phase() const { return phase_; }
  bool active() const { return phase_ == Phase::Countdown || phase_ == Phase::Averaging; }
  const std::vector<drivers::Sample>& window() const { return window_; }
  const CalibrationFlowOptions& options() const { return options_; }
  // For the HUD: "hold the calibration pose still: averaging in 2.4s" / "calibrating: averaging 0.2 of
  // 0.5s (180 samples)".
  std::string progress(int64_t nowNs) const;

 private:
  CalibrationFlowOptions options_;
  Phase phase_ = Phase::Idle;
  int64_t windowStartNs_ = 0, windowEndNs_ = 0;
  std::vector<drivers::Sample> window_;
};

// The outcome of a window: the new calibration (offsets from the window's means, checked against the character and
// the device) and the largest channel noise; or the reasons the window was rejected, one diagnostic each (the
// window's problems without a location, or Calibration::create's diagnostics).
struct CalibrationResult {
  calibration::Calibration calibration;
  double maxNoiseDeg = 0;
  std::string noisiestChannel;
};
std::expected<CalibrationResult, Diagnostics> calibrateWindow(
    const calibration::RigMap& rig, std::span<const drivers::Sample> window, const drivers::DeviceInfo& device,
    const Character& character, double maxNoiseDeg, std::string infoJson);

}  // namespace imps::app
