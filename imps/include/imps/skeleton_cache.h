// SPDX-License-Identifier: MIT
// The skeleton cache (thesis 3.7): the current pose of a character, its world-space primitives and, for each joint,
// the differential transform since the previous update.
//
// Zeroth-order control: the application sets joints' rotations and translations absolutely (relative to the parent
// joint, as in the file) every frame; update() computes everything incremental polygonizers need. A particle owned
// by a primitive of joint j that sat at x before update() should move to differential(j).apply(x).
//
// Thread safety: none; one owner (the frame loop) calls the setters and update(). The Field returned by field() is
// immutable between updates and may be read from any number of threads.
#pragma once

#include <string_view>
#include <vector>

#include "imps/character.h"
#include "imps/field.h"

namespace imps {

// A pose in the character's vocabulary: absolute local rotations/translations for named joints.
struct JointPose {
  std::string joint;
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  bool hasTranslation = false;
  glm::vec3 translation{0.0f};
};

class SkeletonCache {
 public:
  // Starts in the rest pose, already updated. The character must outlive the cache.
  explicit SkeletonCache(const Character& character);

  const Character& character() const { return *character_; }

  // Absolute local rotation / translation of a joint (relative to its parent). Return false for unknown names.
  bool setRotation(std::string_view joint, const glm::quat& rotation);
  bool setTranslation(std::string_view joint, const glm::vec3& translation);
  void setRotation(int joint, const glm::quat& rotation) { local_[joint].rotation = rotation; }
  void setTranslation(int joint, const glm::vec3& translation) { local_[joint].translation = translation; }
  // Applies every entry; returns the number of unknown joint names (which are ignored).
  int setPose(const std::vector<JointPose>& pose);
  // Back to the file's pose.
  void resetPose();

  // Where the character stands in the world (a world file's Transform above its Inline): applied above every root
  // joint and to joint-less primitives, so world(), field() and texGen() are in world space. The identity by
  // default. Takes effect at the next update(), whose differentials include the move (particles follow it).
  void setPlacement(const Rigid& placement) { placement_ = placement; }
  const Rigid& placement() const { return placement_; }

  // Recomputes world transforms, differential transforms and the field's world-space primitives.
  void update();

  const Rigid& local(int joint) const { return local_[joint]; }
  const Rigid& world(int joint) const { return world_[joint]; }
  // world(now) * inverse(world(previous update)); the identity after the first update.
  const Rigid& differential(int joint) const { return differential_[joint]; }
  // Differential transform for the particles owned by primitive i (for joint-less primitives the placement's move
  // since the previous update, usually the identity).
  Rigid primitiveDifferential(size_t i) const;
  const Field& field() const { return field_; }
  // Primitive i's texture-coordinate generator in world space (it follows the primitive's joint), or null when the
  // primitive has none.
  const TexGen* texGen(size_t i) const { return texGens_.empty() || !hasTexGen_[i] ? nullptr : &texGens_[i]; }
  // Incremented by every update().
  uint64_t generation() const { return generation_; }

 private:
  const Character* character_;
  std::vector<Rigid> local_, world_, differential_;
  Rigid placement_, appliedPlacement_, placementDifferential_;
  Field field_;
  std::vector<TexGen> texGens_;   // empty when no primitive has a generator
  std::vector<uint8_t> hasTexGen_;
  uint64_t generation_ = 0;
};

}  // namespace imps
