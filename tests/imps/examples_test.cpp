// SPDX-License-Identifier: MIT
// The bundled examples: each compiles, meshes closed and manifold at several resolutions, and the biped keeps the
// hierarchy's blending rule when posed.
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "examples.h"
#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"

namespace imps {
namespace {

const Character& loadExample(const std::string& name) { return test::exampleCharacter(name); }

class ExampleTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ExampleTest, MeshesClosedAndManifoldAtSeveralResolutions) {
  const Character& c = loadExample(GetParam());
  SkeletonCache cache(c);
  for (int res : {12, 24, 48, 96}) {
    MarchingCubesOptions o;
    o.resolution = res;
    const Mesh mesh = polygonize(cache.field(), o);
    const MeshTopology t = analyzeTopology(mesh);
    EXPECT_GT(mesh.triangleCount(), 0u) << res;
    EXPECT_TRUE(t.closedManifold()) << GetParam() << " at " << res << " cells: boundary " << t.boundaryEdges
                                    << " non-manifold edges " << t.nonManifoldEdges << " vertices "
                                    << t.nonManifoldVertices << " orientation " << t.orientationConflicts;
    EXPECT_GT(signedVolume(mesh), 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Examples, ExampleTest,
                         ::testing::Values("transformed_blobs", "textured_blobs", "beanito", "flubber", "simple_biped",
                                           "textured_biped"));

// The simple biped is one piece, and stays one piece (its thin hands and feet included) even at a coarse cell.
TEST(Examples, BipedIsOneConnectedSurfaceEvenAtCoarseCells) {
  const Character& c = loadExample("simple_biped");
  SkeletonCache cache(c);
  for (float cell : {0.1f, 0.05f, 0.025f}) {
    MarchingCubesOptions o;
    o.cellSize = cell;
    const Mesh mesh = polygonize(cache.field(), o);
    EXPECT_EQ(analyzeTopology(mesh).components, 1u) << cell;
    // Both hands are reached: the mesh spans the T-pose's arm span (about 1.7 m).
    float minX = 1e9f, maxX = -1e9f;
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
      minX = std::min(minX, mesh.position(v).x);
      maxX = std::max(maxX, mesh.position(v).x);
    }
    EXPECT_GT(maxX - minX, 1.6f) << cell;
  }
}

// Arms down, hands against the thighs: grandparent-grandchild pairs like hand and thigh never blend, so where a
// global blend would glue the hand to the hip (F_flat >= iso) the character's field leaves the two apart.
TEST(Examples, BipedHandsDoNotBlendIntoItsHips) {
  const Character& c = loadExample("simple_biped");
  SkeletonCache cache(c);
  const float down = glm::half_pi<float>();  // arms straight down: each hand touches its thigh
  cache.setRotation("L_UpperArm", glm::angleAxis(-down, glm::vec3(0, 0, 1)));
  cache.setRotation("R_UpperArm", glm::angleAxis(down, glm::vec3(0, 0, 1)));
  cache.update();
  const Field& field = cache.field();
  // The same posed primitives with everything blending with everything.
  std::vector<float> params;
  std::vector<glm::vec3> colors;
  for (size_t i = 0; i < field.size(); ++i) {
    params.push_back(field.param(i));
    colors.push_back(field.color(i));
  }
  const Field flat(field.primitives(), params, colors, field.blend(), BlendSets::all(field.size()));

  // Search a box around the left hand.
  size_t hand = 0;
  for (size_t i = 0; i < c.primitives().size(); ++i)
    if (c.primitives()[i].name == "L_Hand_SEG") hand = i;
  const glm::vec3 centre = 0.5f * (field.primitive(hand).p1 + field.primitive(hand).p2);
  int glued = 0, agreeing = 0;
  for (int k = -12; k <= 12; ++k)
    for (int j = -12; j <= 12; ++j)
      for (int i = -12; i <= 12; ++i) {
        const glm::vec3 x = centre + 0.01f * glm::vec3(i, j, k);
        const float hier = field.value(x), all = flat.value(x);
        EXPECT_LE(hier, all + 1e-6f) << "the rule only ever removes blending";
        if (all >= 1.0f && hier < 1.0f) ++glued;
        if ((all >= 1.0f) == (hier >= 1.0f)) ++agreeing;
      }
  EXPECT_GT(glued, 20) << "points a global blend would fill between hand and hip";
  EXPECT_GT(agreeing, glued) << "elsewhere the two fields agree on inside/outside";
}

}  // namespace
}  // namespace imps
