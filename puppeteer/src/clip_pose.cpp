// SPDX-License-Identifier: MIT
// VRML clips on an implicit character: binding targets to joints and playing them (see clip_pose.h).
#include "clip_pose.h"

#include <algorithm>
#include <cstdio>

#include "calibration/joint_map.h"
#include "imps/clock.h"
#include "hud.h"

namespace imps::app {

namespace {

std::string secondsText(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g s", s);
  return buf;
}

}  // namespace

ClipDriver::ClipDriver(Clip clip, const Character& character) : clip_(std::move(clip)) {
  for (const std::string& target : clip_.targets()) {
    const int joint = character.findJoint(target);
    if (joint >= 0) bound_.emplace_back(target, joint);
    else unbound_.push_back(target);
  }
}

std::expected<ClipDriver, Diagnostics> ClipDriver::load(const std::string& path, const std::string& clipName,
                                                        const std::string& map, const Character& character) {
  auto file = readVrmlFile(path);
  if (!file) return std::unexpected(file.error());
  auto clips = readClips(*file);
  if (!clips) return std::unexpected(clips.error());
  if (clips->clips.empty())
    return std::unexpected(singleError({path}, "no clip: no TimeSensor drives an interpolator routed to a Transform"));
  auto chosen = clips->clips.begin();
  if (!clipName.empty()) {
    chosen = std::find_if(clips->clips.begin(), clips->clips.end(), [&](const Clip& c) { return c.name == clipName; });
    if (chosen == clips->clips.end()) {
      std::string names;
      for (const Clip& c : clips->clips) names += (names.empty() ? "" : ", ") + c.name;
      return std::unexpected(singleError({path}, "no clip named '" + clipName + "' (the clips: " + names + ")"));
    }
  }
  ClipDriver driver;
  driver.clip_ = std::move(*chosen);
  const std::vector<std::string> targets = driver.clip_.targets();
  if (map == "auto" || map == "names") {
    driver = ClipDriver(std::move(driver.clip_), character);
  } else {
    auto matches = calibration::readJointMapFile(map, targets, &character);
    if (!matches) return std::unexpected(matches.error());
    for (const std::string& target : targets) {
      const auto m = std::find_if(matches->begin(), matches->end(),
                                  [&](const calibration::JointMatch& jm) { return jm.source == target; });
      if (m != matches->end()) driver.bound_.emplace_back(target, character.findJoint(m->character));
      else driver.unbound_.push_back(target);
    }
  }
  if (driver.bound_.empty()) {
    std::string names;
    for (const std::string& t : targets) names += (names.empty() ? "" : ", ") + t;
    return std::unexpected(singleError({path}, "clip " + driver.clip_.name + " drives no joint of the character (its " +
                                                   "targets: " + names +
                                                   "; pass --map FILE.json, docs/calibration.md#joint-maps)"));
  }
  return driver;
}

void ClipDriver::apply(double seconds, SkeletonCache& skeleton) const {
  const auto values = clip_.sample(clip_.fraction(seconds, true));
  for (const auto& [target, joint] : bound_) {
    const TransformValues& v = values.at(target);
    skeleton.setRotation(joint, v.rotation);
    skeleton.setTranslation(joint, v.rigidTranslation());
  }
}

bool ClipDriver::hasScale() const {
  return std::any_of(clip_.tracks.begin(), clip_.tracks.end(), [](const ClipTrack& t) {
    return t.property == ClipProperty::Scale || t.property == ClipProperty::ScaleOrientation;
  });
}

std::string ClipDriver::describe() const {
  return "clip " + clip_.name + " (" + secondsText(clip_.cycleInterval) + ", " + std::to_string(bound_.size()) +
         " of " + std::to_string(bound_.size() + unbound_.size()) + " targets)";
}

ClipPoseSource::ClipPoseSource(ClipDriver driver, double speed, double fixedStepSeconds, std::string name)
    : driver_(std::move(driver)), speed_(speed), fixedStep_(fixedStepSeconds), name_(std::move(name)),
      startNs_(steadyNowNs()) {}

double ClipPoseSource::seconds() const {
  if (fixedStep_ > 0.0) return static_cast<double>(frames_) * fixedStep_ * speed_;
  return static_cast<double>(steadyNowNs() - startNs_) * 1e-9 * speed_;
}

bool ClipPoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  driver_.apply(seconds(), skeleton);
  if (arrivalNs != nullptr) *arrivalNs = steadyNowNs();
  return true;
}

void ClipPoseSource::describe(HudInfo& info) {
  const double t = seconds();
  const double cycle = driver_.clip().cycleInterval;
  info.source = "clip: " + name_;
  info.mapping = driver_.describe();
  char state[96];
  std::snprintf(state, sizeof state, "playing x%.2g, %.2f / %.2f s, loop %llu", speed_,
                t - cycle * std::floor(t / cycle), cycle, static_cast<unsigned long long>(t / cycle) + 1);
  info.state = state;
}

}  // namespace imps::app
