// SPDX-License-Identifier: MIT
// `--pose` on the command line: turn a joint about an axis (degrees unless written otherwise) or move it.
#pragma once

#include <expected>
#include <string>
#include <string_view>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "imps/diagnostic.h"
#include "imps/skeleton_cache.h"

namespace imps::app {

// One --pose argument.
//   JOINT=AX,AY,AZ,ANGLE  turn by ANGLE about the axis (AX,AY,AZ) of the parent's frame, on top of the rest rotation.
//                         ANGLE is in degrees; "90deg" says so explicitly and "1.57rad" gives radians.
//   JOINT=TX,TY,TZ        move the joint by (TX,TY,TZ) metres in the parent's frame, from its rest translation.
struct PoseArgument {
  std::string joint;
  bool translation = false;
  glm::vec3 axis{0.0f, 0.0f, 1.0f};  // rotation: not normalised, non-zero
  float radians = 0.0f;              // rotation
  glm::vec3 offset{0.0f};            // translation, metres
};

// Parses one argument. Errors: one diagnostic without a position that says what was expected
// ("expected JOINT=AX,AY,AZ,ANGLE … or JOINT=TX,TY,TZ …").
std::expected<PoseArgument, Diagnostics> parsePoseArgument(std::string_view text);

// Applies `p` to joint `joint` of `skeleton` on top of the current local pose (rotations compose on the left, in the
// parent's frame; offsets add). Call skeleton.update() afterwards.
void applyPoseArgument(const PoseArgument& p, int joint, SkeletonCache& skeleton);

}  // namespace imps::app
