// SPDX-License-Identifier: MIT
// The live app's frame pipeline without a window (the mesh version and the posed scene are also exercised in
// viewer_replay_test.cpp): meshHash tells meshes apart by every array, the rest bounds hold the surface and move with
// the placement, a document that does not compile changes nothing, a new document keeps the pose, and a reset
// settles the particles again.
#include "viewer_pipeline.h"

#include <gtest/gtest.h>

#include <string>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/scene_reader.h"

namespace imps::app {
namespace {

std::unique_ptr<ViewerPipeline> load(const std::string& example, Polygonizer polygonizer) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/" + example);
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  PipelineOptions o;
  o.polygonizer = polygonizer;
  o.mcResolution = 32;
  o.settleUpdates = 60;
  return std::make_unique<ViewerPipeline>(std::move(*scene), std::move(*character), o);
}

Mesh triangle() {
  Mesh m;
  m.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  m.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  m.colors = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.indices = {0, 1, 2};
  return m;
}

TEST(ViewerPipeline, MeshHashTellsMeshesApartByEveryArray) {
  const Mesh a = triangle();
  EXPECT_EQ(meshHash(a), meshHash(triangle()));
  // FNV-1a 64 of no bytes is its offset basis.
  EXPECT_EQ(meshHash(Mesh{}), 14695981039346656037ull);
  Mesh moved = a;
  moved.positions[4] = 0.5f;
  Mesh turned = a;
  turned.normals[2] = -1.0f;
  Mesh recoloured = a;
  recoloured.colors[0] = 0.5f;
  Mesh flipped = a;
  flipped.indices = {0, 2, 1};
  Mesh bare = a;
  bare.colors.clear();
  for (const Mesh* m : {&moved, &turned, &recoloured, &flipped, &bare}) EXPECT_NE(meshHash(*m), meshHash(a));
  // -0 and +0 are different bytes: the hash is of the stored bytes, not of the values.
  Mesh negativeZero = a;
  negativeZero.positions[0] = -0.0f;
  EXPECT_NE(meshHash(negativeZero), meshHash(a));
}

TEST(ViewerPipeline, RestBoundsHoldTheSurfaceAndMoveWithThePlacement) {
  auto p = load("simple_biped.wrl", Polygonizer::MarchingCubes);
  const MeshBounds rest = p->restBounds();
  ASSERT_FALSE(rest.empty());
  p->frame();
  const MeshBounds surface = bounds(p->mesh());
  ASSERT_FALSE(surface.empty());
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(rest.min[k], surface.min[k] + 1e-4f) << k;
    EXPECT_GE(rest.max[k], surface.max[k] - 1e-4f) << k;
  }
  // Posing does not move them (the camera frames the rest pose).
  p->skeleton().setRotation(p->character().findJoint("L_UpperArm"), glm::angleAxis(-1.2f, glm::vec3(0, 0, 1)));
  p->skeleton().update();
  p->frame();
  EXPECT_EQ(p->restBounds().min, rest.min);
  EXPECT_EQ(p->restBounds().max, rest.max);
  // A placement 3 m along x (made before the first frame, as a world does) moves them by 3 m.
  p = load("simple_biped.wrl", Polygonizer::MarchingCubes);
  p->setPlacement(Rigid{glm::quat(1, 0, 0, 0), glm::vec3(3, 0, 0)});
  EXPECT_NEAR(p->restBounds().min.x, rest.min.x + 3.0f, 1e-3f);
  EXPECT_NEAR(p->restBounds().max.x, rest.max.x + 3.0f, 1e-3f);
  EXPECT_NEAR(p->restBounds().min.y, rest.min.y, 1e-3f);
}

TEST(ViewerPipeline, ADocumentThatDoesNotCompileChangesNothing) {
  auto p = load("simple_biped.wrl", Polygonizer::MarchingCubes);
  p->frame();
  const uint64_t version = p->meshVersion();
  const uint64_t hash = meshHash(p->mesh());
  const size_t joints = p->character().joints().size();
  const auto diagnostics = p->setState(DocumentState{Scene{}, {}});
  ASSERT_TRUE(diagnostics.has_value());
  EXPECT_NE(diagnostics->str().find("error"), std::string::npos);
  EXPECT_EQ(p->character().joints().size(), joints);
  p->frame();
  EXPECT_EQ(p->meshVersion(), version) << "Marching Cubes still holds the old, valid mesh";
  EXPECT_EQ(meshHash(p->mesh()), hash);
}

TEST(ViewerPipeline, ANewDocumentKeepsThePoseItIsGiven) {
  auto p = load("simple_biped.wrl", Polygonizer::MarchingCubes);
  p->frame();
  const int arm = p->character().findJoint("L_UpperArm");
  DocumentState state = p->state();
  const glm::quat bent = glm::angleAxis(-1.0f, glm::vec3(0, 0, 1));
  state.pose[size_t(arm)].rotation = bent;
  const uint64_t version = p->meshVersion();
  ASSERT_FALSE(p->setState(state).has_value());
  EXPECT_LT(glm::length(glm::vec4(p->skeleton().local(arm).rotation.x, p->skeleton().local(arm).rotation.y,
                                  p->skeleton().local(arm).rotation.z, p->skeleton().local(arm).rotation.w) -
                        glm::vec4(bent.x, bent.y, bent.z, bent.w)),
            1e-6f);
  EXPECT_EQ(p->pose().size(), p->character().joints().size());
  // Marching Cubes runs again for the new document even though the skeleton's generation may match.
  p->frame();
  EXPECT_GT(p->meshVersion(), version);
}

TEST(ViewerPipeline, ParticlesSettleOnTheFirstFrameAndAfterAReset) {
  auto p = load("simple_biped.wrl", Polygonizer::Particles);
  EXPECT_EQ(p->polygonizer(), Polygonizer::Particles);
  p->frame();
  const size_t settled = p->tesselator().particles().positions.size();
  EXPECT_GT(settled, 100u);
  EXPECT_GT(p->mesh().triangleCount(), 0u);
  p->resetPolygonizer();
  p->frame();
  EXPECT_GT(p->tesselator().particles().positions.size(), settled / 2) << "the reset settles again, not a few seeds";
  EXPECT_GT(p->mesh().triangleCount(), 0u);
  EXPECT_GE(p->lastFrameMs(), 0.0);
}

}  // namespace
}  // namespace imps::app
