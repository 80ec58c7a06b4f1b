// SPDX-License-Identifier: MIT
// The modeller's document edits without a window: a pose written into unnamed transforms too, translate / rotate /
// scale of joints, primitives and endpoints (USE copies follow their DEF), limb length, round trips through the
// writer, and the undo/redo history.
#include "scene_edit.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "imps/scene_writer.h"
#include "viewer_pipeline.h"

namespace imps::app {
namespace {

Scene parse(const std::string& text) {
  auto scene = readScene(text, "test.wrl");
  EXPECT_TRUE(scene.has_value()) << (scene ? "" : scene.error().str());
  return scene ? *scene : Scene{};
}

Character compile(const Scene& scene) {
  auto c = Character::fromScene(scene);
  EXPECT_TRUE(c.has_value()) << (c ? "" : c.error().str());
  return std::move(*c);
}

DocumentState stateOf(const Scene& scene) {
  const Character c = compile(scene);
  DocumentState s{scene, {}};
  for (const Joint& j : c.joints()) s.pose.push_back(j.rest);
  return s;
}

// Reading back what the writer makes gives the same document (what `s` saves re-opens identically).
void expectRoundTrip(const Scene& scene) {
  auto back = readScene(writeScene(scene), "saved.wrl");
  ASSERT_TRUE(back.has_value()) << back.error().str();
  EXPECT_TRUE(*back == scene) << writeScene(scene);
  EXPECT_EQ(writeScene(*back), writeScene(scene));
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

// A chain of three joints, the middle and last without DEF names.
const char* const kChain = R"(#VRML V2.0 utf8
Tesselator3MP {
  blendingFunction ExponentialBlend { variance 1 }
  sceneGraph DEF Root RigidTransform {
    children [
      Metaball { radius 0.4 }
      RigidTransform {
        translation 0 -1 0
        children [
          LineSeg { point1 0 0 0 point2 0 -1 0 radius1 0.3 radius2 0.2 }
          RigidTransform { translation 0 -1 0 children [ Ellipsoid { radii 0.3 0.2 0.1 } ] }
        ]
      }
    ]
  }
}
)";

// A flat scene whose second metaball is a USE of the first.
const char* const kFlat = R"(#VRML V2.0 utf8
MarchingCubes {
  sceneGraph ExponentialBlend {
    children [
      DEF A Metaball { center -0.5 0 0 radius 0.5 }
      USE A
      DEF S LineSeg { point1 1 0 0 point2 2 0 0 radius1 0.3 radius2 0.3 }
    ]
  }
}
)";

TEST(SceneEdit, NodesInCharacterOrder) {
  Scene scene = parse(kChain);
  const Character c = compile(scene);
  const SceneNodes nodes = sceneNodes(scene);
  ASSERT_EQ(nodes.joints.size(), c.joints().size());
  ASSERT_EQ(nodes.primitives.size(), c.primitives().size());
  EXPECT_EQ(nodes.joints[0]->name, "Root");
  EXPECT_EQ(nodes.primitives[1]->kind, ShapeKind::LineSeg);
  EXPECT_EQ(nodes.primitives[2]->kind, ShapeKind::Ellipsoid);
}

// Before, the pose was written into named transforms only: a turned unnamed joint was lost on save.
TEST(SceneEdit, PoseOfUnnamedTransformsIsSaved) {
  Scene scene = parse(kChain);
  Character character = compile(scene);
  ViewerPipeline pipeline(scene, std::move(character), PipelineOptions{});
  const glm::quat q = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 0, 1)));
  pipeline.skeleton().setRotation(1, q);
  pipeline.skeleton().setTranslation(2, glm::vec3(0.1f, -1.2f, 0.0f));
  const Scene posed = pipeline.posedScene();
  expectRoundTrip(posed);
  const Character back = compile(*readScene(writeScene(posed), "posed.wrl"));
  EXPECT_GT(std::abs(glm::dot(back.joints()[1].rest.rotation, q)), 1.0f - 1e-6f);
  expectNear(back.joints()[2].rest.translation, {0.1f, -1.2f, 0.0f});
}

