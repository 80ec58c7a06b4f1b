// SPDX-License-Identifier: MIT
// The interactive modeller: handles, picking, drags into document edits, undo/redo (see modeller.h).
#include "modeller.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <glm/geometric.hpp>

namespace imps::app {
namespace {

std::string vectorText(const glm::vec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "%.4g %.4g %.4g", double(v.x), double(v.y), double(v.z));
  return text;
}

bool samePose(const std::vector<Rigid>& a, const std::vector<Rigid>& b) {
  if (a.size() != b.size()) return false;
  for (size_t j = 0; j < a.size(); ++j)
    if (a[j].rotation != b[j].rotation || a[j].translation != b[j].translation) return false;
  return true;
}

}  // namespace

OrbitCamera initialOrbit(const ViewerPipeline& pipeline, int width, int height, float* sceneRadius) {
  return initialOrbit(pipeline.restBounds().empty() ? bounds(pipeline.mesh()) : pipeline.restBounds(), width, height,
                      sceneRadius);
}

namespace {

void addQuad(std::vector<OverlayVertex>& out, glm::vec2 a, glm::vec2 b, glm::vec2 c, glm::vec2 d, glm::vec3 color) {
  for (const glm::vec2& p : {a, b, c, a, c, d}) out.push_back(OverlayVertex{p, color});
}

void addLine(std::vector<OverlayVertex>& out, glm::vec2 a, glm::vec2 b, float width, glm::vec3 color) {
  const glm::vec2 d = b - a;
  const float len = glm::length(d);
  if (!(len > 0.0f)) return;
  const glm::vec2 n = glm::vec2(-d.y, d.x) / len * (0.5f * width);
  addQuad(out, a - n, b - n, b + n, a + n, color);
}

void addSquare(std::vector<OverlayVertex>& out, glm::vec2 c, float half, glm::vec3 color) {
  addQuad(out, c + glm::vec2(-half, -half), c + glm::vec2(half, -half), c + glm::vec2(half, half),
          c + glm::vec2(-half, half), color);
}

const glm::vec3 kAxisColors[3] = {{0.9f, 0.12f, 0.1f}, {0.15f, 0.75f, 0.15f}, {0.15f, 0.3f, 0.95f}};

void addSelectedHandle(std::vector<OverlayVertex>& out, const HandleLayout& layout, ManipulatorMode mode) {
  const glm::vec3 dark(0.02f);
  if (mode == ManipulatorMode::Rotate) {
    constexpr int kSegments = 48;
    const float r = 0.8f * Modeller::kHandlePixels;
    for (int i = 0; i < kSegments; ++i) {
      const float a0 = 2.0f * 3.14159265f * float(i) / kSegments, a1 = 2.0f * 3.14159265f * float(i + 1) / kSegments;
      addLine(out, layout.center + r * glm::vec2(std::cos(a0), std::sin(a0)),
              layout.center + r * glm::vec2(std::cos(a1), std::sin(a1)), 2.5f, glm::vec3(0.95f, 0.8f, 0.2f));
    }
  }
  for (int a = 0; a < 3; ++a) {
    const glm::vec2 tip = layout.tips[a];
    const glm::vec2 d = tip - layout.center;
    const float len = glm::length(d);
    if (len < 4.0f) continue;  // pointing at the viewer
    addLine(out, layout.center, tip, 5.0f, dark);  // outline, readable on any background
    addLine(out, layout.center, tip, 3.0f, kAxisColors[a]);
    const glm::vec2 u = d / len, n(-u.y, u.x);
    if (mode == ManipulatorMode::Translate) {
      const glm::vec2 base = tip - 12.0f * u;
      for (const glm::vec2& p : {tip + 2.0f * u, base + 7.0f * n, base - 7.0f * n}) out.push_back({p, kAxisColors[a]});
    } else if (mode == ManipulatorMode::Scale) {
      addSquare(out, tip, 6.0f, dark);
      addSquare(out, tip, 4.5f, kAxisColors[a]);
    }
  }
  addSquare(out, layout.center, 6.5f, dark);
  addSquare(out, layout.center, 5.0f, glm::vec3(1.0f, 0.85f, 0.1f));
}

}  // namespace

std::vector<OverlayVertex> handleOverlay(const ScreenView& view, const std::vector<Handle>& handles,
                                         const std::optional<EditTarget>& selected, ManipulatorMode mode) {
  std::vector<OverlayVertex> out;
  const Handle* chosen = nullptr;
  for (const Handle& h : handles) {
    HandleLayout layout;
    if (!handleLayout(view, h.origin, h.frame, Modeller::kHandlePixels, &layout)) continue;
    if (selected && h.target == *selected) {
      chosen = &h;
      continue;
    }
    const glm::vec3 color = h.target.kind == EditTarget::Kind::Joint       ? glm::vec3(0.55f)
                            : h.target.kind == EditTarget::Kind::Primitive ? glm::vec3(0.95f)
                                                                           : glm::vec3(1.0f, 0.5f, 0.1f);
    addSquare(out, layout.center, 5.0f, glm::vec3(0.02f));
    addSquare(out, layout.center, 3.5f, color);
  }
  HandleLayout layout;
  if (chosen && handleLayout(view, chosen->origin, chosen->frame, Modeller::kHandlePixels, &layout))
    addSelectedHandle(out, layout, mode);
  return out;
}

