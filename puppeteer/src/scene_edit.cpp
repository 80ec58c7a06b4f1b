// SPDX-License-Identifier: MIT
// The modeller's edits of the scene document (see scene_edit.h).
#include "scene_edit.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <variant>

#include <glm/geometric.hpp>

namespace imps::app {
namespace {

constexpr float kMinRadius = 1e-3f;  // metres: an edit never makes a radius smaller

void collect(SceneNode& node, SceneNodes& out) {
  if (auto* t = std::get_if<TransformNode>(&node)) {
    out.joints.push_back(t);
    for (SceneNode& c : t->children) collect(c, out);
  } else if (auto* s = std::get_if<ShapeNode>(&node)) {
    out.primitives.push_back(s);
  } else if (auto* b = std::get_if<BlendNode>(&node)) {
    for (SceneNode& c : b->children) collect(c, out);
  }
}

// Makes every `USE NAME` copy in the scene graph equal to its DEF'd node again (as the reader made it: the DEF'd
// node's fields and children, no name of its own), so an edit of a DEF'd node shows in its copies and the saved
// file (which writes only `USE NAME`) reads back to what is on screen.
class UseRefresher {
 public:
  void run(Scene& scene) {
    if (auto* t = std::get_if<Tesselator3MPNode>(&scene.polygonizer); t && t->blendingFunction)
      define(t->blendingFunction->name, SceneNode(*t->blendingFunction));
    if (auto* m = std::get_if<MarchingCubesNode>(&scene.polygonizer); m && m->blendingFunction)
      define(m->blendingFunction->name, SceneNode(*m->blendingFunction));
    if (SceneNode* root = scene.sceneGraph()) visit(*root);
  }

