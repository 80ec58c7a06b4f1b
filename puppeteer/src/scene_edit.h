// SPDX-License-Identifier: MIT
// The modeller's edits of the scene document (imps::Scene): finding the RigidTransform of a joint and the shape node
// of a primitive, writing a pose into the document, translating / turning / scaling a joint, a primitive or a
// meta-line segment's endpoint, and the undo/redo history of whole document states.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "imps/character.h"
#include "imps/scene.h"

namespace imps::app {

// The document nodes behind a compiled character, in Character::fromScene's order (depth first, children in file
// order): joints[j] is joint j's RigidTransform, primitives[i] primitive i's shape node. Pointers into `scene`;
// valid until it changes shape.
struct SceneNodes {
  std::vector<TransformNode*> joints;
  std::vector<ShapeNode*> primitives;
};
SceneNodes sceneNodes(Scene& scene);

// What is on screen besides the file: the document and every joint's local transform (the pose; one per joint).
struct DocumentState {
  Scene scene;
  std::vector<Rigid> pose;
};

// Writes every joint's local transform (pose[j], one per joint of the document's character) into the joints'
// RigidTransforms, matched by position in the document, so unnamed transforms keep their pose too.
void writePose(Scene& scene, const std::vector<Rigid>& pose);

// A rotation as the document writes it (unit axis and angle in [0, pi]; the identity as 0 0 1 0).
Rotation toRotation(const glm::quat& q);

// What an edit acts on: joint `index` (its RigidTransform), primitive `index` as a whole, or one endpoint of
// primitive `index` (a LineSeg).
struct EditTarget {
  enum class Kind { Joint, Primitive, Endpoint1, Endpoint2 } kind = Kind::Joint;
  int index = -1;
  bool operator==(const EditTarget&) const = default;
};

// The target's name for messages: the joint's or primitive's name, ".point1" / ".point2" for endpoints.
std::string targetName(const Character& character, const EditTarget& target);

// The edits. Each changes `state` (its scene and, for joints, its pose) as the modeller's handles do, given the
// character compiled from state.scene and the world rotation of the frame the target's values live in
// (`containerWorld`: a joint's parent's world rotation; a primitive's joint's; the identity for a flat scene's
// primitives). They return "" on success and otherwise the reason nothing changed (a USE'd copy, a target that
// cannot take this edit); the DEF'd node of a shape is edited together with every `USE` of it.
//
// Translate by a world-space vector (metres): a joint's translation, a primitive's centre (a LineSeg's both
// endpoints), or one endpoint.
std::string translateTarget(DocumentState& state, const Character& character, const EditTarget& target,
                            const glm::quat& containerWorld, const glm::vec3& worldDelta);
// Turn by a world-space rotation about the target's own origin: a joint's rotation, an ellipsoid's orientation, a
// LineSeg about its midpoint. Metaballs and endpoints have no orientation.
std::string rotateTarget(DocumentState& state, const Character& character, const EditTarget& target,
                         const glm::quat& containerWorld, const glm::quat& worldRotation);
// Scale by `factor` (> 0): a metaball's radius; an endpoint's radius; a LineSeg's two radii; an ellipsoid's radii
// (`axis` 0–2: only that semi-axis, -1: all three); a joint's limb length (the positions of everything in its frame —
// its primitives' centres and endpoints, its child joints' translations — scale about its origin; radii do not).
// Radii stay at least 1e-3 m.
std::string scaleTarget(DocumentState& state, const Character& character, const EditTarget& target, float factor,
                        int axis);

// Makes every `USE NAME` copy in the scene graph equal to its DEF'd node again (as the reader makes it), so an edit
// of a DEF'd node shows in its copies and the saved file reads back to what is on screen. The edits above call it.
void refreshUses(Scene& scene);

// The blending function in force: a flat scene's root blend node, else the polygonizer's blendingFunction; null
// when the scene has neither (the default blend applies).
BlendNode* blendInForce(Scene& scene);
const BlendNode* blendInForce(const Scene& scene);
// The polygonizer node's isoValue; null for a bare scene graph (iso-value 1).
float* isoValueOf(Scene& scene);
const float* isoValueOf(const Scene& scene);

// Undo/redo of whole document states (scenes are small: a copy per edit, at most `limit` kept).
class EditHistory {
 public:
  explicit EditHistory(size_t limit = 200) : limit_(limit) {}
  // An edit is about to replace `before`: it becomes the state undo() returns; the redo list is dropped.
  void record(DocumentState before);
  // The state to go back to, given the `current` one (which redo() will then return); nullopt when none.
  std::optional<DocumentState> undo(DocumentState current);
  std::optional<DocumentState> redo(DocumentState current);
  size_t undoCount() const { return undo_.size(); }
  size_t redoCount() const { return redo_.size(); }

 private:
  size_t limit_;
  std::vector<DocumentState> undo_, redo_;
};

}  // namespace imps::app
