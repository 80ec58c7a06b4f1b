// SPDX-License-Identifier: MIT
// Skeleton cache: zeroth-order joint control, world-space primitives and differential transforms (thesis 3.7).
#include "imps/skeleton_cache.h"

#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "imps/scene_reader.h"

namespace imps {
namespace {

const char* kArm = R"(#VRML V2.0 utf8
DEF SHOULDER RigidTransform { children [
  DEF UPPER LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.2 radius2 0.2 }
  DEF ELBOW RigidTransform { translation 1 0 0 children [
    DEF FORE LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.15 radius2 0.15 }
  ] }
] }
)";

Character arm() {
  auto scene = readScene(kArm, "arm.wrl");
  EXPECT_TRUE(scene.has_value());
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value());
  return std::move(*c);
}

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-5f) {
  EXPECT_NEAR(glm::length(a - b), 0.0f, tolerance)
      << a.x << " " << a.y << " " << a.z << " vs " << b.x << " " << b.y << " " << b.z;
}

TEST(SkeletonCache, RestPoseMatchesTheFile) {
  const Character c = arm();
  SkeletonCache cache(c);
  expectNear(cache.field().primitive(1).p1, {1, 0, 0});
  expectNear(cache.field().primitive(1).p2, {2, 0, 0});
  expectNear(cache.differential(0).apply({3, 4, 5}), {3, 4, 5});
}

TEST(SkeletonCache, AbsoluteRotationsPoseTheChildren) {
  const Character c = arm();
  SkeletonCache cache(c);
  const glm::quat quarter = glm::angleAxis(glm::half_pi<float>(), glm::vec3(0, 0, 1));
  ASSERT_TRUE(cache.setRotation("SHOULDER", quarter));
  ASSERT_TRUE(cache.setRotation("ELBOW", quarter));
  EXPECT_FALSE(cache.setRotation("WRIST", quarter));
  cache.update();
  expectNear(cache.field().primitive(0).p2, {0, 1, 0});
  expectNear(cache.field().primitive(1).p1, {0, 1, 0});
  expectNear(cache.field().primitive(1).p2, {-1, 1, 0});
  // Zeroth order: setting the same absolute pose again changes nothing.
  cache.setRotation("SHOULDER", quarter);
  cache.setRotation("ELBOW", quarter);
  cache.update();
  expectNear(cache.field().primitive(1).p2, {-1, 1, 0});
  expectNear(cache.differential(1).apply({7, 8, 9}), {7, 8, 9});
}

// A particle on the forearm's surface before the update, moved by its primitive's differential transform, is on
// the forearm's surface after it, at the same place relative to the forearm.
TEST(SkeletonCache, DifferentialTransformsCarryParticlesWithTheirPrimitives) {
  const Character c = arm();
  SkeletonCache cache(c);
  const glm::vec3 particle(1.5f, 0.15f, 0.0f);  // on the forearm's surface (radius 0.15)
  EXPECT_NEAR(cache.field().primitive(1).distance(particle), 1.0f, 1e-5f);
  cache.setRotation("SHOULDER", glm::angleAxis(0.3f, glm::vec3(0, 1, 0)));
  cache.setRotation("ELBOW", glm::angleAxis(-0.7f, glm::vec3(0, 0, 1)));
  cache.setTranslation("ELBOW", {1.1f, 0, 0});
  cache.update();
  const glm::vec3 moved = cache.primitiveDifferential(1).apply(particle);
  EXPECT_NEAR(cache.field().primitive(1).distance(moved), 1.0f, 1e-4f);
  // Relative to the forearm's end points it sits where it did.
  const Primitive& fore = cache.field().primitive(1);
  EXPECT_NEAR(glm::dot(moved - fore.p1, fore.axis), 0.5f, 1e-5f);
  EXPECT_GT(glm::length(moved - particle), 0.1f) << "the particle did move";
  cache.resetPose();
  cache.update();
  expectNear(cache.primitiveDifferential(1).apply(moved), particle, 1e-4f);
}

