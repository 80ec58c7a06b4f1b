// SPDX-License-Identifier: MIT
// The skinned, animated glTF export (puppeteer/src/export_gltf.cpp): skin weights are at most four per vertex,
// positive, normalised and heaviest first; a vertex on one limb is skinned to that limb's joint; the file written is
// the bytes encoded, read back by an independent glTF reader; a directory that does not exist is an error.
// (The weights' agreement with the implicit surface is in export_take_test.cpp, Export.SkinnedGlb….)
#include "export_gltf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "examples.h"
#include "imps/marching_cubes.h"
#include "imps/skeleton_cache.h"
#include "mesh_readers.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

// The rest pose, `frames` times.
Take restTake(const Character& c, size_t frames) {
  Take take;
  take.frameTime = 0.1;
  std::vector<Rigid> rest;
  for (const Joint& j : c.joints()) rest.push_back(j.rest);
  take.locals.assign(frames, rest);
  return take;
}

Mesh restMesh(const Character& c, float cell) {
  const SkeletonCache cache(c);
  MarchingCubesOptions o;
  o.cellSize = cell;
  return polygonize(cache.field(), o);
}

TEST(SkinWeights, AreAtMostFourPositiveNormalisedHeaviestFirst) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const Mesh mesh = restMesh(biped, 0.05f);
  ASSERT_GT(mesh.vertexCount(), 100u);
  const SkinWeights w = skinWeights(biped, mesh);
  ASSERT_EQ(w.joints.size(), mesh.vertexCount());
  ASSERT_EQ(w.weights.size(), mesh.vertexCount());
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    float sum = 0;
    for (size_t k = 0; k < 4; ++k) {
      EXPECT_LT(w.joints[v][k], biped.joints().size()) << v;
      EXPECT_GE(w.weights[v][k], 0.0f) << v;
      if (k > 0) {
        EXPECT_GE(w.weights[v][k - 1], w.weights[v][k]) << v;
      }
      if (w.weights[v][k] == 0.0f) {
        EXPECT_EQ(w.joints[v][k], 0) << v << ": unused slots are (0, 0)";
      }
      sum += w.weights[v][k];
    }
    EXPECT_GT(w.weights[v][0], 0.0f) << v;
    EXPECT_NEAR(sum, 1.0f, 1e-5f) << v;
  }
}

// The vertex furthest down the left forearm's hand is skinned mostly to the hand or forearm, not to the other side.
TEST(SkinWeights, AVertexOnALimbFollowsThatLimb) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const Mesh mesh = restMesh(biped, 0.04f);
  const SkinWeights w = skinWeights(biped, mesh);
  const SkeletonCache cache(biped);
  const glm::vec3 hand = cache.world(biped.findJoint("L_Hand")).translation;
  size_t nearest = 0;
  for (size_t v = 1; v < mesh.vertexCount(); ++v)
    if (glm::distance(mesh.position(v), hand) < glm::distance(mesh.position(nearest), hand)) nearest = v;
  const std::string heaviest = biped.joints()[w.joints[nearest][0]].name;
  EXPECT_TRUE(heaviest == "L_Hand" || heaviest == "L_Forearm") << heaviest;
}

TEST(SkinnedGlb, TheFileIsTheEncodedBytesAndReadsBack) {
  const ScratchDir dir("imps_export_gltf");
  const Character& biped = test::exampleCharacter("simple_biped");
  const Take take = restTake(biped, 3);
  GltfExportOptions options;
  options.cellSize = 0.06f;
  const auto bytes = encodeSkinnedGlb(biped, take, options);
  ASSERT_TRUE(bytes) << bytes.error().str();
  ASSERT_FALSE(bytes->empty());
  const std::string path = (dir / "rest.glb").string();
  const auto written = writeSkinnedGlb(biped, take, options, path);
  ASSERT_TRUE(written) << written.error().str();
  EXPECT_EQ(fileBytes(path), std::string(bytes->begin(), bytes->end())) << "deterministic, and written as encoded";
  std::string error;
  tinygltf::Model model;
  std::string warning;
  ASSERT_TRUE(test::loadGlbModel(path, &model, &error, &warning)) << error;
  ASSERT_EQ(model.skins.size(), 1u);
  EXPECT_EQ(model.skins[0].joints.size(), biped.joints().size());
  ASSERT_EQ(model.animations.size(), 1u);
  EXPECT_EQ(model.accessors[size_t(model.animations[0].samplers[0].input)].count, take.frames());
  Mesh mesh;
  ASSERT_TRUE(test::readGlb(path, &mesh, &error)) << error;
  EXPECT_EQ(mesh.triangleCount(), restMesh(biped, 0.06f).triangleCount());
}

TEST(SkinnedGlb, AMissingDirectoryIsAnErrorAndWritesNothing) {
  const ScratchDir dir("imps_export_gltf");
  const Character& biped = test::exampleCharacter("simple_biped");
  GltfExportOptions options;
  options.cellSize = 0.08f;
  const auto written = writeSkinnedGlb(biped, restTake(biped, 1), options, (dir / "nodir/x.glb").string());
  EXPECT_FALSE(written);
  EXPECT_FALSE(fs::exists(dir / "nodir"));
}

}  // namespace
}  // namespace imps::app