 private:
  void define(const std::string& name, const SceneNode& node) {
    if (!name.empty()) defined_.insert_or_assign(name, node);
  }
  static std::string& useOf(SceneNode& n) {
    return std::visit([](auto& x) -> std::string& { return x.useOf; }, n);
  }
  void visit(SceneNode& node) {
    if (const std::string use = useOf(node); !use.empty()) {
      if (auto it = defined_.find(use); it != defined_.end()) {
        const SourceLoc loc = std::visit([](auto& x) { return x.loc; }, node);
        node = it->second;
        std::visit([&](auto& x) { x.name.clear(), x.useOf = use, x.loc = loc; }, node);
      }
      return;
    }
    if (auto* t = std::get_if<TransformNode>(&node))
      for (SceneNode& c : t->children) visit(c);
    if (auto* b = std::get_if<BlendNode>(&node))
      for (SceneNode& c : b->children) visit(c);
    define(std::visit([](auto& x) { return x.name; }, node), node);
  }
  std::map<std::string, SceneNode> defined_;
};

Rigid poseOf(const DocumentState& state, int joint) {
  return joint >= 0 && size_t(joint) < state.pose.size() ? state.pose[size_t(joint)] : Rigid{};
}

// The shape behind `target`, or the reason it cannot be edited.
ShapeNode* editableShape(SceneNodes& nodes, const EditTarget& target, std::string* why) {
  if (target.index < 0 || size_t(target.index) >= nodes.primitives.size()) {
    *why = "no such primitive";
    return nullptr;
  }
  ShapeNode* s = nodes.primitives[size_t(target.index)];
  if (!s->useOf.empty()) {
    *why = "a USE of " + s->useOf + ": edit " + s->useOf + " itself";
    return nullptr;
  }
  if (target.kind != EditTarget::Kind::Primitive && s->kind != ShapeKind::LineSeg) {
    *why = "only a LineSeg has endpoints";
    return nullptr;
  }
  return s;
}

TransformNode* editableJoint(SceneNodes& nodes, const EditTarget& target, std::string* why) {
  if (target.index < 0 || size_t(target.index) >= nodes.joints.size()) {
    *why = "no such joint";
    return nullptr;
  }
  TransformNode* t = nodes.joints[size_t(target.index)];
  if (!t->useOf.empty()) {
    *why = "a USE of " + t->useOf + ": edit " + t->useOf + " itself";
    return nullptr;
  }
  return t;
}

glm::vec3 shapeCenter(const ShapeNode& s) {
  return s.kind == ShapeKind::LineSeg ? 0.5f * (s.point1 + s.point2) : s.center;
}

// Writes joint `j`'s posed local transform into its RigidTransform.
void writeJoint(TransformNode& t, const Rigid& local) {
  t.translation = local.translation;
  t.rotation = toRotation(local.rotation);
}

}  // namespace

void refreshUses(Scene& scene) { UseRefresher().run(scene); }

BlendNode* blendInForce(Scene& scene) {
  if (SceneNode* root = scene.sceneGraph())
    if (auto* flat = std::get_if<BlendNode>(root); flat && flat->useOf.empty()) return flat;
  if (auto* t = std::get_if<Tesselator3MPNode>(&scene.polygonizer); t && t->blendingFunction)
    return &*t->blendingFunction;
  if (auto* m = std::get_if<MarchingCubesNode>(&scene.polygonizer); m && m->blendingFunction)
    return &*m->blendingFunction;
  return nullptr;
}

float* isoValueOf(Scene& scene) {
  if (auto* t = std::get_if<Tesselator3MPNode>(&scene.polygonizer)) return &t->isoValue;
  if (auto* m = std::get_if<MarchingCubesNode>(&scene.polygonizer)) return &m->isoValue;
  return nullptr;
}

const BlendNode* blendInForce(const Scene& scene) { return blendInForce(const_cast<Scene&>(scene)); }
const float* isoValueOf(const Scene& scene) { return isoValueOf(const_cast<Scene&>(scene)); }

SceneNodes sceneNodes(Scene& scene) {
  SceneNodes out;
  if (SceneNode* root = scene.sceneGraph()) collect(*root, out);
  return out;
}

Rotation toRotation(const glm::quat& rotation) {
  glm::quat q = glm::normalize(rotation);
  if (q.w < 0.0f) q = -q;  // the angle in [0, pi]
  const glm::vec3 v(q.x, q.y, q.z);
  const float s = glm::length(v);
  if (!(s > 1e-7f)) return Rotation{glm::vec3(0, 0, 1), 0.0f};
  return Rotation{v / s, 2.0f * std::atan2(s, q.w)};
}

void writePose(Scene& scene, const std::vector<Rigid>& pose) {
  SceneNodes nodes = sceneNodes(scene);
  for (size_t j = 0; j < nodes.joints.size() && j < pose.size(); ++j)
    if (nodes.joints[j]->useOf.empty()) writeJoint(*nodes.joints[j], pose[j]);
  refreshUses(scene);
}

std::string targetName(const Character& character, const EditTarget& target) {
  if (target.kind == EditTarget::Kind::Joint)
    return target.index >= 0 && size_t(target.index) < character.joints().size()
               ? character.joints()[size_t(target.index)].name
               : "?";
  std::string name = target.index >= 0 && size_t(target.index) < character.primitives().size()
                         ? character.primitives()[size_t(target.index)].name
                         : "?";
  if (target.kind == EditTarget::Kind::Endpoint1) name += ".point1";
  if (target.kind == EditTarget::Kind::Endpoint2) name += ".point2";
  return name;
}

std::string translateTarget(DocumentState& state, const Character& /*character*/, const EditTarget& target,
                            const glm::quat& containerWorld, const glm::vec3& worldDelta) {
  SceneNodes nodes = sceneNodes(state.scene);
  std::string why;
  const glm::vec3 d = glm::inverse(containerWorld) * worldDelta;
  if (target.kind == EditTarget::Kind::Joint) {
    TransformNode* t = editableJoint(nodes, target, &why);
    if (!t) return why;
    Rigid local = poseOf(state, target.index);
    local.translation += d;
    if (size_t(target.index) < state.pose.size()) state.pose[size_t(target.index)] = local;
    writeJoint(*t, local);
  } else {
    ShapeNode* s = editableShape(nodes, target, &why);
    if (!s) return why;
    if (target.kind == EditTarget::Kind::Endpoint1) {
      s->point1 += d;
    } else if (target.kind == EditTarget::Kind::Endpoint2) {
      s->point2 += d;
    } else if (s->kind == ShapeKind::LineSeg) {
      s->point1 += d, s->point2 += d;
    } else {
      s->center += d;
    }
  }
  refreshUses(state.scene);
  return {};
}

std::string rotateTarget(DocumentState& state, const Character& /*character*/, const EditTarget& target,
                         const glm::quat& containerWorld, const glm::quat& worldRotation) {
  SceneNodes nodes = sceneNodes(state.scene);
  std::string why;
  // The rotation expressed in the container's frame.
  const glm::quat r = glm::normalize(glm::inverse(containerWorld) * worldRotation * containerWorld);
  if (target.kind == EditTarget::Kind::Joint) {
    TransformNode* t = editableJoint(nodes, target, &why);
    if (!t) return why;
    Rigid local = poseOf(state, target.index);
    local.rotation = glm::normalize(r * local.rotation);
    if (size_t(target.index) < state.pose.size()) state.pose[size_t(target.index)] = local;
    writeJoint(*t, local);
  } else {
    ShapeNode* s = editableShape(nodes, target, &why);
    if (!s) return why;
    if (target.kind != EditTarget::Kind::Primitive || s->kind == ShapeKind::Metaball)
      return "a " + std::string(s->kind == ShapeKind::Metaball ? "metaball" : "endpoint") + " has no orientation";
    if (s->kind == ShapeKind::Ellipsoid) {
      s->orientation = toRotation(r * toQuat(s->orientation));
    } else {
      const glm::vec3 mid = shapeCenter(*s);
      s->point1 = mid + r * (s->point1 - mid);
      s->point2 = mid + r * (s->point2 - mid);
    }
  }
  refreshUses(state.scene);
  return {};
}

std::string scaleTarget(DocumentState& state, const Character& character, const EditTarget& target, float factor,
                        int axis) {
  if (!(factor > 0.0f) || !std::isfinite(factor)) return "the scale factor must be positive";
  SceneNodes nodes = sceneNodes(state.scene);
  std::string why;
  auto scaled = [factor](float r) { return std::max(kMinRadius, r * factor); };
  if (target.kind == EditTarget::Kind::Joint) {
    // Limb length: everything placed in the joint's frame moves away from (or towards) its origin.
    TransformNode* t = editableJoint(nodes, target, &why);
    if (!t) return why;
    for (SceneNode& child : t->children) {
      if (auto* c = std::get_if<TransformNode>(&child)) {
        c->translation *= factor;
      } else if (auto* s = std::get_if<ShapeNode>(&child)) {
        s->center *= factor, s->point1 *= factor, s->point2 *= factor;
      }
    }
    const auto& joints = character.joints();
    for (size_t c = 0; c < joints.size() && c < state.pose.size(); ++c)
      if (joints[c].parent == target.index) state.pose[c].translation *= factor;
  } else {
    ShapeNode* s = editableShape(nodes, target, &why);
    if (!s) return why;
    if (target.kind == EditTarget::Kind::Endpoint1) {
      s->radius1 = scaled(s->radius1);
    } else if (target.kind == EditTarget::Kind::Endpoint2) {
      s->radius2 = scaled(s->radius2);
    } else if (s->kind == ShapeKind::Metaball) {
      s->radius = scaled(s->radius);
    } else if (s->kind == ShapeKind::LineSeg) {
      s->radius1 = scaled(s->radius1), s->radius2 = scaled(s->radius2);
    } else {
      for (int a = 0; a < 3; ++a)
        if (axis < 0 || axis == a) s->radii[a] = scaled(s->radii[a]);
    }
  }
  refreshUses(state.scene);
  return {};
}

void EditHistory::record(DocumentState before) {
  undo_.push_back(std::move(before));
  if (undo_.size() > limit_) undo_.erase(undo_.begin());
  redo_.clear();
}

std::optional<DocumentState> EditHistory::undo(DocumentState current) {
  if (undo_.empty()) return std::nullopt;
  DocumentState back = std::move(undo_.back());
  undo_.pop_back();
  redo_.push_back(std::move(current));
  return back;
}

std::optional<DocumentState> EditHistory::redo(DocumentState current) {
  if (redo_.empty()) return std::nullopt;
  DocumentState forward = std::move(redo_.back());
  redo_.pop_back();
  undo_.push_back(std::move(current));
  return forward;
}

}  // namespace imps::app
