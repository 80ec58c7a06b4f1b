// SPDX-License-Identifier: MIT
// Session channels → joints by name, and the replay thread feeding the frame loop.
#include "viewer_replay.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string_view>
#include <utility>

#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "imps/clock.h"

namespace imps::app {

ChannelPoseMap::ChannelPoseMap(const sim::Session& session, const Character& character) {
  size_t slot = 0;
  for (size_t d = 0; d < session.devices.size(); ++d) {
    const sim::DeviceInfo& info = session.devices[d];
    firstSlot_.push_back(slot);
    bits_.push_back(info.bitsPerChannel);
    for (int c = 0; c < info.channelCount; ++c, ++slot) {
      const std::string name = c < static_cast<int>(info.channelNames.size()) ? info.channelNames[size_t(c)] : "";
      // "<joint>:<channel>"; joint names may themselves contain ':' (mixamorig:Hips), so split at the last one.
      const size_t colon = name.rfind(':');
      const std::string_view channel =
          colon == std::string::npos ? std::string_view{} : std::string_view(name).substr(colon + 1);
      const int axis = channel == "Xrotation" ? 0 : channel == "Yrotation" ? 1 : channel == "Zrotation" ? 2 : -1;
      const int joint = axis < 0 ? -1 : character.findJoint(std::string_view(name).substr(0, colon));
      if (joint < 0) {
        unmatched_.push_back(name);
        continue;
      }
      auto it = std::find_if(joints_.begin(), joints_.end(), [&](const MappedJoint& m) { return m.joint == joint; });
      if (it == joints_.end()) {
        joints_.push_back({joint, character.joints()[size_t(joint)].rest.rotation, {}});
        it = joints_.end() - 1;
      }
      it->channels.push_back({slot, axis});
    }
  }
  angles_.assign(slot, 0.0);
}

size_t ChannelPoseMap::mappedChannels() const {
  size_t n = 0;
  for (const MappedJoint& m : joints_) n += m.channels.size();
  return n;
}

void ChannelPoseMap::apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton) {
  if (device >= firstSlot_.size()) return;
  const size_t first = firstSlot_[device];
  const size_t end = device + 1u < firstSlot_.size() ? firstSlot_[device + 1u] : angles_.size();
  const size_t count = std::min<size_t>(end - first, sample.channelCount);
  for (size_t c = 0; c < count; ++c)
    if (sample.flags[c] == drivers::ChannelFlag::Valid)
      angles_[first + c] = sim::countsToDegrees(sample.counts[c], bits_[device]);
  static const glm::vec3 kAxes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const MappedJoint& m : joints_) {
    glm::quat q = m.rest;
    for (const Channel& ch : m.channels)
      q = q * glm::angleAxis(static_cast<float>(glm::radians(angles_[ch.slot])), kAxes[ch.axis]);
    skeleton.setRotation(m.joint, q);
  }
}

ReplayThread::ReplayThread(const sim::Session& session, double speed) : session_(session), speed_(speed) {
  for (size_t d = 0; d < std::max<size_t>(1, session.devices.size()); ++d)
    mailboxes_.push_back(std::make_unique<drivers::PoseMailbox>());
  sim::ReplayOptions options;
  options.speed = speed_;
  options.rewriteArrivalTime = true;
  options.maxSleepNs = 20'000'000;
  replay_ = std::make_unique<sim::SessionReplay>(session_, clock_, options);
  thread_ = std::thread([this] { run(); });
}

ReplayThread::~ReplayThread() {
  stop_.store(true, std::memory_order_relaxed);
  replay_->stop();
  thread_.join();
}

void ReplayThread::run() {
  while (!stop_.load(std::memory_order_relaxed) && !session_.samples.empty()) {
    replay_->seek(0);
    replay_->run([this](uint16_t device, const drivers::Sample& sample) {
      if (device < mailboxes_.size()) mailboxes_[device]->publish(sample);
      return !stop_.load(std::memory_order_relaxed);
    });
    loops_.fetch_add(1, std::memory_order_relaxed);
  }
}

}  // namespace imps::app

