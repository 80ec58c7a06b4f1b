// SPDX-License-Identifier: MIT
// Texture layers (imps/texturing.h): ownership, normalised blend weights without a hard seam, untextured shares,
// and both polygonizers.
#include "imps/texturing.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/tesselator.h"

namespace imps {
namespace {

// Figure 3-4's two metaballs; `left` and `right` are the fields each primitive's node gets besides its geometry.
Character blobs(const std::string& left, const std::string& right) {
  auto scene = readScene("#VRML V2.0 utf8\nMarchingCubes { sceneGraph ExponentialBlend { children [\n"
                         "  DEF LEFT Metaball { center -0.9 0 0 radius 1.0 " + left + " }\n"
                         "  DEF RIGHT Metaball { center 0.9 0 0 radius 0.8 " + right + " }\n"
                         "] } }\n", "/s/blobs.wrl");
  EXPECT_TRUE(scene.has_value()) << scene.error().str();
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value()) << c.error().str();
  return std::move(*c);
}

Mesh marched(const SkeletonCache& cache, int threads = 0) {
  MarchingCubesOptions o;
  o.cellSize = 0.08f;
  o.threads = threads;
  Mesh mesh = polygonize(cache.field(), o);
  textureMesh(mesh, cache, threads);
  return mesh;
}

// The weight layer l has at vertex v (0 when neither slot names it).
float weightOf(const Mesh& mesh, size_t v, int32_t l) {
  float w = 0.0f;
  for (int k = 0; k < 2; ++k)
    if (mesh.layers[2 * v + k] == l) w += mesh.layerWeights[2 * v + k];
  return w;
}

// The invariants of mesh.h's texture layers.
void expectLayerInvariants(const Mesh& mesh) {
  ASSERT_EQ(mesh.layers.size(), 2 * mesh.vertexCount());
  ASSERT_EQ(mesh.layerWeights.size(), 2 * mesh.vertexCount());
  ASSERT_EQ(mesh.texcoords.size(), 2 * mesh.vertexCount());
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const float sum = mesh.layerWeights[2 * v] + mesh.layerWeights[2 * v + 1];
    EXPECT_LE(sum, 1.0f + 1e-5f);
    for (int k = 0; k < 2; ++k) {
      EXPECT_GE(mesh.layerWeights[2 * v + k], 0.0f);
      EXPECT_LT(mesh.layers[2 * v + k], int32_t(mesh.layerGens.size()));
      if (mesh.layers[2 * v + k] < 0) {
        EXPECT_EQ(mesh.layerWeights[2 * v + k], 0.0f);
      }
    }
    if (mesh.layers[2 * v] >= 0) {
      const glm::vec2 uv = mesh.layerGens[size_t(mesh.layers[2 * v])].map(mesh.position(v));
      EXPECT_EQ(mesh.texcoords[2 * v], uv.x);
      EXPECT_EQ(mesh.texcoords[2 * v + 1], uv.y);
    }
  }
}

TEST(TextureMesh, OwnersTakeTheirOwnCoordinatesAndTheNeckBlendsWithoutASeam) {
  const Character c = blobs("texGen TexGenSphere { } texture ImageTexture { url \"a.png\" }",
                            "texGen TexGenPlane { } texture ImageTexture { url \"b.png\" }");
  SkeletonCache cache(c);
  const Mesh mesh = marched(cache);
  ASSERT_TRUE(mesh.textured());
  ASSERT_EQ(mesh.layerGens.size(), 2u);
  EXPECT_EQ(mesh.layerImages, (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(mesh.layerGens[0].type, TexGenType::Sphere);
  EXPECT_EQ(mesh.layerGens[0].origin, glm::vec3(-0.9f, 0, 0));  // centred on its metaball
  EXPECT_EQ(mesh.layerGens[1].type, TexGenType::Plane);
  expectLayerInvariants(mesh);
  size_t farLeft = 0, farRight = 0, neck = 0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = mesh.position(v);
    const float left = weightOf(mesh, v, 0), right = weightOf(mesh, v, 1);
    EXPECT_NEAR(left + right, 1.0f, 1e-5f) << "both primitives are textured: the whole vertex is textured";
    if (p.x < -1.4f) {
      ++farLeft;
      EXPECT_GT(left, 0.99f);
      EXPECT_EQ(mesh.layers[2 * v], 0);
      const glm::vec2 uv = mesh.layerGens[0].map(p);  // the closest point on the sphere generator's
      EXPECT_EQ(mesh.texcoords[2 * v], uv.x);
    }
    if (p.x > 1.45f) {  // the exponential blend reaches far: a little of LEFT is still felt at x = 1.2
      ++farRight;
      EXPECT_GT(right, 0.99f);
      EXPECT_EQ(mesh.layers[2 * v], 1);
    }
    if (std::abs(p.x) < 0.05f) {
      ++neck;
      EXPECT_GT(std::min(left, right), 0.2f) << "the neck mixes both textures, it is not cut between them";
    }
  }
  EXPECT_GT(farLeft, 10u);
  EXPECT_GT(farRight, 10u);
  EXPECT_GT(neck, 5u);
  // No seam: along every edge the weight of a layer changes by little (a Voronoi cut would jump from 0 to 1).
  float worstJump = 0.0f;
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = mesh.indices[3 * t + e], b = mesh.indices[3 * t + (e + 1) % 3];
      worstJump = std::max(worstJump, std::abs(weightOf(mesh, a, 0) - weightOf(mesh, b, 0)));
    }
  EXPECT_LT(worstJump, 0.25f);
}

