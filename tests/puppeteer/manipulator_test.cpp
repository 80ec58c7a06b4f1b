// SPDX-License-Identifier: MIT
// The manipulators' maths without a window (the projection and pick rays they use are tested in camera_test.cpp):
// picking finds the bone under the cursor (and the joint that starts where two bones meet), the arcball is a
// two-axis trackball near its centre and makes a grabbed limb follow the cursor, the twist turns about the view axis,
// and a world rotation becomes the right local rotation under a turned parent.
#include "manipulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <glm/gtc/quaternion.hpp>

namespace imps::app {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

// A camera on +z looking at the origin, y up, in a 640x480 window: screen right = +x, up = +y, towards viewer = +z.
ScreenView frontView() { return screenView(Camera{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f}, 640, 480, 2.0f); }

glm::vec2 project(const ScreenView& v, const glm::vec3& p) {
  glm::vec2 out(-1.0f);
  EXPECT_TRUE(projectToWindow(v, p, &out));
  return out;
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-4f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(Manipulator, BonesOfASkeleton) {
  // 0 root → 1 upper arm → 2 forearm (leaf); 0 → 3 thigh (leaf).
  const std::vector<int> parents = {-1, 0, 1, 0};
  const std::vector<glm::vec3> world = {{0, 0, 0}, {0.2f, 0.4f, 0}, {0.6f, 0.4f, 0}, {0.1f, -0.1f, 0}};
  const std::vector<Bone> bones = skeletonBones(parents, world);
  ASSERT_EQ(bones.size(), 5u);  // 0-1, 1-2, 0-3, and the leaves 2 and 3 as points
  EXPECT_EQ(bones[0].joint, 0);
  expectNear(bones[1].a, world[1]);
  expectNear(bones[1].b, world[2]);
  EXPECT_EQ(bones[3].joint, 2);
  expectNear(bones[3].a, bones[3].b);
}

TEST(Manipulator, PickJointByBone) {
  const ScreenView v = frontView();
  // A horizontal arm: shoulder (joint 1) at x 0.2, elbow (joint 2) at x 0.6, wrist (joint 3, leaf) at x 1.0.
  const std::vector<int> parents = {-1, 0, 1, 2};
  const std::vector<glm::vec3> world = {{0, 0, 0}, {0.2f, 0, 0}, {0.6f, 0, 0}, {1.0f, 0, 0}};
  const std::vector<Bone> bones = skeletonBones(parents, world);
  const float tolerance = pixelsToAngle(10.0f, v.height, 0.6f);
  auto pickAt = [&](const glm::vec2& pixel) { return pickJoint(pickRay(v, pixel), bones, tolerance); };
  // On the upper arm's middle → the shoulder turns it; a few pixels off the line still picks it.
  EXPECT_EQ(pickAt(project(v, {0.4f, 0, 0})), 1);
  EXPECT_EQ(pickAt(project(v, {0.4f, 0, 0}) + glm::vec2(0, 6)), 1);
  // On the forearm → the elbow.
  EXPECT_EQ(pickAt(project(v, {0.8f, 0, 0})), 2);
  // Exactly on the elbow, where the upper arm ends and the forearm starts → the elbow.
  EXPECT_EQ(pickAt(project(v, {0.6f, 0, 0})), 2);
  // Far from every bone → nothing.
  EXPECT_EQ(pickAt(project(v, {0.4f, 0.5f, 0})), -1);
  // Nearest wins: between two parallel bones, the nearer one.
  const std::vector<Bone> two = {Bone{7, {-1, 0.1f, 0}, {1, 0.1f, 0}}, Bone{8, {-1, -0.1f, 0}, {1, -0.1f, 0}}};
  EXPECT_EQ(pickJoint(pickRay(v, project(v, {0, 0.05f, 0})), two, 0.1f), 7);
  EXPECT_EQ(pickJoint(pickRay(v, project(v, {0, -0.06f, 0})), two, 0.1f), 8);
}

TEST(Manipulator, ArcballNearItsCentreIsATwoAxisTrackball) {
  const ScreenView v = frontView();
  const glm::vec2 c(320, 240);
  // A small drag right from the centre: about the screen's up axis, and the front (+z) moves right (+x).
  const glm::quat right = arcballRotation(c, 100.0f, c, c + glm::vec2(10, 0), v);
  expectNear(glm::axis(right), {0, 1, 0});
  EXPECT_NEAR(glm::angle(right), std::asin(0.1f), 1e-4f);
  EXPECT_GT((right * glm::vec3(0, 0, 1)).x, 0.0f);
  // A small drag down: about the screen's right axis, and the front moves down (-y).
  const glm::quat down = arcballRotation(c, 100.0f, c, c + glm::vec2(0, 10), v);
  expectNear(glm::axis(down), {1, 0, 0});
  EXPECT_LT((down * glm::vec3(0, 0, 1)).y, 0.0f);
  // Nothing moves for a zero drag or a zero radius.
  EXPECT_NEAR(glm::angle(arcballRotation(c, 100.0f, c + glm::vec2(5, 5), c + glm::vec2(5, 5), v)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::angle(arcballRotation(c, 0.0f, c, c + glm::vec2(5, 5), v)), 0.0f, 1e-6f);
}

TEST(Manipulator, ArcballTurnsAGrabbedLimbTowardsTheCursor) {
  const ScreenView v = screenView(Camera{{1.5f, 0.5f, 4}, {0, 0, 0}, {0, 1, 0}, 0.6f}, 1280, 720, 2.0f);
  const glm::vec3 joint(0, 0, 0), hand(-0.8f, 0, -0.2f);  // an arm pointing left and a little away
  const glm::vec2 c = project(v, joint), press = project(v, hand);
  // Drag the hand downwards on screen by 60 pixels.
  const glm::vec2 target = press + glm::vec2(0, 60);
  const glm::quat q = arcballRotation(c, arcballRadius(c, press, 20.0f), press, target, v);
  const glm::vec2 moved = project(v, joint + q * (hand - joint));
  // The hand's direction from the joint on screen now points at the cursor.
  const glm::vec2 want = glm::normalize(target - c), got = glm::normalize(moved - c);
  EXPECT_GT(glm::dot(want, got), 0.999f) << "hand at " << moved.x << "," << moved.y;
  EXPECT_GT(moved.y, press.y + 30.0f);  // and it went down, not up
}

TEST(Manipulator, ArcballRadius) {
  EXPECT_FLOAT_EQ(arcballRadius({0, 0}, {30, 40}, 20.0f), 50.0f);
  EXPECT_FLOAT_EQ(arcballRadius({0, 0}, {3, 4}, 20.0f), 20.0f);
}

TEST(Manipulator, TwistTurnsAboutTheViewAxis) {
  const ScreenView v = frontView();
  const glm::vec2 c(320, 240);
  // From right of the centre to above it: a quarter turn counter-clockwise on screen.
  const glm::quat q = twistRotation(c, c + glm::vec2(50, 0), c + glm::vec2(0, -50), v);
  expectNear(glm::axis(q), {0, 0, 1});
  EXPECT_NEAR(glm::angle(q), kPi / 2, 1e-5f);
  expectNear(q * glm::vec3(1, 0, 0), {0, 1, 0});
  // Across the ±180° seam the short way round: a small clockwise step, not almost a whole turn.
  const glm::quat seam = twistRotation(c, c + glm::vec2(-50, -1), c + glm::vec2(-50, 1), v);
  EXPECT_LT(glm::angle(seam), 0.1f);
}

TEST(Manipulator, WorldRotationBecomesLocalUnderATurnedParent) {
  const glm::quat parentWorld = glm::angleAxis(0.9f, glm::normalize(glm::vec3(1, 2, 0.5f)));
  const glm::quat local = glm::angleAxis(-0.4f, glm::normalize(glm::vec3(0, 1, 1)));
  const glm::quat worldRotation = glm::angleAxis(0.7f, glm::vec3(0, 0, 1));
  const glm::quat newLocal = rotateJointLocal(local, parentWorld, worldRotation);
  // The joint's world frame turned by worldRotation about its origin, the parent untouched.
  const glm::quat want = worldRotation * parentWorld * local, got = parentWorld * newLocal;
  EXPECT_NEAR(std::abs(glm::dot(want, got)), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::length(newLocal), 1.0f, 1e-6f);
}

// --- Handles ---

TEST(Manipulator, HandleLayoutHasAxesOfTheGivenScreenLength) {
  const ScreenView v = screenView(Camera{{1.5f, 0.5f, 4}, {0, 0, 0}, {0, 1, 0}, 0.6f}, 1280, 720, 2.0f);
  HandleLayout layout;
  ASSERT_TRUE(handleLayout(v, {0.2f, 0.1f, 0}, glm::quat(1, 0, 0, 0), 70.0f, &layout));
  EXPECT_LT(glm::length(layout.center - project(v, {0.2f, 0.1f, 0})), 1e-3f);
  // An axis lying in the screen plane (the screen's right axis as the handle's x) is 70 pixels long.
  const glm::quat toRight(glm::vec3(1, 0, 0), v.right);
  ASSERT_TRUE(handleLayout(v, {0.2f, 0.1f, 0}, toRight, 70.0f, &layout));
  EXPECT_NEAR(glm::length(layout.tips[0] - layout.center), 70.0f, 0.5f);
  // Seen from the front, the z axis points at the viewer and collapses to the centre.
  ASSERT_TRUE(handleLayout(frontView(), {0, 0, 0}, glm::quat(1, 0, 0, 0), 70.0f, &layout));
  EXPECT_NEAR(glm::length(layout.tips[0] - layout.center), 70.0f, 0.5f);
  EXPECT_NEAR(layout.tips[1].y, layout.center.y - 70.0f, 0.5f);  // y up on screen
  EXPECT_LT(glm::length(layout.tips[2] - layout.center), 1.0f);
  EXPECT_FALSE(handleLayout(frontView(), {0, 0, 6}, glm::quat(1, 0, 0, 0), 70.0f, &layout));  // behind the eye
}

TEST(Manipulator, PickHandlePart) {
  HandleLayout layout;
  ASSERT_TRUE(handleLayout(frontView(), {0, 0, 0}, glm::quat(1, 0, 0, 0), 70.0f, &layout));
  const glm::vec2 c = layout.center;
  float d = -1.0f;
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(3, -2), 10.0f, &d), HandlePart::Center);
  EXPECT_NEAR(d, std::sqrt(13.0f), 1e-4f);
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(60, 4), 10.0f, &d), HandlePart::AxisX);
  EXPECT_NEAR(d, 4.0f, 1e-3f);
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(-3, -50), 10.0f, nullptr), HandlePart::AxisY);
  // Beyond the tip, beside the axes, and the z axis that points at the viewer: nothing.
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(90, 0), 10.0f, nullptr), HandlePart::None);
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(40, 40), 10.0f, nullptr), HandlePart::None);
  EXPECT_EQ(pickHandlePart(layout, c + glm::vec2(-40, 0), 10.0f, nullptr), HandlePart::None);
}

