// SPDX-License-Identifier: MIT
// Tests of the live app's pose sources and frame pipeline without a window: channels mapped to joints by name,
// and a stepped replay giving the same mesh sequence every run.
#include "viewer_replay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "viewer_pipeline.h"

namespace imps::app {
namespace {

const char* const kClip = R"(HIERARCHY
ROOT Pelvis
{
  OFFSET 0 0 0
  CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT L_UpperArm
  {
    OFFSET 1 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 1 0 0
    }
  }
  JOINT NoSuchJoint
  {
    OFFSET -1 0 0
    CHANNELS 1 Zrotation
    End Site
    {
      OFFSET -1 0 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.1
0 0 0  -60 0 0  10
0 0 0  -30 20 0  10
0 0 0  0 0 0  10
)";

struct Biped {
  Scene scene;
  Character character;
};

Biped loadBiped() {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  return {std::move(*scene), std::move(*character)};
}

sim::Session clipSession() {
  auto clip = sim::readBvhText(kClip, "wave.bvh");
  EXPECT_TRUE(clip.has_value()) << clip.error().str();
  auto session = sim::bvhToSession(*clip, "wave.bvh");
  EXPECT_TRUE(session.has_value()) << session.error().str();
  return std::move(*session);
}

float angleBetween(const glm::quat& a, const glm::quat& b) {
  return 2.0f * std::acos(std::min(1.0f, std::abs(glm::dot(glm::normalize(a), glm::normalize(b)))));
}

TEST(ChannelPoseMap, MapsBvhChannelsToJointsOfTheSameName) {
  Biped b = loadBiped();
  const sim::Session session = clipSession();
  ChannelPoseMap map(session, b.character);
  EXPECT_EQ(map.mappedJoints(), 2u);   // Pelvis and L_UpperArm
  EXPECT_EQ(map.mappedChannels(), 6u);
  ASSERT_EQ(map.unmatched().size(), 1u);
  EXPECT_EQ(map.unmatched()[0], "NoSuchJoint:Zrotation");

  SkeletonCache skeleton(b.character);
  const int arm = b.character.findJoint("L_UpperArm");
  const glm::quat rest = b.character.joints()[size_t(arm)].rest.rotation;
  map.apply(0, session.samples[0], skeleton);
  // -60 degrees about the joint's z axis, on top of its rest rotation (within the 16-bit encoder's resolution).
  EXPECT_LT(angleBetween(skeleton.local(arm).rotation, rest * glm::angleAxis(glm::radians(-60.0f), glm::vec3(0, 0, 1))),
            1e-3f);
  map.apply(0, session.samples[1], skeleton);
  const glm::quat expected = rest * glm::angleAxis(glm::radians(-30.0f), glm::vec3(0, 0, 1)) *
                             glm::angleAxis(glm::radians(20.0f), glm::vec3(1, 0, 0));
  EXPECT_LT(angleBetween(skeleton.local(arm).rotation, expected), 1e-3f);

  // A reading not flagged valid keeps the channel's previous angle.
  drivers::Sample s = session.samples[2];
  s.flags[3] = drivers::ChannelFlag::NotConnected;  // L_UpperArm:Zrotation
  map.apply(0, s, skeleton);
  EXPECT_LT(angleBetween(skeleton.local(arm).rotation, rest * glm::angleAxis(glm::radians(-30.0f), glm::vec3(0, 0, 1))),
            1e-3f);
}

TEST(ViewerPipeline, SteppedReplayGivesTheSameMeshesEveryRun) {
  const sim::Session session = clipSession();
  auto run = [&] {
    Biped b = loadBiped();
    PipelineOptions o;
    o.threads = 2;
    o.settleUpdates = 60;  // a short settle keeps the test fast; determinism does not need a settled surface
    ViewerPipeline pipeline(std::move(b.scene), std::move(b.character), o);
    SteppedReplayPoseSource source(session, SampleMapper(session, pipeline.character()), "wave");
    std::vector<uint64_t> hashes;
    for (int f = 0; f < 6; ++f) {
      int64_t arrival = -1;
      EXPECT_TRUE(source.poll(pipeline.skeleton(), &arrival));
      EXPECT_EQ(arrival, 0);
      pipeline.skeleton().update();
      pipeline.frame();
      EXPECT_GT(pipeline.mesh().triangleCount(), 100u);
      hashes.push_back(meshHash(pipeline.mesh()));
    }
    return hashes;
  };
  const std::vector<uint64_t> first = run(), second = run();
  EXPECT_EQ(first, second);
  EXPECT_NE(first[1], first[2]);  // the pose changes between frames, so do the meshes
}

TEST(ViewerPipeline, MeshVersionChangesOnlyWithANewMesh) {
  Biped b = loadBiped();
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;
  o.mcResolution = 24;
  ViewerPipeline pipeline(std::move(b.scene), std::move(b.character), o);
  pipeline.frame();
  const uint64_t first = pipeline.meshVersion();
  const uint64_t hash = meshHash(pipeline.mesh());
  // Marching Cubes: an unchanged pose is not polygonized (nor re-uploaded) again.
  pipeline.frame();
  EXPECT_EQ(pipeline.meshVersion(), first);
  EXPECT_EQ(meshHash(pipeline.mesh()), hash);
  const int arm = pipeline.character().findJoint("L_UpperArm");
  pipeline.skeleton().setRotation(arm, glm::angleAxis(-1.2f, glm::vec3(0, 0, 1)));
  pipeline.skeleton().update();
  pipeline.frame();
  EXPECT_GT(pipeline.meshVersion(), first);
  EXPECT_NE(meshHash(pipeline.mesh()), hash);
  // The particle tesselator moves its particles every frame: every frame is a new mesh.
  pipeline.setPolygonizer(Polygonizer::Particles);
  const uint64_t beforeParticles = pipeline.meshVersion();
  pipeline.frame();
  pipeline.frame();
  EXPECT_EQ(pipeline.meshVersion(), beforeParticles + 2);
  // Back to Marching Cubes: polygonized again even though the pose did not change.
  pipeline.setPolygonizer(Polygonizer::MarchingCubes);
  pipeline.frame();
  EXPECT_EQ(pipeline.meshVersion(), beforeParticles + 3);
}

TEST(ViewerPipeline, PosedSceneWritesJointRotations) {
  Biped b = loadBiped();
  ViewerPipeline pipeline(std::move(b.scene), std::move(b.character), PipelineOptions{});
  const int arm = pipeline.character().findJoint("L_UpperArm");
  const glm::quat q = glm::angleAxis(-1.2f, glm::vec3(0, 0, 1));
  pipeline.skeleton().setRotation(arm, q);
  const Scene posed = pipeline.posedScene();
  auto character = Character::fromScene(posed);
  ASSERT_TRUE(character.has_value());
  EXPECT_LT(angleBetween(character->joints()[size_t(arm)].rest.rotation, q), 1e-5f);
}

}  // namespace
}  // namespace imps::app