const char* modeName(ManipulatorMode mode) {
  switch (mode) {
    case ManipulatorMode::Translate: return "translate";
    case ManipulatorMode::Rotate: return "rotate";
    case ManipulatorMode::Scale: return "scale";
  }
  return "?";
}

Modeller::Modeller(ViewerPipeline& pipeline) : pipeline_(pipeline) {
  mode_ = pipeline.character().hierarchical() ? ManipulatorMode::Rotate : ManipulatorMode::Translate;
}

void Modeller::selectJoint(int joint) {
  if (joint < 0) selected_.reset();
  else selected_ = EditTarget{EditTarget::Kind::Joint, joint};
}

int Modeller::selectedJoint() const {
  if (!selected_) return -1;
  if (selected_->kind == EditTarget::Kind::Joint) return selected_->index;
  const auto& primitives = pipeline_.character().primitives();
  return size_t(selected_->index) < primitives.size() ? primitives[size_t(selected_->index)].joint : -1;
}

std::optional<Handle> Modeller::handleOf(const EditTarget& target) const {
  const Character& character = pipeline_.character();
  const SkeletonCache& skeleton = pipeline_.skeleton();
  auto jointWorld = [&](int j) { return j >= 0 ? skeleton.world(j) : Rigid{}; };
  if (target.kind == EditTarget::Kind::Joint) {
    if (target.index < 0 || size_t(target.index) >= character.joints().size()) return std::nullopt;
    const glm::quat parent = jointWorld(character.joints()[size_t(target.index)].parent).rotation;
    return Handle{target, skeleton.world(target.index).translation, parent, parent};
  }
  if (target.index < 0 || size_t(target.index) >= character.primitives().size()) return std::nullopt;
  const CharacterPrimitive& p = character.primitives()[size_t(target.index)];
  const Rigid world = jointWorld(p.joint);
  Handle h{target, glm::vec3(0.0f), world.rotation, world.rotation};
  switch (target.kind) {
    case EditTarget::Kind::Endpoint1: h.origin = world.apply(p.local.p1); break;
    case EditTarget::Kind::Endpoint2: h.origin = world.apply(p.local.p2); break;
    default:
      if (p.local.kind == PrimitiveKind::LineSeg) {
        h.origin = world.apply(0.5f * (p.local.p1 + p.local.p2));
      } else {
        h.origin = world.apply(p.local.center);
        if (p.local.kind == PrimitiveKind::Ellipsoid) h.frame = glm::normalize(world.rotation * p.local.rotation);
      }
  }
  return h;
}

std::vector<Handle> Modeller::handles() const {
  std::vector<Handle> out;
  if (!enabled_) return out;
  const Character& character = pipeline_.character();
  auto addPrimitive = [&](size_t i) {
    out.push_back(*handleOf({EditTarget::Kind::Primitive, int(i)}));
    if (character.primitives()[i].local.kind != PrimitiveKind::LineSeg) return;
    out.push_back(*handleOf({EditTarget::Kind::Endpoint1, int(i)}));
    out.push_back(*handleOf({EditTarget::Kind::Endpoint2, int(i)}));
  };
  if (character.hierarchical()) {
    for (size_t j = 0; j < character.joints().size(); ++j) out.push_back(*handleOf({EditTarget::Kind::Joint, int(j)}));
    const int j = selectedJoint();
    for (size_t i = 0; i < character.primitives().size(); ++i)
      if (j >= 0 && character.primitives()[i].joint == j) addPrimitive(i);
  } else {
    for (size_t i = 0; i < character.primitives().size(); ++i) addPrimitive(i);
  }
  return out;
}

