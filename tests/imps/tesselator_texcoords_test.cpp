// SPDX-License-Identifier: MIT
// Tests for the particle tesselator's carried texture coordinates (imps/src/tesselator_texcoords.cpp,
// TextureMode::Carried): determinism for any thread count, agreement with the generators where the skin moves
// rigidly, nothing carried without textures, and the scene field that selects the mode.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/scene_writer.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "imps/texturing.h"

namespace imps {
namespace {

struct Loaded {
  Scene scene;
  Character character;
  TesselatorOptions options;
};

Loaded load(const std::string& name) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/" + name);
  EXPECT_TRUE(scene.has_value());
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value());
  Loaded l{*scene, std::move(*c), {}};
  l.options = TesselatorOptions::fromNode(std::get<Tesselator3MPNode>(l.scene.polygonizer));
  return l;
}

void drawFrame(Tesselator& tess, const SkeletonCache& cache, Mesh& mesh) {
  tess.frame(cache, mesh);
  textureMesh(mesh, cache, tess.options().threads);
  tess.carryTexcoords(mesh);
}

// The textured biped bending its left elbow up and down for `frames` frames (carried mode), the last mesh.
Mesh bendingElbow(int threads, int frames) {
  Loaded l = load("textured_biped.wrl");
  l.options.threads = threads;
  l.options.textureMode = TextureMode::Carried;
  SkeletonCache cache(l.character);
  Tesselator tess(l.options);
  Mesh mesh;
  const int elbow = l.character.findJoint("L_Forearm");
  const glm::quat rest = cache.local(elbow).rotation;
  for (int f = 0; f < frames; ++f) {
    cache.setRotation(elbow, glm::angleAxis(0.8f * std::sin(0.15f * float(f)), glm::vec3(0, 0, 1)) * rest);
    cache.update();
    drawFrame(tess, cache, mesh);
  }
  return mesh;
}

TEST(CarriedTexcoords, OneTwoAndFourThreadsGiveIdenticalMeshes) {
  const Mesh one = bendingElbow(1, 40), two = bendingElbow(2, 40), four = bendingElbow(4, 40);
  ASSERT_TRUE(one.textured());
  ASSERT_EQ(one.layerTexcoords.size(), 4 * one.vertexCount()) << "the particle mesh carries its coordinates";
  EXPECT_TRUE(one == two);
  EXPECT_TRUE(one == four);
}

// Moving the whole character rigidly moves every particle and every generator by the same transform: the carried
// coordinates then still agree with the generators' (the particles' own small motion is advected).
TEST(CarriedTexcoords, UnderARigidMotionTheCarriedCoordinatesAgreeWithTheGenerators) {
  Loaded l = load("textured_biped.wrl");
  l.options.textureMode = TextureMode::Carried;
  SkeletonCache cache(l.character);
  Tesselator tess(l.options);
  Mesh mesh;
  tess.settle(cache, mesh, 200);
  textureMesh(mesh, cache);
  tess.carryTexcoords(mesh);
  ASSERT_FALSE(mesh.layerTexcoords.empty());
  const int root = l.character.findJoint("Pelvis");
  const Rigid rest = cache.local(root);
  for (int f = 1; f <= 20; ++f) {
    cache.setRotation(root, glm::angleAxis(0.03f * float(f), glm::vec3(0, 1, 0)) * rest.rotation);
    cache.setTranslation(root, rest.translation + glm::vec3(0.01f * float(f), 0, 0));
    cache.update();
    drawFrame(tess, cache, mesh);
  }
  ASSERT_FALSE(tess.stats().fallback);
  size_t compared = 0;
  double worst = 0.0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v)
    for (size_t k = 0; k < 2; ++k) {
      const int32_t layer = mesh.layers[2 * v + k];
      if (layer < 0 || mesh.layerWeights[2 * v + k] < 0.5f) continue;  // well inside the primitive's own skin
      const glm::vec2 carried = mesh.layerUv(v, layer), projected = mesh.layerGens[size_t(layer)].map(mesh.position(v));
      const float du = carried.x - projected.x - std::round(carried.x - projected.x);
      worst = std::max(worst, double(std::hypot(du, carried.y - projected.y)));
      ++compared;
    }
  EXPECT_GT(compared, 200u);
  // A texel of a 256-texel image is 0.004; the 20 frames' drift stays within a few.
  EXPECT_LT(worst, 0.02) << "over " << compared << " vertex layers";
}