namespace imps::app {
SampleMapper::SampleMapper(const sim::Session& devices, const Character& character) {
  byName_.emplace(devices, character);
}

SampleMapper::SampleMapper(calibration::Calibration calibration, std::string label) : label_(std::move(label)) {
  calibrator_.emplace(std::move(calibration));
}

SampleMapper::SampleMapper(ClipPoseMap clip, std::string label) : label_(std::move(label)) {
  clip_.emplace(std::move(clip));
}

std::expected<ClipPoseMap, Diagnostics> ClipPoseMap::create(const sim::Session& session, const Character& character,
                                                            const RetargetOptions& options) {
  auto fail = [](std::string message) {
    Diagnostics d;
    d.error({}, std::move(message));
    return std::unexpected(std::move(d));
  };
  if (!session.skeleton) return fail("the session has no skeleton (it was not made from a BVH clip)");
  auto parsed = sim::readBvhText(session.skeleton->bvh, "session skeleton");
  if (!parsed) return std::unexpected(parsed.error());
  ClipPoseMap m;
  m.clip_ = std::move(*parsed);
  m.unitsPerCount_ = session.skeleton->positionUnitsPerCount;
  size_t slots = 0;
  for (const sim::DeviceInfo& info : session.devices) {
    m.firstSlot_.push_back(slots);
    m.bits_.push_back(info.bitsPerChannel);
    slots += static_cast<size_t>(info.channelCount);
  }
  if (slots != m.clip_.channelCount())
    return fail("the skeleton has " + std::to_string(m.clip_.channelCount()) + " channels but the devices " +
                std::to_string(slots));
  for (const sim::BvhJoint& j : m.clip_.joints)
    for (sim::BvhChannel c : j.channels) m.rotation_.push_back(sim::isRotation(c));
  m.values_.assign(slots, 0.0f);
  // The first frame (every device's first sample) is the reference for translations.
  std::vector<bool> seen(session.devices.size(), false);
  for (size_t i = 0; i < session.samples.size(); ++i) {
    const uint16_t d = session.sampleDevice[i];
    if (d >= seen.size() || seen[d]) continue;
    seen[d] = true;
    m.read(d, session.samples[i]);
  }
  auto r = Retargeter::create(m.clip_, character, options);
  if (!r) return std::unexpected(r.error());
  r->setReferenceFrame(m.values_);
  m.retargeter_.emplace(std::move(*r));
  return m;
}

void ClipPoseMap::read(uint16_t device, const drivers::Sample& sample) {
  if (device >= firstSlot_.size()) return;
  const size_t first = firstSlot_[device];
  const size_t end = device + 1u < firstSlot_.size() ? firstSlot_[device + 1u] : values_.size();
  const size_t count = std::min<size_t>(end - first, sample.channelCount);
  for (size_t c = 0; c < count; ++c)
    if (sample.flags[c] == drivers::ChannelFlag::Valid)
      values_[first + c] = static_cast<float>(
          sessionChannelValue(sample.counts[c], rotation_[first + c], bits_[device], unitsPerCount_));
}

void ClipPoseMap::apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton) {
  read(device, sample);
  retargeter_->pose(values_, pose_);
  skeleton.setPose(pose_);
}

void SampleMapper::apply(uint16_t device, const drivers::Sample& sample, SkeletonCache& skeleton) {
  if (byName_) {
    byName_->apply(device, sample, skeleton);
  } else if (clip_) {
    clip_->apply(device, sample, skeleton);
  } else {
    skeleton.setPose(calibrator_->update(device, sample));
  }
}

size_t SampleMapper::mappedJoints() const {
  if (clip_) return clip_->retargeter().report().mapped();
  return byName_ ? byName_->mappedJoints() : calibrator_->calibration().rigMap().joints.size();
}

std::string SampleMapper::describe() const {
  const std::string how = byName_ ? std::string("channel names") : clip_ ? "clip retargeted (" + label_ + ")"
                                                                       : "calibration " + label_;
  return how + ", " + std::to_string(mappedJoints()) + " joints";
}

ReplayPoseSource::ReplayPoseSource(const sim::Session& session, SampleMapper mapper, double speed, std::string name)
    : map_(std::move(mapper)), thread_(session, speed), name_(std::move(name)), speed_(speed) {
  rateWindowStartNs_ = steadyNowNs();
}

bool ReplayPoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  bool any = false;
  int64_t newest = 0;
  for (size_t d = 0; d < thread_.devices(); ++d) {
    if (!thread_.mailbox(d).latest(sample_)) continue;
    map_.apply(static_cast<uint16_t>(d), sample_, skeleton);
    newest = std::max(newest, sample_.arrivalTimeNs);
    any = true;
  }
  if (any && arrivalNs) *arrivalNs = newest;
  return any;
}

void ReplayPoseSource::describe(HudInfo& info) {
  const drivers::PoseMailboxStats stats = thread_.mailbox(0).stats();
  const int64_t now = steadyNowNs();
  if (now - rateWindowStartNs_ >= 500'000'000) {
    rateHz_ = double(stats.published - rateWindowStartCount_) / (double(now - rateWindowStartNs_) * 1e-9);
    rateWindowStartNs_ = now, rateWindowStartCount_ = stats.published;
  }
  info.source = "replay: " + name_;
  info.mapping = map_.describe();
  char state[96];
  std::snprintf(state, sizeof state, "playing x%.2g, loop %llu", speed_,
                static_cast<unsigned long long>(thread_.loops() + 1));
  info.state = state;
  info.sampleRateHz = rateHz_;
  info.dropped = 0;  // a replay delivers every recorded sample; device-side drops are in the recording's gaps
  info.corrupt = 0;
  info.overwritten = stats.overwritten;
  info.sampleAgeMs = double(stats.lastAgeNs) * 1e-6;
}

SteppedReplayPoseSource::SteppedReplayPoseSource(const sim::Session& session, SampleMapper mapper, std::string name)
    : session_(session), map_(std::move(mapper)), name_(std::move(name)) {}

bool SteppedReplayPoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  const size_t n = session_.samples.size();
  if (n == 0) return false;
  if (next_ >= n) next_ = 0;
  // This frame's device-0 sample and every other device's sample up to the next device-0 sample.
  do {
    map_.apply(session_.sampleDevice[next_], session_.samples[next_], skeleton);
    ++next_;
  } while (next_ < n && session_.sampleDevice[next_] != 0);
  ++frames_;
  if (arrivalNs) *arrivalNs = 0;  // no clock: no latency to measure
  return true;
}

void SteppedReplayPoseSource::describe(HudInfo& info) {
  info.source = "replay: " + name_;
  info.mapping = map_.describe();
  info.state = "stepped, frame " + std::to_string(frames_);
  info.sampleRateHz = -1.0;
}

}  // namespace imps::app