bool Modeller::press(const ScreenView& view, const glm::vec2& pixel, bool shift) {
  drag_ = Drag::None;
  grabbed_.clear();
  if (!enabled_) return false;
  // 1. The handle part nearest the cursor (primitive handles drawn over joints win ties: they come later).
  const std::vector<Handle> all = handles();
  const Handle* best = nullptr;
  HandlePart bestPart = HandlePart::None;
  float bestDistance = std::numeric_limits<float>::infinity();
  for (const Handle& h : all) {
    HandleLayout layout;
    if (!handleLayout(view, h.origin, h.frame, kHandlePixels, &layout)) continue;
    float d = 0.0f;
    HandlePart part = pickHandlePart(layout, pixel, kPickPixels, &d);
    const bool chosen = selected_ && *selected_ == h.target;
    if (part >= HandlePart::AxisX && !chosen) {
      d = glm::length(pixel - layout.center);
      part = d <= kPickPixels ? HandlePart::Center : HandlePart::None;
    }
    // In rotate mode the selected handle's whole ring turns it.
    if (part == HandlePart::None && chosen && mode_ == ManipulatorMode::Rotate &&
        glm::length(pixel - layout.center) <= 0.8f * kHandlePixels + kPickPixels)
      part = HandlePart::Center, d = kPickPixels;
    if (part != HandlePart::None && d <= bestDistance) best = &h, bestPart = part, bestDistance = d;
  }
  if (best) return grab(view, *best, bestPart, pixel, shift);
  // 2. A bone of the skeleton: turn its joint (the arcball), whatever the mode.
  const Character& character = pipeline_.character();
  if (character.hierarchical()) {
    const SkeletonCache& skeleton = pipeline_.skeleton();
    std::vector<int> parents(character.joints().size());
    std::vector<glm::vec3> world(parents.size());
    for (size_t j = 0; j < parents.size(); ++j)
      parents[j] = character.joints()[j].parent, world[j] = skeleton.world(int(j)).translation;
    const std::vector<Bone> bones = skeletonBones(parents, world);
    // 24 pixels at the window's centre, from the projection's vertical scale.
    const float fovScale = view.viewProjection[1][1];
    const float maxAngle = std::atan(24.0f / (0.5f * float(view.height)) / std::max(1e-6f, fovScale));
    const int j = pickJoint(pickRay(view, pixel), bones, maxAngle);
    if (j >= 0 || (shift && selectedJoint() >= 0)) {
      const ManipulatorMode saved = mode_;
      mode_ = ManipulatorMode::Rotate;
      const bool ok = grab(view, *handleOf({EditTarget::Kind::Joint, j >= 0 ? j : selectedJoint()}),
                           HandlePart::None, pixel, shift);
      mode_ = saved;
      return ok;
    }
  }
  return false;
}

bool Modeller::grab(const ScreenView& view, const Handle& handle, HandlePart part, const glm::vec2& pixel,
                    bool shift) {
  HandleLayout layout;
  if (!handleLayout(view, handle.origin, handle.frame, kHandlePixels, &layout)) return false;
  handle_ = handle, part_ = part, twist_ = shift;
  press_ = last_ = pixel, center_ = layout.center;
  moved_ = glm::vec3(0.0f), factor_ = 1.0f;
  refused_.clear();
  start_ = pipeline_.state();
  selected_ = handle.target;
  const bool joint = handle.target.kind == EditTarget::Kind::Joint;
  std::string how = modeName(mode_);
  if (mode_ == ManipulatorMode::Rotate) {
    how = shift ? "twist" : "arcball";
    // The arcball through the press point: the grabbed limb follows the cursor around its joint.
    arcballRadius_ = arcballRadius(center_, pixel, 0.03f * float(view.height));
  }
  // Joints turn and move through the pose while dragged (particles follow by differential transforms); everything
  // else, and a limb's length, edits the document.
  drag_ = joint && mode_ != ManipulatorMode::Scale ? Drag::Pose : Drag::Document;
  grabbed_ = how + " " + targetName(pipeline_.character(), handle.target);
  if (part_ >= HandlePart::AxisX) grabbed_ += std::string(" ") + "xyz"[int(part_) - int(HandlePart::AxisX)];
  return true;
}

void Modeller::drag(const ScreenView& view, const glm::vec2& pixel) {
  if (!refused_.empty()) return;
  if (drag_ == Drag::Pose) dragPose(view, pixel);
  else if (drag_ == Drag::Document) dragDocument(view, pixel);
  last_ = pixel;
}

glm::vec3 Modeller::translation(const ScreenView& view, const glm::vec2& pixel) const {
  if (part_ < HandlePart::AxisX) return planeDrag(view, handle_.origin, press_, pixel);
  glm::vec3 unit(0.0f);
  unit[int(part_) - int(HandlePart::AxisX)] = 1.0f;
  const glm::vec3 axis = handle_.frame * unit;
  return axisDrag(view, handle_.origin, axis, press_, pixel) * axis;
}