// At the thesis's fidelity (~900 particles) the repair joins a wrist's rims through rows of new vertices on the
// surface in some renders (Tesselator::triangulate). Those vertices carry coordinates too: a nearby particle's, moved
// by what the layer's generator maps the step to. So each one's offset from its generator's mapping is that of a
// particle within a few desiredRadius (to rounding), and some of those offsets are not zero (the coordinates really
// are carried, not projected).
TEST(CarriedTexcoords, SurfaceRowVerticesContinueTheParticlesCoordinates) {
  Loaded l = load("textured_biped.wrl");
  l.options.textureMode = TextureMode::Carried;
  for (float* v : {&l.options.desiredRadius, &l.options.queryRadius, &l.options.cubeSize}) *v *= 1.728f;
  const float h = l.options.desiredRadius;
  SkeletonCache cache(l.character);
  Tesselator tess(l.options);
  Mesh mesh;
  std::vector<int> joints;
  std::vector<glm::quat> rest;
  for (const char* name : {"L_UpperArm", "R_UpperArm", "L_Forearm", "R_Forearm", "L_Thigh", "R_Thigh"}) {
    joints.push_back(l.character.findJoint(name));
    rest.push_back(cache.local(joints.back()).rotation);
  }
  // Vertex v's offset from its layer's generator in its slot k (a sphere generator's u unwrapped).
  const auto offset = [&](size_t v, size_t k) {
    const glm::vec2 uv(mesh.layerTexcoords[4 * v + 2 * k], mesh.layerTexcoords[4 * v + 2 * k + 1]);
    glm::vec2 d = uv - mesh.layerGens[size_t(mesh.layers[2 * v + k])].map(mesh.position(v));
    d.x -= std::round(d.x);
    return d;
  };
  size_t withRows = 0, checked = 0, moved = 0;
  for (int f = 0; f < 300; ++f) {
    const float angle = glm::radians(45.0f * std::sin(0.2f * float(f)));
    for (size_t k = 0; k < joints.size(); ++k)
      cache.setRotation(joints[k], rest[k] * glm::angleAxis(k % 2 ? -angle : angle, glm::vec3(0, 0, 1)));
    cache.update();
    drawFrame(tess, cache, mesh);
    if (tess.stats().fallback) continue;
    const size_t particles = tess.particles().size();
    ASSERT_EQ(mesh.vertexCount(), particles + tess.stats().surfaceRowVertices);
    ASSERT_EQ(mesh.layerTexcoords.size(), 4 * mesh.vertexCount()) << "render " << f << " is no longer carried";
    withRows += tess.stats().surfaceRowVertices > 0;
    for (size_t v = particles; v < mesh.vertexCount(); ++v)
      for (size_t k = 0; k < 2; ++k) {
        const int32_t layer = mesh.layers[2 * v + k];
        if (layer < 0) continue;
        const glm::vec2 own = offset(v, k);
        bool found = false;
        for (size_t p = 0; p < particles && !found; ++p)
          if (glm::length(mesh.position(p) - mesh.position(v)) < 4.0f * h)
            for (size_t q = 0; q < 2 && !found; ++q)
              found = mesh.layers[2 * p + q] == layer && glm::length(offset(p, q) - own) < 1e-4f;
        EXPECT_TRUE(found) << "render " << f << ": vertex " << v << "'s layer " << layer << " offset (" << own.x << ", "
                           << own.y << ") is no nearby particle's";
        ++checked;
        moved += glm::length(own) > 1e-3f;
      }
  }
  std::printf("%zu renders with surface rows; %zu textured row vertex layers, %zu of them off their generator\n",
              withRows, checked, moved);
  EXPECT_GT(moved, 0u) << "no carried coordinates on a surface row: nothing was checked";
}