TEST(SceneEdit, TranslateAPrimitiveMovesItsUseCopiesToo) {
  const Scene scene = parse(kFlat);
  DocumentState s = stateOf(scene);
  const Character c = compile(scene);
  EXPECT_EQ(translateTarget(s, c, {EditTarget::Kind::Primitive, 0}, glm::quat(1, 0, 0, 0), {0.25f, 0.5f, 0}), "");
  const SceneNodes nodes = sceneNodes(s.scene);
  expectNear(nodes.primitives[0]->center, {-0.25f, 0.5f, 0});
  expectNear(nodes.primitives[1]->center, {-0.25f, 0.5f, 0});
  EXPECT_EQ(nodes.primitives[1]->useOf, "A");
  expectRoundTrip(s.scene);
  // The USE itself is not edited (the file could not say it).
  DocumentState t = stateOf(scene);
  EXPECT_NE(translateTarget(t, c, {EditTarget::Kind::Primitive, 1}, glm::quat(1, 0, 0, 0), {1, 0, 0}), "");
  EXPECT_TRUE(t.scene == scene);
}

TEST(SceneEdit, LineSegEndpointsAndRadii) {
  const Scene scene = parse(kFlat);
  const Character c = compile(scene);
  DocumentState s = stateOf(scene);
  EXPECT_EQ(translateTarget(s, c, {EditTarget::Kind::Endpoint2, 2}, glm::quat(1, 0, 0, 0), {0, 1, 0}), "");
  EXPECT_EQ(scaleTarget(s, c, {EditTarget::Kind::Endpoint1, 2}, 2.0f, -1), "");
  const ShapeNode& seg = *sceneNodes(s.scene).primitives[2];
  expectNear(seg.point1, {1, 0, 0});
  expectNear(seg.point2, {2, 1, 0});
  EXPECT_FLOAT_EQ(seg.radius1, 0.6f);
  EXPECT_FLOAT_EQ(seg.radius2, 0.3f);
  // The whole segment turns about its midpoint; a metaball has no orientation, and no endpoints.
  EXPECT_EQ(rotateTarget(s, c, {EditTarget::Kind::Primitive, 2}, glm::quat(1, 0, 0, 0),
                         glm::angleAxis(3.14159265f, glm::vec3(0, 0, 1))),
            "");
  const ShapeNode& turned = *sceneNodes(s.scene).primitives[2];
  expectNear(turned.point1, {2, 1, 0}, 1e-5f);
  expectNear(turned.point2, {1, 0, 0}, 1e-5f);
  const Scene before = s.scene;
  EXPECT_NE(rotateTarget(s, c, {EditTarget::Kind::Primitive, 0}, glm::quat(1, 0, 0, 0),
                         glm::angleAxis(1.0f, glm::vec3(0, 0, 1))),
            "");
  EXPECT_NE(translateTarget(s, c, {EditTarget::Kind::Endpoint1, 0}, glm::quat(1, 0, 0, 0), {1, 0, 0}), "");
  EXPECT_TRUE(s.scene == before);
  expectRoundTrip(s.scene);
}

TEST(SceneEdit, ScaleMetaballEllipsoidAxisAndMinimumRadius) {
  const Scene scene = parse(kChain);
  const Character c = compile(scene);
  DocumentState s = stateOf(scene);
  EXPECT_EQ(scaleTarget(s, c, {EditTarget::Kind::Primitive, 0}, 1.5f, -1), "");
  EXPECT_EQ(scaleTarget(s, c, {EditTarget::Kind::Primitive, 2}, 2.0f, 1), "");
  SceneNodes nodes = sceneNodes(s.scene);
  EXPECT_FLOAT_EQ(nodes.primitives[0]->radius, 0.6f);
  expectNear(nodes.primitives[2]->radii, {0.3f, 0.4f, 0.1f});
  EXPECT_EQ(scaleTarget(s, c, {EditTarget::Kind::Primitive, 2}, 1e-6f, -1), "");
  expectNear(sceneNodes(s.scene).primitives[2]->radii, {1e-3f, 1e-3f, 1e-3f});
  EXPECT_NE(scaleTarget(s, c, {EditTarget::Kind::Primitive, 0}, -1.0f, -1), "");
  EXPECT_NE(scaleTarget(s, c, {EditTarget::Kind::Primitive, 0}, std::nanf(""), -1), "");
  expectRoundTrip(s.scene);
}

