// SPDX-License-Identifier: MIT
// Skeleton cache: pose -> world transforms, differential transforms and world-space primitives.
#include "imps/skeleton_cache.h"

namespace imps {

SkeletonCache::SkeletonCache(const Character& character) : character_(&character) {
  const size_t n = character.primitives().size();
  std::vector<float> params(n);
  std::vector<glm::vec3> colors(n);
  std::vector<Primitive> prims(n);
  for (size_t i = 0; i < n; ++i) {
    params[i] = character.primitives()[i].blendParam;
    colors[i] = character.primitives()[i].color;
    prims[i] = character.primitives()[i].local;
  }
  if (character.textured()) {
    texGens_.resize(n);
    hasTexGen_.resize(n);
    for (size_t i = 0; i < n; ++i) hasTexGen_[i] = character.primitives()[i].texGen.has_value();
  }
  field_ = Field(std::move(prims), std::move(params), std::move(colors), character.blend(), character.blendSets(),
                 character.iso());
  resetPose();
  world_.resize(local_.size());
  differential_.resize(local_.size());
  update();
  for (Rigid& d : differential_) d = Rigid{};
  placementDifferential_ = Rigid{};
}

bool SkeletonCache::setRotation(std::string_view joint, const glm::quat& rotation) {
  const int j = character_->findJoint(joint);
  if (j < 0) return false;
  local_[j].rotation = rotation;
  return true;
}

bool SkeletonCache::setTranslation(std::string_view joint, const glm::vec3& translation) {
  const int j = character_->findJoint(joint);
  if (j < 0) return false;
  local_[j].translation = translation;
  return true;
}

int SkeletonCache::setPose(const std::vector<JointPose>& pose) {
  int unknown = 0;
  for (const JointPose& p : pose) {
    const int j = character_->findJoint(p.joint);
    if (j < 0) {
      ++unknown;
      continue;
    }
    local_[j].rotation = p.rotation;
    if (p.hasTranslation) local_[j].translation = p.translation;
  }
  return unknown;
}

void SkeletonCache::resetPose() {
  local_.clear();
  for (const Joint& j : character_->joints()) local_.push_back(j.rest);
}

void SkeletonCache::update() {
  const auto& joints = character_->joints();
  for (size_t j = 0; j < joints.size(); ++j) {  // parents precede children
    const Rigid now = joints[j].parent >= 0 ? world_[joints[j].parent] * local_[j] : placement_ * local_[j];
    differential_[j] = now * world_[j].inverse();
    world_[j] = now;
  }
  // Joint-less primitives stay bit-identical without a placement (Marching Cubes' hashes do not move).
  const bool placed =
      placement_.rotation != glm::quat(1.0f, 0.0f, 0.0f, 0.0f) || placement_.translation != glm::vec3(0.0f);
  std::vector<Primitive> prims(field_.size());
  const auto& cp = character_->primitives();
  for (size_t i = 0; i < prims.size(); ++i) {
    const int j = cp[i].joint;
    const Rigid& to = j >= 0 ? world_[j] : placement_;
    prims[i] = j >= 0 || placed ? cp[i].local.transformed(to.rotation, to.translation) : cp[i].local;
  }
  placementDifferential_ = placement_ * appliedPlacement_.inverse();
  appliedPlacement_ = placement_;
  field_.setPrimitives(std::move(prims));
  for (size_t i = 0; i < texGens_.size(); ++i) {
    if (!hasTexGen_[i]) continue;
    const int j = cp[i].joint;
    const Rigid& to = j >= 0 ? world_[j] : placement_;
    texGens_[i] = j >= 0 || placed ? cp[i].texGen->transformed(to.rotation, to.translation) : *cp[i].texGen;
  }
  ++generation_;
}

Rigid SkeletonCache::primitiveDifferential(size_t i) const {
  const int j = character_->primitives()[i].joint;
  return j >= 0 ? differential_[j] : placementDifferential_;
}

}  // namespace imps
