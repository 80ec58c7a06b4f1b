// SPDX-License-Identifier: MIT
// Counts → angles → joint rotations (Calibration), and the stateful per-stream filter (Calibrator).
#include "calibration/calibration.h"

#include "imps/atomic_file.h"

#include <algorithm>
#include <cmath>

namespace imps::calibration {

double countDelta(double count, double offset, double countsPerTurn, EncoderKind encoder) {
  double d = count - offset;
  if (encoder == EncoderKind::Linear) return d;
  // Shortest signed difference on a circle of countsPerTurn counts: [-turn/2, turn/2).
  d = std::fmod(d, countsPerTurn);
  if (d >= countsPerTurn / 2) d -= countsPerTurn;
  if (d < -countsPerTurn / 2) d += countsPerTurn;
  return d;
}

std::expected<Calibration, Diagnostics> Calibration::create(RigMap map, const Character* character,
                                                            const drivers::DeviceInfo* device,
                                                            std::span<const drivers::DeviceInfo> devices) {
  Diagnostics diags;
  RigMapContext ctx{character, device, true, devices};
  validateRigMap(map, ctx, diags);
  for (const ChannelMap& c : map.channels)
    if (c.channel < 0)
      diags.error(c.loc, "channel '" + c.channelName +
                             "' is named but no device description is at hand to find its index: use an index");
  if (diags.hasErrors()) return std::unexpected(diags);
  Calibration cal;
  cal.map_ = std::move(map);
  for (const JointMap& jm : cal.map_.joints) {
    Rigid rest;
    if (character) {
      const int j = character->findJoint(jm.joint);
      if (j >= 0) rest = character->joints()[static_cast<size_t>(j)].rest;
    }
    cal.rest_.push_back(rest.rotation);
    cal.restTranslation_.push_back(rest.translation);
  }
  return cal;
}

std::expected<Calibration, Diagnostics> Calibration::parse(std::string_view json, std::string_view name,
                                                           const Character* character,
                                                           const drivers::DeviceInfo* device,
                                                           std::span<const drivers::DeviceInfo> devices) {
  auto map = parseRigMap(json, name, RigMapContext{character, device, true, devices});
  if (!map) return std::unexpected(map.error());
  return create(std::move(*map), character, device, devices);
}

std::expected<Calibration, Diagnostics> Calibration::readFile(const std::filesystem::path& path,
                                                              const Character* character,
                                                              const drivers::DeviceInfo* device,
                                                              std::span<const drivers::DeviceInfo> devices) {
  auto map = readRigMapFile(path, RigMapContext{character, device, true, devices});
  if (!map) return std::unexpected(map.error());
  return create(std::move(*map), character, device, devices);
}

IoResult<void> Calibration::save(const std::filesystem::path& path) const {
  return imps::writeFileAtomically(path.string(), toJson());
}

double Calibration::rawAngle(size_t i, double count) const {
  const ChannelMap& c = map_.channels[i];
  return c.sign * countDelta(count, *c.offset, map_.countsPerTurn(), c.encoder) / c.gain;
}

double Calibration::angle(size_t i, double count) const {
  const ChannelMap& c = map_.channels[i];
  return std::clamp(rawAngle(i, count), c.minAngle, c.maxAngle);
}

glm::dquat Calibration::jointRotation(size_t j, std::span<const double> angles) const {
  const JointMap& jm = map_.joints[j];
  glm::dquat r{1.0, 0.0, 0.0, 0.0};
  for (char a : jm.order) {
    const Axis axis = static_cast<Axis>(a - 'X');
    double theta = 0;
    for (size_t i : jm.mappings)
      if (map_.channels[i].axis == axis && !map_.channels[i].translation) theta = angles[i];
    glm::dvec3 unit{0.0};
    unit[static_cast<int>(axis)] = 1.0;
    r = r * glm::angleAxis(theta, unit);
  }
  return r;
}

void Calibration::compose(std::span<const double> angles, std::vector<JointPose>& out) const {
  out.resize(map_.joints.size());
  for (size_t j = 0; j < map_.joints.size(); ++j) {
    JointPose& p = out[j];
    if (p.joint != map_.joints[j].joint) p.joint = map_.joints[j].joint;  // no per-frame string copies
    p.rotation = glm::normalize(rest_[j] * glm::quat(jointRotation(j, angles)));
    p.hasTranslation = false;
    p.translation = restTranslation_[j];
    for (size_t i : map_.joints[j].mappings) {
      if (!map_.channels[i].translation) continue;
      p.hasTranslation = true;
      p.translation[static_cast<int>(map_.channels[i].axis)] += static_cast<float>(angles[i]);
    }
  }
}

namespace {

bool usable(const drivers::Sample& s, int channel) {
  return channel >= 0 && channel < s.channelCount &&
         s.flags[static_cast<size_t>(channel)] == drivers::ChannelFlag::Valid;
}

}  // namespace

std::vector<JointPose> Calibration::apply(const drivers::Sample& sample) const {
  std::vector<double> angles(map_.channels.size(), 0.0);
  for (size_t i = 0; i < map_.channels.size(); ++i) {
    const int ch = map_.channels[i].channel;
    if (map_.channels[i].device == 0 && usable(sample, ch))
      angles[i] = angle(i, sample.counts[static_cast<size_t>(ch)]);
  }
  std::vector<JointPose> pose;
  compose(angles, pose);
  return pose;
}

Calibrator::Calibrator(Calibration calibration) : calibration_(std::move(calibration)) { reset(); }

void Calibrator::reset() {
  const size_t n = calibration_.rigMap().channels.size();
  held_.assign(n, 0.0);
  output_.assign(n, 0.0);
  seen_.assign(n, false);
  havePrevious_.clear();
  previousDeviceNs_.clear();
  previousArrivalNs_.clear();
  calibration_.compose(output_, pose_);
}

const std::vector<JointPose>& Calibrator::update(uint16_t device, const drivers::Sample& sample) {
  // Time since the device's previous sample: its clock when it advances, else the host's, else a nominal 1 ms.
  if (device >= havePrevious_.size()) {
    havePrevious_.resize(device + 1u, false);
    previousDeviceNs_.resize(device + 1u, 0);
    previousArrivalNs_.resize(device + 1u, 0);
  }
  double dtMs = 1.0;
  if (havePrevious_[device]) {
    if (sample.deviceTimeNs > previousDeviceNs_[device])
      dtMs = static_cast<double>(sample.deviceTimeNs - previousDeviceNs_[device]) * 1e-6;
    else if (sample.arrivalTimeNs > previousArrivalNs_[device])
      dtMs = static_cast<double>(sample.arrivalTimeNs - previousArrivalNs_[device]) * 1e-6;
  }
  havePrevious_[device] = true;
  previousDeviceNs_[device] = sample.deviceTimeNs;
  previousArrivalNs_[device] = sample.arrivalTimeNs;

  const RigMap& map = calibration_.rigMap();
  for (size_t i = 0; i < map.channels.size(); ++i) {
    const ChannelMap& c = map.channels[i];
    if (c.device != device || !usable(sample, c.channel)) continue;  // hold the previous angle
    const double a = calibration_.angle(i, sample.counts[static_cast<size_t>(c.channel)]);
    if (!seen_[i]) {
      seen_[i] = true;
      held_[i] = output_[i] = a;
      continue;
    }
    // Deadband: jitter within it never moves the held value.
    if (std::abs(a - held_[i]) > c.deadband) held_[i] = a;
    // One-pole low-pass: y += (1 - e^(-dt/tau)) (x - y).
    if (c.smoothingMs > 0) output_[i] += (1.0 - std::exp(-dtMs / c.smoothingMs)) * (held_[i] - output_[i]);
    else output_[i] = held_[i];
  }
  calibration_.compose(output_, pose_);
  return pose_;
}

}  // namespace imps::calibration
