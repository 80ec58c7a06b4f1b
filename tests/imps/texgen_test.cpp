// SPDX-License-Identifier: MIT
// Texture-coordinate generators (thesis 3.9): the sphere's and the plane's mappings, checked analytically.
#include "imps/texgen.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

namespace imps {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

void expectUv(const glm::vec2& uv, float u, float v, float tolerance = 1e-6f) {
  EXPECT_NEAR(uv.x, u, tolerance);
  EXPECT_NEAR(uv.y, v, tolerance);
}

TEST(TexGen, SphereMapsLongitudeAndLatitudeAboutLocalY) {
  TexGen g;  // a sphere at the origin, axis-aligned
  expectUv(g.map({0, 0, 1}), 0.5f, 0.5f);    // straight ahead: the image's centre
  expectUv(g.map({1, 0, 0}), 0.75f, 0.5f);   // a quarter turn towards +x
  expectUv(g.map({-1, 0, 0}), 0.25f, 0.5f);  // and towards -x
  expectUv(g.map({0, 2, 0}), 0.5f, 1.0f);    // north pole (atan2(0, 0) = 0)
  expectUv(g.map({0, -3, 0}), 0.5f, 0.0f);   // south pole
  // 45 degrees up, 45 degrees round: latitude pi/4 -> v = 3/4; longitude pi/4 -> u = 5/8.
  const float c = std::cos(kPi / 4);
  expectUv(g.map({c * c, c, c * c}), 0.625f, 0.75f);
  // The seam is behind (on -z): just either side of it u is near 1 and near 0.
  EXPECT_NEAR(g.map({1e-4f, 0, -1}).x, 1.0f, 1e-4f);
  EXPECT_NEAR(g.map({-1e-4f, 0, -1}).x, 0.0f, 1e-4f);
  expectUv(g.map({0, 0, 0}), 0.5f, 0.5f);  // the centre itself
}

TEST(TexGen, SphereGivesTheClosestPointsCoordinatesWhateverTheDistance) {
  TexGen g;
  g.origin = {1, 2, 3};
  for (const glm::vec3 d : {glm::vec3(0.3f, -0.5f, 0.8f), glm::vec3(-2, 1, 0.1f), glm::vec3(0, 0, -1)})
    for (float scale : {0.01f, 1.0f, 50.0f})
      expectUv(g.map(g.origin + scale * d), g.map(g.origin + d).x, g.map(g.origin + d).y, 1e-5f);
}

TEST(TexGen, SphereFollowsItsRotationAndTranslation) {
  TexGen g;
  // Turned a quarter about x: local +y (north) now points along world +z... and local +z along world -y.
  g.rotation = glm::angleAxis(kPi / 2, glm::vec3(1, 0, 0));
  g.origin = {0, 0, 5};
  expectUv(g.map({0, 0, 6}), 0.5f, 1.0f, 1e-5f);   // world +z from the centre is the north pole
  expectUv(g.map({0, -1, 5}), 0.5f, 0.5f, 1e-5f);  // world -y is straight ahead
  // transformed() composes: the same point moved with the generator keeps its coordinates.
  const glm::quat r = glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3)));
  const glm::vec3 t(-1, 4, 2);
  const TexGen moved = g.transformed(r, t);
  for (const glm::vec3 x : {glm::vec3(0.2f, 0.1f, 5.3f), glm::vec3(-1, 2, 3), glm::vec3(0, -1, 5)}) {
    const glm::vec2 before = g.map(x), after = moved.map(r * x + t);
    expectUv(after, before.x, before.y, 1e-5f);
  }
}

TEST(TexGen, PlaneProjectsAlongLocalZLikeASlideProjector) {
  TexGen g;
  g.type = TexGenType::Plane;
  g.width = 2.0f;
  g.height = 4.0f;
  expectUv(g.map({0, 0, 0}), 0.5f, 0.5f);
  expectUv(g.map({1, 2, 0}), 1.0f, 1.0f);     // the slide's top-right corner
  expectUv(g.map({-1, -2, 0}), 0.0f, 0.0f);   // bottom-left
  expectUv(g.map({0.5f, -1, 7}), 0.75f, 0.25f);
  expectUv(g.map({0.5f, -1, -7}), 0.75f, 0.25f);  // depth does not matter: the closest point on the plane
  expectUv(g.map({3, 0, 0}), 2.0f, 0.5f);     // beyond the slide: coordinates go on (the image repeats)
  // Rotated a quarter about z: local x is world y.
  g.rotation = glm::angleAxis(kPi / 2, glm::vec3(0, 0, 1));
  g.origin = {10, 0, 0};
  expectUv(g.map({10, 1, 0}), 1.0f, 0.5f, 1e-5f);
  expectUv(g.map({9, 0, 0}), 0.5f, 0.75f, 1e-5f);
}

}  // namespace
}  // namespace imps
