// SPDX-License-Identifier: MIT
// The interactive modeller without a window, driven by window-pixel mouse events as the viewer drives it: a dragged
// translate handle moves its primitive by the dragged amount, a scale handle sets a metaball's radius, a bone drag
// turns a joint and writes it into the document, undo/redo restore the document and the pose, and what is on screen
// saves and re-opens identically.
#include "modeller.h"

#include <gtest/gtest.h>

#include <string>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "imps/scene_writer.h"

namespace imps::app {
namespace {

constexpr int kWidth = 1280, kHeight = 720;

std::unique_ptr<ViewerPipeline> load(const std::string& path) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/" + path);
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;  // the modeller needs no mesh
  return std::make_unique<ViewerPipeline>(std::move(*scene), std::move(*character), o);
}

// The app's first view of the pipeline.
ScreenView viewOf(const ViewerPipeline& pipeline) {
  float radius = 1.0f;
  const OrbitCamera orbit = initialOrbit(pipeline, kWidth, kHeight, &radius);
  return screenView(orbit.camera(), kWidth, kHeight, radius);
}

glm::vec2 project(const ScreenView& v, const glm::vec3& p) {
  glm::vec2 out(-1.0f);
  EXPECT_TRUE(projectToWindow(v, p, &out));
  return out;
}

// A whole drag as the viewer delivers a scripted one: press, eight moves, release.
std::string dragFromTo(Modeller& m, const ScreenView& v, glm::vec2 from, glm::vec2 to, bool shift = false) {
  if (!m.press(v, from, shift)) return "(nothing grabbed)";
  for (int i = 1; i <= 8; ++i) m.drag(v, from + (to - from) * (float(i) / 8.0f));
  return m.release();
}

const ShapeNode& shape(const ViewerPipeline& p, int i) {
  return *sceneNodes(const_cast<Scene&>(p.scene())).primitives[size_t(i)];
}

TEST(Modeller, HandlesPerPrimitiveInFlatScenesAndPerJointInHierarchies) {
  auto blobs = load("examples/textured_blobs.wrl");
  Modeller flat(*blobs);
  EXPECT_EQ(flat.mode(), ManipulatorMode::Translate);
  EXPECT_EQ(flat.handles().size(), 2u);  // two metaballs
  auto biped = load("examples/simple_biped.wrl");
  Modeller tree(*biped);
  EXPECT_EQ(tree.mode(), ManipulatorMode::Rotate);
  const size_t joints = biped->character().joints().size();
  EXPECT_EQ(tree.handles().size(), joints);
  // Selecting a joint adds its primitives, and each LineSeg's two endpoints.
  const int arm = biped->character().findJoint("L_UpperArm");
  tree.selectJoint(arm);
  size_t extra = 0;
  for (const CharacterPrimitive& p : biped->character().primitives())
    if (p.joint == arm) extra += p.local.kind == PrimitiveKind::LineSeg ? 3 : 1;
  EXPECT_GT(extra, 0u);
  EXPECT_EQ(tree.handles().size(), joints + extra);
  tree.setEnabled(false);
  EXPECT_TRUE(tree.handles().empty());
  EXPECT_FALSE(tree.press(viewOf(*biped), project(viewOf(*biped), biped->skeleton().world(arm).translation), false));
}

TEST(Modeller, DraggingATranslateHandleMovesThePrimitiveByTheDraggedAmount) {
  auto p = load("examples/textured_blobs.wrl");
  Modeller m(*p);
  const ScreenView v = viewOf(*p);
  const glm::vec3 before = shape(*p, 0).center;
  const glm::vec2 from = project(v, before), to = from + glm::vec2(80.0f, -45.0f);
  const std::string what = dragFromTo(m, v, from, to);
  EXPECT_EQ(what.rfind("translate LEFT by ", 0), 0u) << what;
  const glm::vec3 after = shape(*p, 0).center;
  // The centre is under the cursor where the drag ended, at the same depth; the other metaball stayed.
  EXPECT_LT(glm::length(project(v, after) - to), 0.05f);
  EXPECT_NEAR(glm::dot(after - before, v.towardsViewer), 0.0f, 1e-5f);
  EXPECT_EQ(shape(*p, 1).center, glm::vec3(0.9f, 0, 0));
  // The compiled character follows the document.
  EXPECT_EQ(p->character().primitives()[0].local.center, after);
}

TEST(Modeller, AnAxisHandleMovesAlongItsAxisOnly) {
  auto p = load("examples/textured_blobs.wrl");
  Modeller m(*p);
  const ScreenView v = viewOf(*p);
  const glm::vec3 before = shape(*p, 1).center;
  const glm::vec2 c = project(v, before);
  ASSERT_EQ(dragFromTo(m, v, c, c), "");  // a click selects (and changes nothing)
  ASSERT_TRUE(m.selected().has_value());
  HandleLayout layout;
  ASSERT_TRUE(handleLayout(v, before, glm::quat(1, 0, 0, 0), Modeller::kHandlePixels, &layout));
  const glm::vec2 tip = layout.tips[1];  // +y
  const std::string what = dragFromTo(m, v, tip, tip + glm::vec2(7.0f, -40.0f));
  EXPECT_EQ(what.rfind("translate RIGHT y by ", 0), 0u) << what;
  const glm::vec3 after = shape(*p, 1).center;
  EXPECT_EQ(after.x, before.x);
  EXPECT_EQ(after.z, before.z);
  EXPECT_GT(after.y, before.y + 0.05f);
}

TEST(Modeller, ScalingAMetaballSetsItsRadius) {
  auto p = load("examples/textured_blobs.wrl");
  Modeller m(*p);
  m.setMode(ManipulatorMode::Scale);
  const ScreenView v = viewOf(*p);
  const glm::vec3 centre = shape(*p, 0).center;
  const glm::vec2 c = project(v, centre);
  dragFromTo(m, v, c, c);  // select LEFT
  HandleLayout layout;
  ASSERT_TRUE(handleLayout(v, centre, glm::quat(1, 0, 0, 0), Modeller::kHandlePixels, &layout));
  const glm::vec2 tip = layout.tips[0];
  const std::string what = dragFromTo(m, v, tip, c + 1.5f * (tip - c));
  EXPECT_EQ(what.rfind("scale LEFT x x1.5", 0), 0u) << what;
  EXPECT_NEAR(shape(*p, 0).radius, 1.5f, 1e-4f);
  EXPECT_EQ(shape(*p, 0).center, centre);
  EXPECT_NEAR(p->character().primitives()[0].local.radius, 1.5f, 1e-4f);
}

TEST(Modeller, UndoRedoRestoreTheDocumentAndSaveReopensIdentically) {
  auto p = load("examples/textured_blobs.wrl");
  Modeller m(*p);
  const ScreenView v = viewOf(*p);
  const Scene original = p->scene();
  const glm::vec2 c = project(v, shape(*p, 0).center);
  ASSERT_NE(dragFromTo(m, v, c, c + glm::vec2(50, 0)), "");
  const Scene moved = p->scene();
  m.setMode(ManipulatorMode::Scale);
  const glm::vec3 centre = shape(*p, 0).center;
  HandleLayout layout;
  ASSERT_TRUE(handleLayout(v, centre, glm::quat(1, 0, 0, 0), Modeller::kHandlePixels, &layout));
  const glm::vec2 c2 = layout.center, tip = layout.tips[0];
  ASSERT_NE(dragFromTo(m, v, tip, c2 + 0.5f * (tip - c2)), "");
  EXPECT_NEAR(shape(*p, 0).radius, 0.5f, 1e-4f);
  const Scene scaled = p->scene();
  EXPECT_EQ(m.history().undoCount(), 2u);
  m.undo();
  EXPECT_TRUE(p->scene() == moved);
  m.undo();
  EXPECT_TRUE(p->scene() == original);
  EXPECT_EQ(m.undo(), "nothing to undo");
  EXPECT_EQ(p->character().primitives()[0].local.center, glm::vec3(-0.9f, 0, 0));
  m.redo();
  m.redo();
  EXPECT_TRUE(p->scene() == scaled);
  EXPECT_EQ(m.redo(), "nothing to redo");
  // Saved and re-opened: the same document, the same primitives.
  auto back = readScene(writeScene(p->posedScene()), "saved.wrl");
  ASSERT_TRUE(back.has_value());
  EXPECT_TRUE(*back == p->scene());
  auto character = Character::fromScene(*back);
  ASSERT_TRUE(character.has_value());
  for (size_t i = 0; i < character->primitives().size(); ++i) {
    EXPECT_EQ(character->primitives()[i].local.center, p->character().primitives()[i].local.center);
    EXPECT_EQ(character->primitives()[i].local.radius, p->character().primitives()[i].local.radius);
  }
}

TEST(Modeller, AUseCopyCannotBeDraggedAndSaysWhy) {
  auto scene = readScene(R"(#VRML V2.0 utf8
MarchingCubes { sceneGraph ExponentialBlend { children [ DEF A Metaball { center -1 0 0 } USE A ] } }
)",
                         "use.wrl");
  ASSERT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  ASSERT_TRUE(character.has_value());
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;
  ViewerPipeline p(*scene, std::move(*character), o);
  Modeller m(p);
  const ScreenView v = viewOf(p);
  // Both copies sit at the same place: the later handle (the USE) wins the tie.
  const glm::vec2 c = project(v, {-1, 0, 0});
  const std::string what = dragFromTo(m, v, c, c + glm::vec2(30, 0));
  EXPECT_EQ(what, "translate metaball1: a USE of A: edit A itself");
  EXPECT_TRUE(p.scene() == *scene);
  EXPECT_EQ(m.history().undoCount(), 0u);
}