TEST(TextureMesh, UntexturedPrimitivesKeepTheirShareAsPlainColour) {
  // LEFT has only a generator (coordinates, no image); RIGHT has nothing.
  const Character c = blobs("texGen TexGenSphere { }", "");
  SkeletonCache cache(c);
  const Mesh mesh = marched(cache);
  ASSERT_TRUE(mesh.textured());
  EXPECT_EQ(mesh.layerImages, (std::vector<int32_t>{-1}));
  expectLayerInvariants(mesh);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = mesh.position(v);
    EXPECT_EQ(mesh.layers[2 * v + 1], -1) << "one textured primitive: one layer at most";
    if (p.x > 1.45f) {
      EXPECT_LT(weightOf(mesh, v, 0), 0.01f);
    }
    if (p.x < -1.4f) {
      EXPECT_GT(weightOf(mesh, v, 0), 0.99f);
    }
    if (std::abs(p.x) < 0.05f) {
      EXPECT_GT(weightOf(mesh, v, 0), 0.2f);
      EXPECT_LT(weightOf(mesh, v, 0), 0.8f);
    }
  }
}

TEST(TextureMesh, NoGeneratorsNoLayersAndThreadCountsAgree) {
  const Character plain = blobs("", "");
  SkeletonCache plainCache(plain);
  EXPECT_FALSE(marched(plainCache).textured());
  const Character c = blobs("texture ImageTexture { url \"a.png\" }", "texture ImageTexture { url \"a.png\" }");
  EXPECT_EQ(c.textures().size(), 1u) << "one file, one image";
  SkeletonCache cache(c);
  const Mesh one = marched(cache, 1), two = marched(cache, 2);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one.layerImages, (std::vector<int32_t>{0, 0}));
}

TEST(TextureMesh, TheParticleTesselatorsMeshGetsLayersToo) {
  const Character c = blobs("texGen TexGenSphere { } texture ImageTexture { url \"a.png\" }",
                            "texGen TexGenPlane { } texture ImageTexture { url \"b.png\" }");
  SkeletonCache cache(c);
  TesselatorOptions o;
  o.desiredRadius = 0.15f;
  Tesselator tess(o);
  Mesh mesh;
  tess.settle(cache, mesh, 60);
  ASSERT_GT(mesh.vertexCount(), 50u);
  textureMesh(mesh, cache);
  expectLayerInvariants(mesh);
  size_t mixed = 0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    EXPECT_NEAR(weightOf(mesh, v, 0) + weightOf(mesh, v, 1), 1.0f, 1e-5f);
    mixed += std::min(weightOf(mesh, v, 0), weightOf(mesh, v, 1)) > 0.2f;
  }
  EXPECT_GT(mixed, 3u);
}

// One triangle owned by a single generator: every corner takes that generator's (u, v) unchanged unless the
// generator wraps. A plane projector's u is a straight line across the slide (0.2 ... 0.8 here, spanning more than
// half a turn), so it must not be "unwrapped"; a sphere generator's triangle across its seam (u 0.95 and 0.05) is.
Mesh oneTriangleOf(const TexGen& gen, const std::array<glm::vec3, 3>& corners) {
  Mesh mesh;
  for (const glm::vec3& p : corners) {
    mesh.positions.insert(mesh.positions.end(), {p.x, p.y, p.z});
    const glm::vec2 uv = gen.map(p);
    mesh.layers.insert(mesh.layers.end(), {0, -1});
    mesh.layerWeights.insert(mesh.layerWeights.end(), {1.0f, 0.0f});
    mesh.texcoords.insert(mesh.texcoords.end(), {uv.x, uv.y});
  }
  mesh.indices = {0, 1, 2};
  mesh.layerGens = {gen};
  mesh.layerImages = {0};
  return mesh;
}

TEST(SplitByTexture, OnlyASphereGeneratorsUWrapsAtItsSeam) {
  TexGen plane;
  plane.type = TexGenType::Plane;
  plane.width = 1.0f;
  const Mesh flat = oneTriangleOf(plane, {glm::vec3(-0.3f, 0, 0), glm::vec3(0.3f, 0, 0), glm::vec3(0, 0.2f, 0)});
  const auto flatParts = splitByTexture(flat);
  ASSERT_EQ(flatParts.size(), 1u);
  ASSERT_EQ(flatParts[0].uvs.size(), 6u);
  for (uint32_t c = 0; c < 3; ++c) {
    const glm::vec2 uv = plane.map(flat.position(c));
    EXPECT_FLOAT_EQ(flatParts[0].uvs[2 * c], uv.x) << "corner " << c;
    EXPECT_FLOAT_EQ(flatParts[0].uvs[2 * c + 1], uv.y) << "corner " << c;
  }
  EXPECT_NEAR(flatParts[0].uvs[2] - flatParts[0].uvs[0], 0.6f, 1e-6f);

  TexGen sphere;  // seam behind, on -z: corners just either side of it
  const Mesh round = oneTriangleOf(sphere, {glm::vec3(-0.05f, 0, -1), glm::vec3(0.05f, 0, -1), glm::vec3(0, 0.1f, -1)});
  const float u0 = sphere.map(round.position(0)).x, u1 = sphere.map(round.position(1)).x;
  ASSERT_GT(std::abs(u1 - u0), 0.5f);  // the seam lies between the first two corners
  const auto roundParts = splitByTexture(round);
  ASSERT_EQ(roundParts.size(), 1u);
  for (uint32_t c = 1; c < 3; ++c)
    EXPECT_LT(std::abs(roundParts[0].uvs[2 * c] - roundParts[0].uvs[0]), 0.5f) << "corner " << c << " unwrapped";
}

}  // namespace
}  // namespace imps