// A placement (a world's Transform above the character) moves every world transform and primitive rigidly, joint-less
// ones too, and the differentials carry particles along when it changes.
TEST(SkeletonCache, APlacementMovesTheWholeCharacter) {
  const Character c = arm();
  SkeletonCache home(c), placed(c);
  Rigid where;
  where.rotation = glm::angleAxis(0.8f, glm::normalize(glm::vec3(0, 1, 0.2f)));
  where.translation = {3.0f, -1.0f, 2.0f};
  const glm::vec3 particle(1.5f, 0.15f, 0.0f);
  placed.setPlacement(where);
  placed.update();
  for (size_t j = 0; j < c.joints().size(); ++j) {
    expectNear(placed.world(int(j)).translation, where.apply(home.world(int(j)).translation));
  }
  const glm::vec3 moved = placed.primitiveDifferential(1).apply(particle);
  expectNear(moved, where.apply(particle));
  EXPECT_NEAR(placed.field().primitive(1).distance(moved), 1.0f, 1e-4f);
  const Box a = home.field().surfaceBounds(), b = placed.field().surfaceBounds();
  EXPECT_GT(glm::length(b.center() - a.center()), 1.0f) << "the surface moved with the placement";

  // A flat scene's joint-less primitive is placed too; without a placement it stays bit-identical.
  auto flat = readScene("#VRML V2.0 utf8\nMetaball { center 1 2 3 radius 0.5 }\n", "flat.wrl");
  ASSERT_TRUE(flat.has_value());
  auto ball = Character::fromScene(*flat);
  ASSERT_TRUE(ball.has_value());
  SkeletonCache still(*ball), moving(*ball);
  still.update();
  EXPECT_EQ(still.field().primitive(0).center, glm::vec3(1, 2, 3));
  moving.setPlacement(where);
  moving.update();
  expectNear(moving.field().primitive(0).center, where.apply(glm::vec3(1, 2, 3)), 1e-4f);
}

// Thesis 3.9: the generator is centred on its primitive and follows it through the skeleton cache, so a point fixed
// to the forearm keeps its texture coordinates however the arm is posed.
TEST(SkeletonCache, TexGensFollowTheirPrimitives) {
  auto scene = readScene(R"(#VRML V2.0 utf8
DEF SHOULDER RigidTransform { children [
  DEF UPPER LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.2 radius2 0.2 }
  DEF ELBOW RigidTransform { translation 1 0 0 children [
    DEF FORE LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.15 radius2 0.15
                       texGen TexGenSphere { translation 0 0.1 0 } texture ImageTexture { url "fore.png" } }
  ] }
] }
)", "/scenes/arm.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  auto c = Character::fromScene(*scene);
  ASSERT_TRUE(c.has_value()) << c.error().str();
  ASSERT_TRUE(c->textured());
  EXPECT_FALSE(c->primitives()[0].texGen);
  ASSERT_EQ(c->textures().size(), 1u);
  EXPECT_EQ(c->textures()[0].path, "/scenes/fore.png");  // relative to the scene file
  EXPECT_EQ(c->primitives()[1].texture, 0);
  SkeletonCache cache(*c);
  EXPECT_EQ(cache.texGen(0), nullptr);
  ASSERT_NE(cache.texGen(1), nullptr);
  expectNear(cache.texGen(1)->origin, {1.5f, 0.1f, 0});  // the forearm's midpoint, moved up by the translation
  const glm::vec3 point(1.7f, 0.15f, 0.05f);
  const glm::vec2 before = cache.texGen(1)->map(point);
  cache.setRotation("SHOULDER", glm::angleAxis(0.3f, glm::vec3(0, 1, 0)));
  cache.setRotation("ELBOW", glm::angleAxis(-1.2f, glm::vec3(0, 0, 1)));
  cache.update();
  const glm::vec3 moved = cache.primitiveDifferential(1).apply(point);
  const glm::vec2 after = cache.texGen(1)->map(moved);
  EXPECT_NEAR(after.x, before.x, 1e-5f);
  EXPECT_NEAR(after.y, before.y, 1e-5f);
  EXPECT_GT(glm::length(moved - point), 0.1f);
}

TEST(SkeletonCache, SetPoseReportsUnknownJoints) {
  const Character c = arm();
  SkeletonCache cache(c);
  const std::vector<JointPose> pose = {{"ELBOW", glm::angleAxis(1.0f, glm::vec3(0, 0, 1)), false, {}},
                                       {"KNEE", glm::quat(1, 0, 0, 0), false, {}}};
  EXPECT_EQ(cache.setPose(pose), 1);
  const uint64_t before = cache.generation();
  cache.update();
  EXPECT_EQ(cache.generation(), before + 1);
  EXPECT_GT(cache.field().primitive(1).p2.y, 0.5f);
}

}  // namespace
}  // namespace imps
