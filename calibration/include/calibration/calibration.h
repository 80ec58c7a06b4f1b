// SPDX-License-Identifier: MIT
// Calibrated conversion of raw Samples to a Pose: per channel, angle = sign * wrap(count - offset) / gain, clamped
// to the limits; per joint, the pose rotation is rest * R(order), the axis rotations composed in the joint's order.
// Translation channels (axes tx, ty, tz) read metres the same way and move the joint from its rest translation.
// `Calibration` is the stateless free conversion; `Calibrator` adds deadband, smoothing and hold-last-good across
// samples. The math is in docs/calibration.md.
#pragma once

#include <expected>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "calibration/rig_map.h"
#include "drivers/sample.h"
#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/io_error.h"
#include "imps/skeleton_cache.h"

namespace imps::calibration {

// The signed difference count - offset in counts. Absolute encoders: the shortest way round the turn of
// `countsPerTurn` counts, in [-turn/2, turn/2). Linear sensors: the plain difference.
double countDelta(double count, double offset, double countsPerTurn, EncoderKind encoder);

// A rig map whose every channel has an offset and a device channel index, bound to a character's rest rotations.
// Immutable once made; apply() may be called from any number of threads.
class Calibration {
 public:
  // Errors (at the map's locations): a channel without an offset or with an unresolved channel name, and
  // everything validateRigMap reports against `character` (may be null: rest rotations are then the identity
  // and joint names are not checked). The character is only read here, not kept.
  // `devices`: every device of a session (RigMapContext::devices), so channels of any of them can be mapped.
  static std::expected<Calibration, Diagnostics> create(RigMap map, const Character* character = nullptr,
                                                        const drivers::DeviceInfo* device = nullptr,
                                                        std::span<const drivers::DeviceInfo> devices = {});
  // parseRigMap(json, name, {character, device, requireOffsets = true}) + create(). The session blob reader.
  static std::expected<Calibration, Diagnostics> parse(std::string_view json, std::string_view name,
                                                       const Character* character = nullptr,
                                                       const drivers::DeviceInfo* device = nullptr,
                                                       std::span<const drivers::DeviceInfo> devices = {});
  static std::expected<Calibration, Diagnostics> readFile(const std::filesystem::path& path,
                                                          const Character* character = nullptr,
                                                          const drivers::DeviceInfo* device = nullptr,
                                                          std::span<const drivers::DeviceInfo> devices = {});

  const RigMap& rigMap() const { return map_; }
  // The calibration file / session blob text (toJson of the map); parse(toJson()) gives an equal calibration.
  std::string toJson() const { return calibration::toJson(map_); }
  // toJson() written with imps::writeFileAtomically (atomic_file.h), failing as it does.
  IoResult<void> save(const std::filesystem::path& path) const;

  // Angle in radians of mapping i (index into rigMap().channels) for a raw count, before limits; metres for a
  // translation channel.
  double rawAngle(size_t i, double count) const;
  // rawAngle clamped to the mapping's limits.
  double angle(size_t i, double count) const;

  // The pose for one sample of device 0 (channels of other devices read as the calibration pose): every driven joint,
  // rotation = rest * calibrated rotation; a joint with translation channels also gets translation = rest translation +
  // the channels' metres along their axes of the parent's frame (hasTranslation), the others none. A channel that is
  // beyond the sample's channelCount or flagged NotConnected / Outlier reads as the calibration pose (angle 0;
  // Calibrator holds the previous angle instead). Deadband and smoothing are not applied here.
  std::vector<JointPose> apply(const drivers::Sample& sample) const;
  // The pose for per-mapping angles (radians, one per rigMap().channels entry), written into `out` (resized).
  void compose(std::span<const double> angles, std::vector<JointPose>& out) const;
  // The calibrated rotation of joint entry j (rigMap().joints[j]) without the rest rotation.
  glm::dquat jointRotation(size_t j, std::span<const double> angles) const;

 private:
  RigMap map_;
  std::vector<glm::quat> rest_;  // per rigMap().joints entry
  std::vector<glm::vec3> restTranslation_;  // per rigMap().joints entry, metres in the parent's frame
};

// Stateful conversion across a stream of samples, for the frame loop. Per mapping: clamp, then deadband (the output
// moves only once the clamped angle is more than `deadband` from the value held, and then takes the new angle whole,
// so jitter within the deadband never reaches the character and nothing lags), then a one-pole low-pass with time
// constant smoothingMs using the samples' timestamps (device time when it advances, else arrival time; 1 ms when
// neither advances). Channels flagged NotConnected / Outlier, or missing from the sample, keep their previous angle (0
// before the first good reading). The first good reading of a channel is taken as is. Not thread-safe: one owner.
class Calibrator {
 public:
  explicit Calibrator(Calibration calibration);

  // Converts one sample of device 0; the returned pose stays valid until the next update()/reset().
  const std::vector<JointPose>& update(const drivers::Sample& sample) { return update(0, sample); }
  // Converts one sample of session device `device`: only the mappings on that device take new readings (their own
  // timestamps drive their smoothing); the others keep their angles.
  const std::vector<JointPose>& update(uint16_t device, const drivers::Sample& sample);
  // Current per-mapping angles (radians), after deadband and smoothing.
  std::span<const double> angles() const { return output_; }
  const std::vector<JointPose>& pose() const { return pose_; }
  const Calibration& calibration() const { return calibration_; }
  // Forgets every channel's history (after a re-calibration or a seek).
  void reset();

 private:
  Calibration calibration_;
  std::vector<double> held_;    // after deadband
  std::vector<double> output_;  // after smoothing
  std::vector<bool> seen_;
  std::vector<bool> havePrevious_;  // per device
  std::vector<int64_t> previousDeviceNs_, previousArrivalNs_;
  std::vector<JointPose> pose_;
};

}  // namespace imps::calibration