TEST(Modeller, ABoneDragTurnsTheJointIntoTheDocumentAndUndoTurnsItBack) {
  auto p = load("examples/simple_biped.wrl");
  Modeller m(*p);
  const ScreenView v = viewOf(*p);
  const int arm = p->character().findJoint("L_UpperArm");
  int hand = -1;
  for (size_t j = 0; j < p->character().joints().size(); ++j)
    if (p->character().joints()[j].parent == arm) hand = int(j);
  ASSERT_GE(hand, 0);
  const glm::vec3 a = p->skeleton().world(arm).translation, b = p->skeleton().world(hand).translation;
  const glm::vec2 grab = project(v, a + 0.7f * (b - a));
  const Rigid rest = p->skeleton().local(arm);
  const std::string what = dragFromTo(m, v, grab, grab + glm::vec2(20, 80));
  EXPECT_EQ(what, "arcball L_UpperArm");
  const Rigid turned = p->skeleton().local(arm);
  EXPECT_LT(std::abs(glm::dot(turned.rotation, rest.rotation)), 0.999f);
  // The document holds the new rotation: recompiled, the joint's rest is the pose.
  EXPECT_GT(std::abs(glm::dot(p->character().joints()[size_t(arm)].rest.rotation, turned.rotation)), 1.0f - 1e-6f);
  m.undo();
  EXPECT_GT(std::abs(glm::dot(p->skeleton().local(arm).rotation, rest.rotation)), 1.0f - 1e-6f);
  EXPECT_GT(std::abs(glm::dot(p->character().joints()[size_t(arm)].rest.rotation, rest.rotation)), 1.0f - 1e-6f);
}