TEST(Manipulator, PlaneDragKeepsThePointUnderTheCursor) {
  const ScreenView v = screenView(Camera{{1.5f, 0.5f, 4}, {0, 0.3f, 0}, {0, 1, 0}, 0.6f}, 1280, 720, 2.0f);
  const glm::vec3 origin(-0.4f, 0.6f, 0.3f);
  const glm::vec2 from = project(v, origin), to = from + glm::vec2(55.0f, -31.0f);
  const glm::vec3 d = planeDrag(v, origin, from, to);
  EXPECT_LT(glm::length(project(v, origin + d) - to), 0.01f);
  EXPECT_NEAR(glm::dot(d, v.towardsViewer), 0.0f, 1e-5f);  // in the screen plane: the depth does not change
  expectNear(planeDrag(v, origin, from, from), glm::vec3(0.0f));
}

TEST(Manipulator, AxisDragFollowsTheCursorAlongTheAxis) {
  const ScreenView v = frontView();
  const glm::vec3 origin(0.3f, -0.2f, 0.0f);
  const glm::vec2 from = project(v, origin);
  // Along x, seen from the front: the point under the cursor follows it.
  const float s = axisDrag(v, origin, {1, 0, 0}, from, from + glm::vec2(40.0f, 0.0f));
  EXPECT_GT(s, 0.0f);
  EXPECT_NEAR(project(v, origin + glm::vec3(s, 0, 0)).x, from.x + 40.0f, 0.01f);
  // Dragging up moves along +y.
  EXPECT_GT(axisDrag(v, origin, {0, 1, 0}, from, from + glm::vec2(0.0f, -30.0f)), 0.0f);
  // On the line of sight: a drag across the x axis does not move along it, and the z axis, pointing at the
  // viewer, cannot be dragged.
  const glm::vec2 centre = project(v, {0, 0, 0});
  EXPECT_NEAR(axisDrag(v, {0, 0, 0}, {1, 0, 0}, centre, centre + glm::vec2(0.0f, 30.0f)), 0.0f, 1e-5f);
  EXPECT_EQ(axisDrag(v, {0, 0, 0}, {0, 0, 1}, centre, centre + glm::vec2(30.0f, 10.0f)), 0.0f);
}

TEST(Manipulator, ScaleFactorIsTheRatioOfDistancesFromTheCentre) {
  const glm::vec2 c(100, 100);
  EXPECT_FLOAT_EQ(scaleFactor(c, {170, 100}, {240, 100}, 70.0f), 2.0f);
  EXPECT_FLOAT_EQ(scaleFactor(c, {180, 100}, {100, 140}, 70.0f), 0.5f);
  EXPECT_FLOAT_EQ(scaleFactor(c, {180, 100}, {180, 100}, 70.0f), 1.0f);
  // A press near the centre: no jump at the press, double 70 pixels further out.
  EXPECT_FLOAT_EQ(scaleFactor(c, {102, 100}, {102, 100}, 70.0f), 1.0f);
  EXPECT_FLOAT_EQ(scaleFactor(c, {102, 100}, {172, 100}, 70.0f), 2.0f);
  EXPECT_FLOAT_EQ(scaleFactor(c, {170, 100}, {100, 100}, 70.0f), 0.01f);  // clamped
}

}  // namespace
}  // namespace imps::app
