// SPDX-License-Identifier: MIT
// `--pose` arguments: degrees by default, radians on request, translations in metres, errors for everything else.
#include "pose_argument.h"

#include <gtest/gtest.h>

#include <numbers>

#include "examples.h"

namespace imps::app {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

TEST(PoseArgument, AnglesAreDegreesUnlessWrittenOtherwise) {
  auto p = parsePoseArgument("Head=0,1,0,90");
  ASSERT_TRUE(p.has_value()) << p.error().str();
  EXPECT_EQ(p->joint, "Head");
  EXPECT_FALSE(p->translation);
  EXPECT_NEAR(p->radians, kPi / 2, 1e-6f);
  EXPECT_NEAR(parsePoseArgument("Head=0,1,0,90deg")->radians, kPi / 2, 1e-6f);
  EXPECT_NEAR(parsePoseArgument("Head=0,1,0,1.5rad")->radians, 1.5f, 1e-6f);
  EXPECT_NEAR(parsePoseArgument("L_UpperArm=0,0,1,-69")->radians, -69 * kPi / 180, 1e-6f);
}

TEST(PoseArgument, ThreeNumbersMoveTheJointInMetres) {
  auto p = parsePoseArgument("Pelvis=0,0.25,-1");
  ASSERT_TRUE(p.has_value()) << p.error().str();
  EXPECT_TRUE(p->translation);
  EXPECT_EQ(p->offset, glm::vec3(0, 0.25f, -1));
}

TEST(PoseArgument, BadArgumentsAreRefused) {
  for (const char* bad : {"Head", "=0,1,0,90", "Head=0,0,0,90", "Head=0,1,0", "Head=0,1,0,90,1", "Head=0,1,x,90",
                          "Head=0,1,0,90grad", "Head=0,1,0,", "Head=0,1,0,nan", "Head=1,2"}) {
    const auto p = parsePoseArgument(bad);
    if (std::string(bad) == "Head=0,1,0") continue;  // three numbers: a translation, valid
    EXPECT_FALSE(p.has_value()) << bad;
    if (!p) {
      EXPECT_NE(p.error().str().find("JOINT=AX,AY,AZ,ANGLE"), std::string::npos);
    }
  }
}

// On the biped: a translation moves the joint (and its children) from the rest translation; a rotation turns it.
TEST(PoseArgument, AppliesToTheSkeleton) {
  const Character& biped = test::exampleCharacter("simple_biped");
  SkeletonCache skeleton(biped);
  const int pelvis = biped.findJoint("Pelvis"), head = biped.findJoint("Head");
  const glm::vec3 headBefore = skeleton.world(head).translation;
  applyPoseArgument(*parsePoseArgument("Pelvis=0,0.3,0"), pelvis, skeleton);
  skeleton.update();
  EXPECT_NEAR(glm::length(skeleton.world(head).translation - (headBefore + glm::vec3(0, 0.3f, 0))), 0, 1e-5f);
  const int arm = biped.findJoint("L_UpperArm"), fore = biped.findJoint("L_Forearm");
  applyPoseArgument(*parsePoseArgument("L_UpperArm=0,0,1,-90"), arm, skeleton);
  skeleton.update();
  const glm::vec3 bone = skeleton.world(fore).translation - skeleton.world(arm).translation;
  EXPECT_NEAR(glm::normalize(bone).y, -1.0f, 1e-4f) << "the T-pose arm, turned -90 degrees about z, hangs down";
}

}  // namespace
}  // namespace imps::app
