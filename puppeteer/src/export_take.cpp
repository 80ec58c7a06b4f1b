// SPDX-License-Identifier: MIT
// Takes on the character: frame selection, clip and session sources, and the character's skeleton as BVH.
#include "export_take.h"

#include <algorithm>
#include <cmath>

namespace imps::app {
namespace {

// Every joint's local transform after `pose` on top of the rest pose.
std::vector<Rigid> localsFor(SkeletonCache& skeleton, const std::vector<JointPose>& pose) {
  skeleton.resetPose();
  skeleton.setPose(pose);
  std::vector<Rigid> out(skeleton.character().joints().size());
  for (size_t j = 0; j < out.size(); ++j) out[j] = skeleton.local(static_cast<int>(j));
  return out;
}

}  // namespace

std::expected<std::vector<size_t>, Diagnostics> selectFrames(std::span<const double> times, double sourceFrameTime,
                                                             const FrameSelection& selection, double* frameTime) {
  const auto fail = [](std::string why) { return std::unexpected(singleError({}, std::move(why))); };
  if (times.empty()) return fail("the input has no frames");
  if (selection.fps < 0 || !std::isfinite(selection.fps)) return fail("--fps must be positive");
  std::vector<size_t> frames;
  if (selection.fps == 0) {
    for (size_t i = 0; i < times.size(); ++i) frames.push_back(i);
    *frameTime = sourceFrameTime;
  } else {
    *frameTime = 1.0 / selection.fps;
    size_t i = 0;
    for (long k = 0;; ++k) {
      const double t = times.front() + static_cast<double>(k) * *frameTime;
      if (t > times.back() + 1e-9) break;
      while (i + 1 < times.size() && times[i + 1] <= t + 1e-9) ++i;
      frames.push_back(i);
    }
  }
  const long count = static_cast<long>(frames.size());
  const long last = selection.last < 0 ? count - 1 : selection.last;
  if (selection.first < 0 || selection.first > last || last >= count)
    return fail("--frames " + std::to_string(selection.first) + ":" + std::to_string(selection.last) +
                " is outside the " + std::to_string(count) + " output frames (0:" + std::to_string(count - 1) + ")");
  return std::vector<size_t>(frames.begin() + selection.first, frames.begin() + last + 1);
}

std::expected<Take, Diagnostics> takeFromClip(const sim::BvhClip& clip, const Retargeter& retargeter,
                                              const Character& character, const FrameSelection& selection) {
  std::vector<double> times(clip.frames.size());
  for (size_t f = 0; f < times.size(); ++f) times[f] = static_cast<double>(f) * clip.frameTime;
  Take take;
  auto frames = selectFrames(times, clip.frameTime > 0 ? clip.frameTime : 1.0 / 30.0, selection, &take.frameTime);
  if (!frames) return std::unexpected(frames.error());
  SkeletonCache skeleton(character);
  std::vector<JointPose> pose;
  for (size_t f : *frames) {
    retargeter.pose(clip.frames[f], pose);
    take.locals.push_back(localsFor(skeleton, pose));
  }
  return take;
}

std::expected<Take, Diagnostics> takeFromSession(const sim::Session& session,
                                                 const calibration::Calibration& calibration,
                                                 const Character& character, const FrameSelection& selection) {
  if (session.devices.empty()) return std::unexpected(singleError({}, "the session has no devices"));
  calibration::Calibrator calibrator(calibration);
  SkeletonCache skeleton(character);
  std::vector<double> times;
  std::vector<std::vector<Rigid>> all;
  const bool deviceClock = session.devices[0].hasDeviceTimestamp;
  // A frame per device-0 sample, emitted once the other devices' samples of that frame (recorded after it) are in.
  bool pending = false;
  for (size_t i = 0; i <= session.samples.size(); ++i) {
    const bool end = i == session.samples.size();
    if (pending && (end || session.sampleDevice[i] == 0)) all.push_back(localsFor(skeleton, calibrator.pose()));
    if (end) break;
    const drivers::Sample s = session.samples[i];
    if (session.sampleDevice[i] == 0) {
      times.push_back(static_cast<double>(deviceClock ? s.deviceTimeNs : s.arrivalTimeNs) * 1e-9);
      pending = true;
    }
    calibrator.update(session.sampleDevice[i], s);
  }
  // The source frame time: the median spacing.
  std::vector<double> gaps;
  for (size_t i = 1; i < times.size(); ++i) gaps.push_back(times[i] - times[i - 1]);
  double median = 1.0 / 60.0;
  if (!gaps.empty()) {
    std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
    if (gaps[gaps.size() / 2] > 0) median = gaps[gaps.size() / 2];
  }
  Take take;
  auto frames = selectFrames(times, median, selection, &take.frameTime);
  if (!frames) return std::unexpected(frames.error());
  for (size_t f : *frames) take.locals.push_back(all[f]);
  return take;
}

glm::dvec3 eulerZXYDegrees(const glm::dquat& q, const glm::dvec3* near) {
  const glm::dmat3 m = glm::mat3_cast(glm::normalize(q));  // m[column][row]
  double a, b, c;
  const double sx = std::clamp(m[1][2], -1.0, 1.0);
  b = std::asin(sx);
  if (std::abs(sx) < 1.0 - 1e-9) {
    a = std::atan2(-m[1][0], m[1][1]);
    c = std::atan2(-m[0][2], m[2][2]);
  } else {  // gimbal lock: only a ± c is defined; put it all in a
    a = std::atan2(m[0][1], m[0][0]);
    c = 0;
  }
  glm::dvec3 out = glm::degrees(glm::dvec3(a, b, c));
  if (near)
    for (int k = 0; k < 3; ++k) out[k] += 360.0 * std::nearbyint(((*near)[k] - out[k]) / 360.0);
  return out;
}

sim::BvhClip characterClip(const Character& character, const Take& take) {
  const auto& joints = character.joints();
  const size_t n = joints.size();
  // Joints that translate during the take.
  std::vector<bool> moves(n, false);
  for (size_t j = 0; j < n; ++j) {
    moves[j] = joints[j].parent < 0;
    for (const auto& frame : take.locals)
      if (glm::length(frame[j].translation - joints[j].rest.translation) > 1e-7f) moves[j] = true;
  }
  // BVH order: depth first from each root, children in joint order (the character's order is already parents first,
  // but a BVH file must list a joint's whole subtree before its next sibling).
  std::vector<size_t> order;
  std::function<void(int)> visit = [&](int parent) {
    for (size_t j = 0; j < n; ++j)
      if (joints[j].parent == parent) {
        order.push_back(j);
        visit(static_cast<int>(j));
      }
  };
  visit(-1);
  std::vector<int> bvhIndex(n, -1);
  sim::BvhClip clip;
  clip.frameTime = take.frameTime;
  for (size_t j : order) {
    sim::BvhJoint b;
    b.name = joints[j].name;
    b.parent = joints[j].parent < 0 ? -1 : bvhIndex[static_cast<size_t>(joints[j].parent)];
    const glm::vec3 t = joints[j].rest.translation;
    b.offset = {t.x, t.y, t.z};
    if (moves[j]) b.channels = {sim::BvhChannel::Xposition, sim::BvhChannel::Yposition, sim::BvhChannel::Zposition};
    b.channels.insert(b.channels.end(),
                      {sim::BvhChannel::Zrotation, sim::BvhChannel::Xrotation, sim::BvhChannel::Yrotation});
    const bool leaf =
        std::none_of(joints.begin(), joints.end(), [&](const Joint& k) { return k.parent == static_cast<int>(j); });
    if (leaf) {
      glm::vec3 end(0.0f, 0.1f, 0.0f);
      float farthest = 0;
      for (const CharacterPrimitive& p : character.primitives()) {
        if (p.joint != static_cast<int>(j)) continue;
        const glm::vec3 tip = p.local.kind == PrimitiveKind::LineSeg ? p.local.p2 : p.local.center;
        if (glm::length(tip) > farthest) farthest = glm::length(tip), end = tip;
      }
      b.hasEndSite = true;
      b.endSiteOffset = {end.x, end.y, end.z};
    }
    bvhIndex[j] = static_cast<int>(clip.joints.size());
    clip.joints.push_back(std::move(b));
  }
  std::vector<glm::dvec3> previous(n);
  for (size_t f = 0; f < take.frames(); ++f) {
    std::vector<float> values;
    for (size_t j : order) {
      const Rigid& local = take.locals[f][j];
      if (moves[j]) values.insert(values.end(), {local.translation.x, local.translation.y, local.translation.z});
      const glm::dvec3 e = eulerZXYDegrees(glm::dquat(local.rotation), f ? &previous[j] : nullptr);
      previous[j] = e;
      values.insert(values.end(), {static_cast<float>(e.x), static_cast<float>(e.y), static_cast<float>(e.z)});
    }
    clip.frames.push_back(std::move(values));
  }
  return clip;
}

}  // namespace imps::app
