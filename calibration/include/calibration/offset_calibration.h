// SPDX-License-Identifier: MIT
// Joint-offset calibration (thesis figure 5-4): average a window of samples taken while the armature is held in the
// character's calibration pose, reject a noisy window, set every channel's offset; optionally check signs and gains
// against a second known pose. Workflow in docs/calibration.md.
#pragma once

#include <expected>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "calibration/calibration.h"
#include "calibration/rig_map.h"
#include "drivers/sample.h"
#include "imps/character.h"
#include "imps/diagnostic.h"

namespace imps::calibration {

struct WindowOptions {
  // A channel whose readings spread more than this (standard deviation, radians through its gain) makes the window
  // too noisy: the armature was moving, or the encoder is faulty.
  double maxStdDev = 0.5 * 3.14159265358979323846 / 180.0;
  // Fewer valid readings than this for any channel rejects the window.
  size_t minSamples = 5;
  // For channel names in reports (may be null).
  const drivers::DeviceInfo* device = nullptr;
};

// One mapped channel over a window.
struct ChannelAverage {
  size_t mapping = 0;       // index into RigMap::channels
  std::string label;        // "channel 7 'L_elbow'"
  double mean = 0;          // counts; absolute encoders: circular mean, in [0, 2^bits)
  double stdDev = 0;        // counts (absolute: of the shortest differences from the mean)
  double stdDevRadians = 0; // stdDev / gain
  size_t samples = 0;       // valid readings used (NotConnected / Outlier readings are skipped)
};

struct WindowAverage {
  std::vector<ChannelAverage> channels;  // one per RigMap::channels entry, same order
  std::vector<std::string> problems;     // why the window is rejected, one line per channel; empty when usable
  bool ok() const { return problems.empty(); }
};

// Averages every mapped channel over `samples`. Absolute encoders use the circular mean (a window straddling the
// 0 / 2^bits wrap averages to the wrap, not to mid-scale). Problems: no samples, a channel with too few valid
// readings, a channel noisier than options.maxStdDev (named, with its spread in degrees and counts).
WindowAverage averageWindow(const RigMap& map, std::span<const drivers::Sample> samples,
                            const WindowOptions& options = {});

// Sets every channel's offset to the window's mean (the calibration pose reads as angle 0). Returns the
// calibrated map, or the window's problems: one error each, in WindowAverage::problems' order, without a location
// (a window of samples is not a file). `report`, when given, receives the averages either way.
std::expected<RigMap, Diagnostics> calibrateOffsets(RigMap map, std::span<const drivers::Sample> samples,
                                                    const WindowOptions& options = {}, WindowAverage* report = nullptr);

// One target of a check pose: joint `joint` should be at `angle` radians about `axis` (the calibrated angle,
// i.e. relative to the calibration pose).
struct PoseTarget {
  std::string joint;
  Axis axis = Axis::X;
  double angle = 0;
  SourceLoc loc;
};

// Parses a check-pose file: {"version": 1, "pose": "elbows bent", "joints": {"L_Forearm": {"y_deg": -90}, …}}
// (axes x|y|z in radians or x_deg|y_deg|z_deg in degrees). Unknown joints (given a character) and fields are
// errors with suggestions, as in rig maps.
std::expected<std::vector<PoseTarget>, Diagnostics> parseCheckPose(std::string_view json, std::string_view fileName,
                                                                   const Character* character = nullptr);
std::expected<std::vector<PoseTarget>, Diagnostics> readCheckPoseFile(const std::filesystem::path& path,
                                                                      const Character* character = nullptr);

struct CheckOptions {
  double gainTolerance = 0.2;  // |measured / target| outside [1 - t, 1 + t] means mis-scaled
  // Targets smaller than this (radians) cannot tell a sign or a gain apart from noise; they are skipped.
  double minTarget = 10.0 * 3.14159265358979323846 / 180.0;
};

struct ChannelCheck {
  size_t mapping = 0;
  std::string label;
  double target = 0;     // radians
  double measured = 0;   // radians through the calibration, before limits
  double ratio = 0;      // measured / target
  bool reversed = false;   // ratio < 0: the sign looks wrong
  bool misScaled = false;  // |ratio| off by more than the tolerance: the gain looks wrong
  double suggestedGain = 0;  // gain * |ratio|: the gain that would read the target
};

struct PoseCheck {
  std::vector<ChannelCheck> channels;  // one per target that a channel drives
  std::vector<std::string> problems;   // reversed / mis-scaled channels, one line each, with the suggested fix
  std::vector<std::string> warnings;   // targets no channel drives, targets too small to judge
  bool ok() const { return problems.empty(); }
};

// Compares a window averaged in the check pose with its targets through `calibration`.
PoseCheck checkPose(const Calibration& calibration, const WindowAverage& window, std::span<const PoseTarget> targets,
                    const CheckOptions& options = {});

}  // namespace imps::calibration
