// SPDX-License-Identifier: MIT
// A take on the character, ready to leave the app: every output frame's local joint transforms (from a retargeted
// clip or a calibrated session, resampled to a frame rate and cut to a frame range), and the character's skeleton as
// a BVH clip. The glTF and surface-sequence writers are in export_gltf.h and export_surfaces.h.
#pragma once

#include <cstdint>
#include <expected>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "calibration/calibration.h"
#include "imps/character.h"
#include "imps/skeleton_cache.h"
#include "retarget.h"
#include "sim/bvh.h"
#include "sim/session_file.h"

namespace imps::app {

// Which frames leave: resampled to `fps` (0: the input's own frames), then output frames first..last (0-based,
// inclusive; last = -1: to the end).
struct FrameSelection {
  double fps = 0;
  long first = 0, last = -1;
};

// Per output frame, every joint's local transform (character joint order), and the time between frames.
struct Take {
  double frameTime = 1.0 / 30.0;
  std::vector<std::vector<Rigid>> locals;
  size_t frames() const { return locals.size(); }
};

// Source frames at times `times` (seconds, non-decreasing) → output frame indices: sample-and-hold at each output
// time, then the range. Errors (one, without a location: the values come from the command line): an empty input, a
// range outside the frames, a non-positive fps.
std::expected<std::vector<size_t>, Diagnostics> selectFrames(std::span<const double> times, double sourceFrameTime,
                                                             const FrameSelection& selection, double* frameTime);

// A clip retargeted onto the character (every frame through `retargeter`). Fails as selectFrames does.
std::expected<Take, Diagnostics> takeFromClip(const sim::BvhClip& clip, const Retargeter& retargeter,
                                              const Character& character, const FrameSelection& selection);
// A session through a calibration: the stateful Calibrator over every sample of every device in order (so smoothing
// and hold-last-good behave as in the app), one frame per device-0 sample (with the other devices' samples of it).
// Fails as selectFrames does, and for a session without devices.
std::expected<Take, Diagnostics> takeFromSession(const sim::Session& session,
                                                 const calibration::Calibration& calibration,
                                                 const Character& character, const FrameSelection& selection);

// Angles (degrees) a, b, c with q = Rz(a) · Rx(b) · Ry(c) (BVH's "Zrotation Xrotation Yrotation"); `near` (degrees)
// picks, per angle, the representative nearest the previous frame's.
glm::dvec3 eulerZXYDegrees(const glm::dquat& q, const glm::dvec3* near = nullptr);

// The character's skeleton as a BVH clip, in metres: every joint (roots as ROOTs, children in file order), OFFSET =
// the rest translation, channels Zrotation Xrotation Yrotation = the full local rotation (rest rotation included, so
// the clip's forward kinematics equals the skeleton cache's), plus Xposition Yposition Zposition (absolute local
// translation) on roots and on every joint whose translation moves during the take. Leaf joints get an End Site at
// the far end of their primitives (0.1 m up when they have none).
sim::BvhClip characterClip(const Character& character, const Take& take);

}  // namespace imps::app
