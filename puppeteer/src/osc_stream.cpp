// SPDX-License-Identifier: MIT
// OSC out (the app's poses to other programs) and OSC in (another host's poses as the pose source).
#include "osc_stream.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "cli.h"
#include "imps/clock.h"

namespace imps::app {
namespace {

std::string countsLine(const char* what, const std::vector<std::pair<const char*, uint64_t>>& counts) {
  std::string out = what;
  for (size_t i = 0; i < counts.size(); ++i)
    out += (i == 0 ? " " : ", ") + std::to_string(counts[i].second) + " " + counts[i].first;
  return out;
}

}  // namespace

// ---- OSC out

OscPoseWriter::OscPoseWriter(const Character& character) {
  const auto& joints = character.joints();
  for (size_t j = 0; j < joints.size(); ++j) {
    const std::string& name = joints[j].name;
    if (name.empty() || name.size() > drivers::kMaxOscJointName || joints_.size() >= size_t(drivers::kMaxOscJoints)) {
      skipped_.push_back(name);
      continue;
    }
    std::memcpy(names_.joints[joints_.size()].name.data(), name.data(), name.size());
    joints_.push_back(int(j));
  }
}

void OscPoseWriter::write(const SkeletonCache& skeleton, int64_t sampleTimeNs, drivers::OscPose& pose) const {
  pose.sampleTimeNs = sampleTimeNs;
  pose.jointCount = uint16_t(joints_.size());
  for (size_t i = 0; i < joints_.size(); ++i) {
    drivers::OscJointRotation& out = pose.joints[i];
    out.name = names_.joints[i].name;
    const glm::quat& q = skeleton.local(joints_[i]).rotation;
    out.w = q.w, out.x = q.x, out.y = q.y, out.z = q.z;
  }
  pose.hasRoot = !skeleton.character().joints().empty();
  if (pose.hasRoot) {
    const glm::vec3& t = skeleton.local(0).translation;
    pose.root = {t.x, t.y, t.z};
  }
}

OscStreamingSource::OscStreamingSource(PoseSource& inner, std::unique_ptr<drivers::OscPoseSender> sender,
                                       const Character& character)
    : inner_(inner), sender_(std::move(sender)), writer_(character), pose_(std::make_unique<drivers::OscPose>()) {}

bool OscStreamingSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  int64_t arrival = 0;
  if (!inner_.poll(skeleton, &arrival)) return false;
  writer_.write(skeleton, arrival, *pose_);
  sender_->send(*pose_);
  if (arrivalNs) *arrivalNs = arrival;
  return true;
}

void OscStreamingSource::describe(HudInfo& info) {
  inner_.describe(info);
  const drivers::OscSenderStats s = sender_->stats();
  info.state += ", OSC out to " + std::to_string(sender_->targets().size()) + " (" + std::to_string(s.dropped) +
                " dropped)";
}

std::string OscStreamingSource::finish() {
  std::string message = inner_.finish();
  sender_->flush(1000);  // the summary counts every frame the performance queued
  const drivers::OscSenderStats s = sender_->stats();
  std::string line = countsLine("OSC out:", {{"frames", s.offered}, {"bundles sent", s.sent},
                                             {"dropped (queue full)", s.dropped}, {"send errors", s.sendErrors}});
  line += " to " + std::to_string(sender_->targets().size()) + " target(s)";
  if (s.sendErrors) line += " (last: " + sender_->lastError() + ")";
  return message.empty() ? line : message + "\npuppeteer: " + line;
}

std::expected<std::unique_ptr<drivers::OscPoseSender>, int> openOscOut(const std::vector<std::string>& urls,
                                                                     const Character& character) {
  if (urls.empty()) return nullptr;
  auto sender = drivers::OscPoseSender::open(urls);
  if (!sender) {
    std::fprintf(stderr, "puppeteer: error: --osc-out %s\n", sender.error().all().front().str().c_str());
    return std::unexpected(int(kExitUsage));
  }
  const OscPoseWriter writer(character);
  for (const std::string& name : writer.skippedJoints())
    std::fprintf(stderr, "puppeteer: warning: --osc-out: joint '%s' is not streamed (names of 1..%zu bytes, at most "
                         "%d joints)\n",
                 name.c_str(), drivers::kMaxOscJointName, drivers::kMaxOscJoints);
  return std::move(*sender);
}

// ---- OSC in

IoResult<std::unique_ptr<OscPoseSource>> OscPoseSource::open(const drivers::DeviceSpec& spec,
                                                             const Character& character,
                                                             std::optional<SampleMapper> calibration,
                                                             drivers::OscReceiverOptions options) {
  std::unique_ptr<OscPoseSource> source(
      new OscPoseSource(character, drivers::formatDeviceSpec(spec), std::move(calibration)));
  options.host = spec.path;
  options.port = spec.port;
  auto receiver = drivers::OscReceiver::open(std::move(options), source->mailbox_);
  if (!receiver) return std::unexpected(receiver.error());
  source->receiver_ = std::move(*receiver);
  source->receiver_->start();
  return source;
}