TEST(Modeller, TranslatingAJointHandleMovesTheJointUnderTheCursor) {
  auto p = load("examples/simple_biped.wrl");
  Modeller m(*p);
  m.setMode(ManipulatorMode::Translate);
  const ScreenView v = viewOf(*p);
  const int head = p->character().findJoint("Head");
  ASSERT_GE(head, 0);
  const glm::vec2 c = project(v, p->skeleton().world(head).translation);
  const std::string what = dragFromTo(m, v, c, c + glm::vec2(0, -30));
  EXPECT_EQ(what.rfind("translate Head by ", 0), 0u) << what;
  EXPECT_LT(glm::length(project(v, p->skeleton().world(head).translation) - (c + glm::vec2(0, -30))), 0.05f);
  // In the document: the joint's RigidTransform got the new translation.
  EXPECT_EQ(p->character().joints()[size_t(head)].rest.translation, p->skeleton().local(head).translation);
}

TEST(Modeller, MenuEditsArePreviewedLiveAndUndoneAsOne) {
  auto p = load("examples/textured_blobs.wrl");
  Modeller m(*p);
  const float iso = p->character().iso();
  for (float v : {1.1f, 1.2f, 1.3f})
    EXPECT_EQ(m.editDocument([v](Scene& s) { *isoValueOf(s) = v; }, false), "");
  EXPECT_FLOAT_EQ(p->character().iso(), 1.3f);
  EXPECT_EQ(m.editDocument([](Scene& s) { blendInForce(s)->variance = 2.0f; }, true), "");
  EXPECT_EQ(m.history().undoCount(), 1u);
  m.undo();
  EXPECT_FLOAT_EQ(p->character().iso(), iso);
  EXPECT_FLOAT_EQ(blendInForce(const_cast<Scene&>(p->scene()))->variance, 1.0f);
  // A document that does not compile is refused and changes nothing.
  const Scene before = p->scene();
  EXPECT_NE(m.editDocument([](Scene& s) { std::get<BlendNode>(*s.sceneGraph()).children.clear(); }), "");
  EXPECT_TRUE(p->scene() == before);
}

}  // namespace
}  // namespace imps::app
