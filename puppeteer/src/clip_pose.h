// SPDX-License-Identifier: MIT
// Keyframed VRML clips (imps/vrml_clip.h) on an implicit character: which clip target drives which joint (a joint
// map, calibration/joint_map.h, or equal names), the pose at a time, and a PoseSource that plays a clip in the app.
#pragma once

#include <expected>
#include <string>
#include <utility>
#include <vector>

#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/skeleton_cache.h"
#include "imps/vrml_clip.h"
#include "viewer.h"

namespace imps::app {

// A clip bound to a character's joints.
class ClipDriver {
 public:
  // Reads `path` (a VRML 97 file, possibly gzipped) and picks its clip named `clipName` (a TimeSensor's DEF name), or
  // its only/first clip when `clipName` is empty. `map` is "auto" or "names" (a target drives the joint of the same
  // name) or a joint-map JSON file (docs/calibration.md#joint-maps) from target names to joint names. Errors are
  // the readers' diagnostics (`file:line:column: error: ...`), or one at `path`: the file does not read, has no
  // clips, no clip of that name, a bad map, or no target drives a joint.
  static std::expected<ClipDriver, Diagnostics> load(const std::string& path, const std::string& clipName,
                                                     const std::string& map, const Character& character);
  // Binds an already read clip by equal names.
  ClipDriver(Clip clip, const Character& character);

  // Poses `skeleton` (without update()) at `seconds` into the clip, looping: every bound joint gets the target's
  // rotation and the rigid part of its translation and centre. Scale tracks are not applied (the character's joints
  // are rigid; hasScale() says whether the clip has any).
  void apply(double seconds, SkeletonCache& skeleton) const;

  const Clip& clip() const { return clip_; }
  const std::vector<std::pair<std::string, int>>& bound() const { return bound_; }  // target, joint index
  const std::vector<std::string>& unbound() const { return unbound_; }             // targets driving no joint
  bool hasScale() const;
  // "clip Bip01-TIMER (2 s, 3 of 4 targets)".
  std::string describe() const;

 private:
  ClipDriver() = default;
  Clip clip_;
  std::vector<std::pair<std::string, int>> bound_;
  std::vector<std::string> unbound_;
};

// Plays a clip in the live app, looping, at `speed`. With a fixed step (headless --frames runs) the time advances by
// exactly `fixedStepSeconds` per frame, so screenshots are repeatable; otherwise it follows the steady clock.
class ClipPoseSource : public PoseSource {
 public:
  ClipPoseSource(ClipDriver driver, double speed, double fixedStepSeconds, std::string name);
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;
  void frameDone() override { ++frames_; }

 private:
  double seconds() const;
  ClipDriver driver_;
  double speed_ = 1.0;
  double fixedStep_ = 0.0;
  std::string name_;
  int64_t startNs_ = 0;
  uint64_t frames_ = 0;
};

}  // namespace imps::app