OscPoseSource::OscPoseSource(const Character& character, std::string spec, std::optional<SampleMapper> calibration)
    : character_(character),
      spec_(std::move(spec)),
      map_(std::move(calibration)),
      pose_(std::make_unique<drivers::OscPose>()),
      rateWindowStartNs_(steadyNowNs()) {}

OscPoseSource::~OscPoseSource() {
  if (receiver_) receiver_->stop();
}

void OscPoseSource::applyPose(SkeletonCache& skeleton) {
  const drivers::OscPose& p = *pose_;
  if (cachedNames_.size() < p.jointCount) {
    cachedNames_.resize(p.jointCount);
    cachedJoints_.resize(p.jointCount, -1);
  }
  for (uint16_t i = 0; i < p.jointCount; ++i) {
    const drivers::OscJointRotation& r = p.joints[i];
    // Senders keep their joint order, so a name is looked up only when it differs from last frame's at this place.
    if (cachedNames_[i] != r.nameView()) {
      cachedNames_[i] = r.nameView();
      cachedJoints_[i] = character_.findJoint(r.nameView());
      if (cachedJoints_[i] < 0 && unknownJoints_.size() < 16) unknownJoints_.push_back(cachedNames_[i]);
    }
    if (cachedJoints_[i] < 0) continue;
    // A sender's unit quaternions arrive bit for bit and are applied as they are, so this host poses exactly as the
    // sender did; only a DIY sender's sloppy ones are normalised.
    const glm::quat q(r.w, r.x, r.y, r.z);
    const float length = glm::length(q);
    skeleton.setRotation(cachedJoints_[i], std::abs(length - 1.0f) > 1e-5f ? q / length : q);
  }
  if (p.hasRoot && !character_.joints().empty())
    skeleton.setTranslation(0, glm::vec3(p.root[0], p.root[1], p.root[2]));
}

bool OscPoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  bool moved = false;
  int64_t arrival = 0;
  if (receiver_->takePose(*pose_)) {
    applyPose(skeleton);
    arrival = pose_->arrivalTimeNs;
    moved = true;
  }
  if (mailbox_.latest(sample_)) {
    if (!map_) {
      // Raw channels without a calibration: by channel names, which a DIY sender does not give ("ch0"…), so
      // nothing moves until a calibration is given (the HUD says so).
      sim::Session names;
      drivers::DeviceInfo info;
      info.name = "OSC raw channels";
      info.channelCount = sample_.channelCount;
      info.bitsPerChannel = 32;
      for (int i = 0; i < info.channelCount; ++i) info.channelNames.push_back("ch" + std::to_string(i));
      names.devices.push_back(info);
      map_.emplace(names, character_);
    }
    map_->apply(0, sample_, skeleton);
    arrival = std::max(arrival, sample_.arrivalTimeNs);
    moved = true;
  }
  if (moved && arrivalNs) *arrivalNs = arrival;
  return moved;
}

void OscPoseSource::describe(HudInfo& info) {
  const drivers::OscReceiverStats s = receiver_->stats();
  const int64_t now = steadyNowNs();
  const uint64_t frames = s.poses + s.samples;
  if (now - rateWindowStartNs_ >= 500'000'000) {
    rateHz_ = double(frames - rateWindowStartCount_) / (double(now - rateWindowStartNs_) * 1e-9);
    rateWindowStartNs_ = now, rateWindowStartCount_ = frames;
  }
  info.source = "OSC (" + spec_ + ")";
  info.mapping = s.samples > 0 && map_ ? map_->describe() : "joint names";
  info.state = drivers::toString(s.state);
  if (s.late || s.outOfOrder) info.state += ", " + std::to_string(s.late) + " late, " +
                                            std::to_string(s.outOfOrder) + " out of order";
  if (!unknownJoints_.empty()) info.state += ", unknown joint " + unknownJoints_.front();
  info.sampleRateHz = rateHz_;
  info.dropped = s.dropped;
  info.corrupt = s.malformed;
  info.overwritten = 0;
}

std::string OscPoseSource::finish() {
  const drivers::OscReceiverStats s = receiver_->stats();
  std::string line = countsLine("OSC in:", {{"poses", s.poses}, {"channel samples", s.samples}, {"late", s.late},
                                            {"out of order", s.outOfOrder}, {"dropped", s.dropped},
                                            {"malformed", s.malformed}, {"timeouts", s.timeouts}});
  if (s.malformed) line += " (last: " + receiver_->lastError() + ")";
  if (!unknownJoints_.empty()) {
    line += "; joints the character does not have:";
    for (const std::string& n : unknownJoints_) line += " " + n;
  }
  return line;
}

}  // namespace imps::app