void Modeller::dragPose(const ScreenView& view, const glm::vec2& pixel) {
  SkeletonCache& skeleton = pipeline_.skeleton();
  const int j = handle_.target.index;
  if (mode_ == ManipulatorMode::Translate) {
    moved_ = translation(view, pixel);
    skeleton.setTranslation(j, start_.pose[size_t(j)].translation + glm::inverse(handle_.container) * moved_);
    return;
  }
  // Turning, as the bone manipulators always did: incremental, about the joint's current window position.
  glm::vec2 c;
  if (!projectToWindow(view, skeleton.world(j).translation, &c)) return;
  const glm::quat q =
      twist_ ? twistRotation(c, last_, pixel, view) : arcballRotation(c, arcballRadius_, last_, pixel, view);
  const int parent = pipeline_.character().joints()[size_t(j)].parent;
  const glm::quat parentWorld = parent >= 0 ? skeleton.world(parent).rotation : glm::quat(1, 0, 0, 0);
  skeleton.setRotation(j, rotateJointLocal(skeleton.local(j).rotation, parentWorld, q));
}

void Modeller::dragDocument(const ScreenView& view, const glm::vec2& pixel) {
  DocumentState next = start_;
  const Character& character = pipeline_.character();
  std::string why;
  if (mode_ == ManipulatorMode::Translate) {
    moved_ = translation(view, pixel);
    why = translateTarget(next, character, handle_.target, handle_.container, moved_);
  } else if (mode_ == ManipulatorMode::Scale) {
    // A press on the centre doubles 30 pixels further out; one on an axis scales by the ratio of distances.
    factor_ = scaleFactor(center_, press_, pixel, 3.0f * kPickPixels);
    const int axis = part_ >= HandlePart::AxisX ? int(part_) - int(HandlePart::AxisX) : -1;
    why = scaleTarget(next, character, handle_.target, factor_, axis);
  } else {
    const glm::quat q = twist_ ? twistRotation(center_, press_, pixel, view)
                               : arcballRotation(center_, arcballRadius_, press_, pixel, view);
    why = rotateTarget(next, character, handle_.target, handle_.container, q);
  }
  if (!why.empty()) {
    refused_ = grabbed_ + ": " + why;  // release() says so; the drag changes nothing
    return;
  }
  pipeline_.setState(std::move(next));
}

std::string Modeller::release() {
  const Drag was = std::exchange(drag_, Drag::None);
  if (was == Drag::None) return {};
  if (!refused_.empty()) return std::exchange(refused_, std::string());
  DocumentState now = pipeline_.state();
  if (was == Drag::Pose) {
    // The joint's new local transform goes into its RigidTransform, so `s` saves it and undo brings it back.
    const int j = handle_.target.index;
    DocumentState written = start_;
    written.pose = now.pose;
    const std::string why =
        mode_ == ManipulatorMode::Translate
            ? translateTarget(written, pipeline_.character(), handle_.target, handle_.container, glm::vec3(0.0f))
            : rotateTarget(written, pipeline_.character(), handle_.target, handle_.container, glm::quat(1, 0, 0, 0));
    if (!why.empty()) return grabbed_ + ": pose only (" + why + ")";
    written.pose[size_t(j)] = now.pose[size_t(j)];
    now = std::move(written);
  }
  if (now.scene == start_.scene && samePose(now.pose, start_.pose)) return {};
  history_.record(std::move(start_));
  start_ = {};
  if (was == Drag::Pose) pipeline_.setState(now);
  std::string what = grabbed_;
  if (mode_ == ManipulatorMode::Translate) what += " by " + vectorText(moved_) + " m";
  if (mode_ == ManipulatorMode::Scale) {
    char text[32];
    std::snprintf(text, sizeof text, " x%.4g", double(factor_));
    what += text;
  }
  return what;
}

std::string Modeller::apply(DocumentState state) {
  if (auto errors = pipeline_.setState(std::move(state)))
    return errors->all().empty() ? "the edited scene does not compile" : errors->all().front().message;
  return {};
}

std::string Modeller::undo() {
  if (dragging()) return "finish the drag first";
  auto back = history_.undo(pipeline_.state());
  if (!back) return "nothing to undo";
  const std::string why = apply(std::move(*back));
  return why.empty() ? "undone (" + std::to_string(history_.undoCount()) + " more)" : "undo failed: " + why;
}

std::string Modeller::redo() {
  if (dragging()) return "finish the drag first";
  auto forward = history_.redo(pipeline_.state());
  if (!forward) return "nothing to redo";
  const std::string why = apply(std::move(*forward));
  return why.empty() ? "redone (" + std::to_string(history_.redoCount()) + " more)" : "redo failed: " + why;
}

std::string Modeller::editDocument(const std::function<void(Scene&)>& change, bool final) {
  if (dragging()) return "finish the drag first";
  DocumentState before = pipeline_.state();
  DocumentState after = before;
  change(after.scene);
  refreshUses(after.scene);
  if (after.scene != before.scene) {
    if (std::string why = apply(std::move(after)); !why.empty()) return why;
    if (!previewStart_) previewStart_ = std::move(before);
  }
  if (final && previewStart_) {
    history_.record(std::move(*previewStart_));
    previewStart_.reset();
  }
  return {};
}

}  // namespace imps::app