// Limb length (thesis 6.1): the middle joint's segment and its child joint lengthen; radii stay.
TEST(SceneEdit, ScaleAJointChangesItsLimbLength) {
  const Scene scene = parse(kChain);
  const Character c = compile(scene);
  DocumentState s = stateOf(scene);
  EXPECT_EQ(scaleTarget(s, c, {EditTarget::Kind::Joint, 1}, 1.5f, -1), "");
  const SceneNodes nodes = sceneNodes(s.scene);
  expectNear(nodes.primitives[1]->point2, {0, -1.5f, 0});
  EXPECT_FLOAT_EQ(nodes.primitives[1]->radius1, 0.3f);
  expectNear(nodes.joints[2]->translation, {0, -1.5f, 0});
  expectNear(nodes.joints[1]->translation, {0, -1, 0});  // the joint itself stays where it is
  expectNear(s.pose[2].translation, {0, -1.5f, 0});
  expectRoundTrip(s.scene);
}

// A world-space drag under a turned parent lands where it was dragged.
TEST(SceneEdit, JointTranslationIsInTheParentsFrame) {
  const Scene scene = parse(kChain);
  Character character = compile(scene);
  ViewerPipeline pipeline(scene, std::move(character), PipelineOptions{});
  pipeline.skeleton().setRotation(0, glm::angleAxis(1.1f, glm::normalize(glm::vec3(0.3f, 1, 0.2f))));
  pipeline.skeleton().update();
  const glm::vec3 before = pipeline.skeleton().world(1).translation;
  const glm::vec3 delta(0.2f, -0.1f, 0.35f);
  DocumentState s = pipeline.state();
  EXPECT_EQ(translateTarget(s, pipeline.character(), {EditTarget::Kind::Joint, 1},
                            pipeline.skeleton().world(0).rotation, delta),
            "");
  ASSERT_FALSE(pipeline.setState(s).has_value());
  expectNear(pipeline.skeleton().world(1).translation, before + delta, 1e-5f);
  expectNear(sceneNodes(s.scene).joints[1]->translation, s.pose[1].translation);
}

TEST(SceneEdit, HistoryUndoRedo) {
  const Scene scene = parse(kFlat);
  const Character c = compile(scene);
  EditHistory history(2);
  DocumentState a = stateOf(scene), b = a, cState = a, d = a;
  translateTarget(b, c, {EditTarget::Kind::Primitive, 0}, glm::quat(1, 0, 0, 0), {1, 0, 0});
  cState = b;
  translateTarget(cState, c, {EditTarget::Kind::Primitive, 0}, glm::quat(1, 0, 0, 0), {0, 1, 0});
  EXPECT_FALSE(history.undo(a).has_value());
  history.record(a);  // a -> b
  history.record(b);  // b -> c
  auto back = history.undo(cState);
  ASSERT_TRUE(back.has_value());
  EXPECT_TRUE(back->scene == b.scene);
  back = history.undo(*back);
  ASSERT_TRUE(back.has_value());
  EXPECT_TRUE(back->scene == a.scene);
  EXPECT_FALSE(history.undo(*back).has_value());
  auto forward = history.redo(a);
  ASSERT_TRUE(forward.has_value());
  EXPECT_TRUE(forward->scene == b.scene);
  // A new edit drops the redo list; the limit keeps the newest states.
  history.record(*forward);
  EXPECT_EQ(history.redoCount(), 0u);
  history.record(d);
  EXPECT_EQ(history.undoCount(), 2u);
}

TEST(SceneEdit, BlendAndIsoValueInForce) {
  Scene flat = parse(kFlat);
  ASSERT_NE(blendInForce(flat), nullptr);
  EXPECT_EQ(blendInForce(flat), &std::get<BlendNode>(*flat.sceneGraph()));
  ASSERT_NE(isoValueOf(flat), nullptr);
  Scene chain = parse(kChain);
  ASSERT_NE(blendInForce(chain), nullptr);
  EXPECT_EQ(blendInForce(chain), &*std::get<Tesselator3MPNode>(chain.polygonizer).blendingFunction);
  Scene bare = parse("#VRML V2.0 utf8\nRigidTransform { children [ Metaball { } ] }\n");
  EXPECT_EQ(blendInForce(bare), nullptr);
  EXPECT_EQ(isoValueOf(bare), nullptr);
}

}  // namespace
}  // namespace imps::app