TEST(CarriedTexcoords, ProjectiveModeAndUntexturedCharactersCarryNothing) {
  Loaded biped = load("textured_biped.wrl");
  biped.options.textureMode = TextureMode::Projective;
  SkeletonCache cache(biped.character);
  Tesselator projective(biped.options);
  Mesh mesh;
  projective.settle(cache, mesh, 60);
  textureMesh(mesh, cache);
  const Mesh before = mesh;
  projective.carryTexcoords(mesh);
  EXPECT_TRUE(mesh == before) << "projective: carryTexcoords is a no-op";
  EXPECT_TRUE(mesh.layerTexcoords.empty());

  Loaded plain = load("simple_biped.wrl");
  plain.options.textureMode = TextureMode::Carried;
  SkeletonCache plainCache(plain.character);
  Tesselator carried(plain.options);
  carried.settle(plainCache, mesh, 60);
  textureMesh(mesh, plainCache);
  carried.carryTexcoords(mesh);
  EXPECT_FALSE(mesh.textured());
  EXPECT_TRUE(mesh.layerTexcoords.empty());
}

// The first carried frame takes every coordinate from the generators: the same (u, v) as projective texturing.
TEST(CarriedTexcoords, NewParticlesTakeTheGeneratorsCoordinates) {
  Loaded l = load("textured_biped.wrl");
  l.options.textureMode = TextureMode::Carried;
  SkeletonCache cache(l.character);
  Tesselator tess(l.options);
  Mesh mesh;
  tess.settle(cache, mesh, 60);
  textureMesh(mesh, cache);
  tess.carryTexcoords(mesh);
  ASSERT_EQ(mesh.layerTexcoords.size(), 4 * mesh.vertexCount());
  for (size_t v = 0; v < mesh.vertexCount(); ++v)
    for (size_t k = 0; k < 2; ++k) {
      const int32_t layer = mesh.layers[2 * v + k];
      if (layer < 0) continue;
      EXPECT_EQ(mesh.layerUv(v, layer), mesh.layerGens[size_t(layer)].map(mesh.position(v)));
    }
}

TEST(TextureModeField, ReadWrittenBackAndBadValuesAreErrorsAtThem) {
  const std::string text =
      "#VRML V2.0 utf8\nTesselator3MP {\n  textureMode \"carried\"\n  sceneGraph Metaball { }\n}\n";
  auto scene = readScene(text, "s.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  EXPECT_EQ(std::get<Tesselator3MPNode>(scene->polygonizer).textureMode, TextureMode::Carried);
  EXPECT_EQ(TesselatorOptions::fromNode(std::get<Tesselator3MPNode>(scene->polygonizer)).textureMode,
            TextureMode::Carried);
  const std::string written = writeScene(*scene);
  EXPECT_NE(written.find("textureMode \"carried\""), std::string::npos) << written;
  auto again = readScene(written, "s.wrl");
  ASSERT_TRUE(again.has_value());
  EXPECT_TRUE(*again == *scene);
  auto projective = readScene("#VRML V2.0 utf8\nTesselator3MP { textureMode \"projective\" }\n", "s.wrl");
  ASSERT_TRUE(projective.has_value());
  EXPECT_EQ(std::get<Tesselator3MPNode>(projective->polygonizer).textureMode, TextureMode::Projective);
  EXPECT_EQ(writeScene(*projective).find("textureMode"), std::string::npos) << "the default is not written";

  auto bad = readScene("#VRML V2.0 utf8\nTesselator3MP {\n  textureMode \"sliding\"\n}\n", "s.wrl");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().str().find("s.wrl:3:15: error: field 'textureMode' of Tesselator3MP must be \"projective\" or "
                                   "\"carried\", found \"sliding\""),
            std::string::npos)
      << bad.error().str();
  auto number = readScene("#VRML V2.0 utf8\nTesselator3MP { textureMode 1 }\n", "s.wrl");
  ASSERT_FALSE(number.has_value());
  EXPECT_NE(number.error().str().find("s.wrl:2:29: error:"), std::string::npos) << number.error().str();
}

}  // namespace
}  // namespace imps
