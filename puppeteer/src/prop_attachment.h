// SPDX-License-Identifier: MIT
// Polygonal props (imps/vrml_props.h) in a character's world: loaded from `--prop FILE.wrl[@JOINT]`, a prop on a
// joint following the joint's posed world transform (Beanito's hat), others staying where the file puts them.
#pragma once

#include <expected>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/mesh.h"
#include "imps/skeleton_cache.h"

namespace imps::app {

struct AttachedProp {
  std::string name;  // the prop's name in its file
  Mesh mesh;         // in the joint's frame (the world's when joint < 0)
  int joint = -1;
};

// Reads every `FILE.wrl[@JOINT]` spec: all the Shapes of FILE, attached to JOINT when given. Errors: the file's
// `file:line:column` ones, or "--prop SPEC: the scene has no joint 'X'" (located at "puppeteer", so that it prints
// as `puppeteer: error: …`). Warnings (skipped nodes, bad faces) are appended to *warnings when given.
std::expected<std::vector<AttachedProp>, Diagnostics> loadProps(const std::vector<std::string>& specs,
                                                                const Character& character, Diagnostics* warnings);

// The grab constraint (thesis 4.1): a hand picks a prop up at `pickSeconds` and puts it down at `dropSeconds`.
struct Grab {
  int joint = -1;  // the grabbing joint
  double pickSeconds = 0.0, dropSeconds = 0.0;  // pickSeconds <= dropSeconds
};

// Parses `FILE.wrl@JOINT@PICK:DROP` (seconds) into the file, the grab and nothing else; an error is one diagnostic
// at "puppeteer" ("--grab SPEC: expected FILE.wrl@JOINT@PICK:DROP", an unknown joint, PICK > DROP).
std::expected<std::pair<std::string, Grab>, Diagnostics> parseGrab(const std::string& spec, const Character& character);

// Where a grabbed prop is at `seconds`, as a rigid motion of its file coordinates: not moved before the pick; while
// held, moved with the joint as if glued to it at the pick (jointWorldAt(t) * jointWorldAt(pick)^-1); after the
// drop, left where the hand put it (the held motion at the drop). `jointWorldAt` gives the joint's world transform
// at a time (a clip sampled there).
template <class JointWorldAt>
Rigid grabbedMotion(const Grab& grab, double seconds, const JointWorldAt& jointWorldAt) {
  if (seconds < grab.pickSeconds) return Rigid{};
  const Rigid atPick = jointWorldAt(grab.pickSeconds);
  return jointWorldAt(seconds < grab.dropSeconds ? seconds : grab.dropSeconds) * atPick.inverse();
}

// Appends every prop to `mesh`, posed by the skeleton cache's current world transforms (call update() first).
void appendPosedProps(Mesh& mesh, const std::vector<AttachedProp>& props, const SkeletonCache& skeleton);

}  // namespace imps::app
