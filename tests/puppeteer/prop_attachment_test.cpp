// SPDX-License-Identifier: MIT
// Props in a character's world: `--prop FILE.wrl[@JOINT]` loads every Shape of the file (attached to the joint when
// named), a prop on a joint follows the joint's posed world transform while a free one stays put, `--grab` specs
// parse or are refused with a message, and a grabbed prop moves with the hand only between the pick and the drop.
#include "prop_attachment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "examples.h"
#include "imps/skeleton_cache.h"

namespace imps::app {
namespace {

const std::string kHat = std::string(IMPS_SOURCE_DIR) + "/examples/beanito_hat.wrl";

glm::vec3 vertex(const Mesh& mesh, size_t i) {
  return {mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]};
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-4f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(PropAttachment, LoadsEveryShapeAttachedToTheNamedJoint) {
  const Character& beanito = test::exampleCharacter("beanito");
  Diagnostics warnings;
  const auto attached = loadProps({kHat + "@BEAN_TOP"}, beanito, &warnings);
  ASSERT_TRUE(attached.has_value()) << attached.error().str();
  ASSERT_EQ(attached->size(), 3u);  // BRIM, CROWN, BAND
  EXPECT_EQ((*attached)[0].name, "BRIM");
  for (const AttachedProp& p : *attached) {
    EXPECT_EQ(p.joint, beanito.findJoint("BEAN_TOP"));
    EXPECT_GT(p.mesh.triangleCount(), 0u) << p.name;
  }
  // Without @JOINT the props stay in the world; two specs give both sets, in order.
  const auto free = loadProps({kHat, kHat + "@BEAN_TOP"}, beanito, nullptr);
  ASSERT_TRUE(free.has_value());
  ASSERT_EQ(free->size(), 6u);
  EXPECT_EQ((*free)[0].joint, -1);
  EXPECT_GE((*free)[5].joint, 0);
}

TEST(PropAttachment, BadSpecsAreWholeMessages) {
  const Character& beanito = test::exampleCharacter("beanito");
  const auto noJoint = loadProps({kHat + "@NO_SUCH"}, beanito, nullptr);
  ASSERT_FALSE(noJoint.has_value());
  EXPECT_EQ(noJoint.error().str(), "puppeteer: error: --prop " + kHat + "@NO_SUCH: the scene has no joint 'NO_SUCH'\n");
  const auto noFile = loadProps({"/no/such/hat.wrl"}, beanito, nullptr);
  ASSERT_FALSE(noFile.has_value());
  EXPECT_NE(noFile.error().str().find("/no/such/hat.wrl"), std::string::npos) << noFile.error().str();
}

TEST(PropAttachment, AnAttachedPropFollowsItsJointAndAFreeOneStays) {
  const Character& beanito = test::exampleCharacter("beanito");
  const int top = beanito.findJoint("BEAN_TOP");
  ASSERT_GE(top, 0);
  Mesh square;
  square.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  square.indices = {0, 1, 2};
  const std::vector<AttachedProp> props = {{"onTop", square, top}, {"free", square, -1}};
  SkeletonCache skeleton(beanito);
  skeleton.setRotation(top, glm::angleAxis(0.7f, glm::vec3(0, 0, 1)));
  skeleton.update();
  Mesh mesh;
  mesh.positions = {9, 9, 9};  // something already there stays first
  appendPosedProps(mesh, props, skeleton);
  ASSERT_EQ(mesh.vertexCount(), 7u);
  expectNear(vertex(mesh, 0), {9, 9, 9});
  const Rigid& world = skeleton.world(top);
  for (size_t i = 0; i < 3; ++i) {
    expectNear(vertex(mesh, 1 + i), world.apply(vertex(square, i)));
    expectNear(vertex(mesh, 4 + i), vertex(square, i));
  }
  EXPECT_EQ(mesh.triangleCount(), 2u);
}

TEST(PropAttachment, ParseGrab) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const auto ok = parseGrab("props/ball.wrl@L_Hand@0.5:1.25", biped);
  ASSERT_TRUE(ok.has_value()) << ok.error().str();
  EXPECT_EQ(ok->first, "props/ball.wrl");
  EXPECT_EQ(ok->second.joint, biped.findJoint("L_Hand"));
  EXPECT_EQ(ok->second.pickSeconds, 0.5);
  EXPECT_EQ(ok->second.dropSeconds, 1.25);
  for (const char* bad :
       {"ball.wrl", "ball.wrl@L_Hand", "ball.wrl@L_Hand@1", "ball.wrl@Nobody@0:1", "ball.wrl@L_Hand@x:1",
        "ball.wrl@L_Hand@0:1s", "ball.wrl@L_Hand@2:1", "ball.wrl@L_Hand@-1:1", "ball.wrl@L_Hand@0:inf"}) {
    const auto refused = parseGrab(bad, biped);
    ASSERT_FALSE(refused.has_value()) << bad;
    EXPECT_EQ(refused.error().str().rfind(std::string("puppeteer: error: --grab ") + bad + ": ", 0), 0u)
        << refused.error().str();
  }
}

TEST(PropAttachment, AGrabbedPropMovesWithTheHandOnlyWhileHeld) {
  // The hand slides along +x at 1 m/s and turns about z.
  auto hand = [](double t) {
    return Rigid{glm::angleAxis(float(t), glm::vec3(0, 0, 1)), glm::vec3(float(t), 0.5f, 0)};
  };
  const Grab grab{3, 1.0, 2.0};
  const glm::vec3 p(1.2f, 0.5f, 0.0f);                     // a point of the prop, in the hand at the pick
  expectNear(grabbedMotion(grab, 0.5, hand).apply(p), p);  // before the pick: untouched
  // While held it keeps its place in the hand's frame.
  const glm::vec3 inHand = hand(1.0).inverse().apply(p);
  expectNear(grabbedMotion(grab, 1.5, hand).apply(p), hand(1.5).apply(inHand));
  // After the drop it stays where the hand left it.
  expectNear(grabbedMotion(grab, 5.0, hand).apply(p), hand(2.0).apply(inHand));
  expectNear(grabbedMotion(grab, 1.0, hand).apply(p), p);  // continuous at the pick
}

}  // namespace
}  // namespace imps::app
