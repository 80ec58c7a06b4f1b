// SPDX-License-Identifier: MIT
// Primitives: normalised squared distances, gradients, continuity of the meta-line segment, bounds.
#include "imps/primitives.h"

#include <gtest/gtest.h>

#include <random>

#include <glm/gtc/quaternion.hpp>

namespace imps {
namespace {

glm::vec3 randomPoint(std::mt19937& rng, float extent) {
  std::uniform_real_distribution<float> u(-extent, extent);
  return {u(rng), u(rng), u(rng)};
}

glm::vec3 numericGradient(const Primitive& p, const glm::vec3& x) {
  const float h = 1e-3f;
  glm::vec3 g;
  for (int a = 0; a < 3; ++a) {
    glm::vec3 xp = x, xm = x;
    xp[a] += h;
    xm[a] -= h;
    g[a] = (p.distance(xp) - p.distance(xm)) / (2 * h);
  }
  return g;
}

TEST(Primitives, MetaballIsNormalisedSquaredDistance) {
  const Primitive p = Primitive::metaball({1, 2, 3}, 2.0f);
  EXPECT_FLOAT_EQ(p.distance({1, 2, 3}), 0.0f);
  EXPECT_FLOAT_EQ(p.distance({3, 2, 3}), 1.0f);
  EXPECT_FLOAT_EQ(p.distance({1, 6, 3}), 4.0f);
}

TEST(Primitives, EllipsoidAxesAndOrientation) {
  // Semi-axes 1, 2, 3 along local x, y, z; local x rotated onto world y.
  const glm::quat r = glm::angleAxis(glm::half_pi<float>(), glm::vec3(0, 0, 1));
  const Primitive p = Primitive::ellipsoid({0, 0, 0}, r, {1, 2, 3});
  EXPECT_NEAR(p.distance({0, 1, 0}), 1.0f, 1e-5f);   // local +x
  EXPECT_NEAR(p.distance({-2, 0, 0}), 1.0f, 1e-5f);  // local +y -> world -x
  EXPECT_NEAR(p.distance({0, 0, 3}), 1.0f, 1e-5f);
  EXPECT_NEAR(p.distance({0, 0.5f, 0}), 0.25f, 1e-5f);
}

TEST(Primitives, LineSegWithEqualRadiiIsACapsule) {
  const Primitive p = Primitive::lineSeg({0, 0, 0}, {0, 2, 0}, 0.5f, 0.5f);
  EXPECT_NEAR(p.distance({0.5f, 1, 0}), 1.0f, 1e-6f);   // side
  EXPECT_NEAR(p.distance({0, 2.5f, 0}), 1.0f, 1e-6f);   // cap
  EXPECT_NEAR(p.distance({0, -0.5f, 0}), 1.0f, 1e-6f);  // cap
  EXPECT_NEAR(p.distance({1, 1, 0}), 4.0f, 1e-5f);
}

// thickness(): the distance from the core (the nearest swept sphere's centre, the ellipsoid's centre scaled), never
// less than the radius there: a point inside the primitive gets the radius.
TEST(Primitives, ThicknessIsTheDistanceFromTheCoreAtLeastTheRadiusThere) {
  const Primitive cone = Primitive::lineSeg({0, 0, 0}, {0, 2, 0}, 0.4f, 0.2f);  // radius 0.3 half way
  EXPECT_NEAR(cone.thickness({0, 1, 0}), 0.3f, 1e-5f) << "on the axis: the radius there";
  // Inside, off the axis: the radius of the sphere nearest the point, a little up the cone (s = t + slope rho^2 / a).
  EXPECT_NEAR(cone.thickness({0.1f, 1, 0}), 0.4f - 0.1f * (1.0f - 0.1f * 0.01f / 0.3f), 1e-5f);
  EXPECT_NEAR(Primitive::lineSeg({0, 0, 0}, {0, 2, 0}, 0.3f, 0.3f).thickness({0.1f, 1, 0}), 0.3f, 1e-6f)
      << "inside a capsule: its radius";
  EXPECT_NEAR(cone.thickness({0, 3, 0}), 1.0f, 1e-5f) << "beyond the small end: the distance from its centre";
  EXPECT_NEAR(cone.thickness({0, -0.4f, 0}), 0.4f, 1e-5f) << "on the big end's cap";
  const Primitive ball = Primitive::metaball({1, 2, 3}, 0.5f);
  EXPECT_FLOAT_EQ(ball.thickness({1, 2, 3}), 0.5f);
  EXPECT_FLOAT_EQ(ball.thickness({1, 4, 3}), 2.0f);
  const Primitive egg = Primitive::ellipsoid({0, 0, 0}, glm::quat(1, 0, 0, 0), {1, 2, 3});
  EXPECT_NEAR(egg.thickness({0, 0, 0}), 1.0f, 1e-6f) << "its smallest radius";
  EXPECT_NEAR(egg.thickness({0, 4, 0}), 2.0f, 1e-5f) << "twice its d = 1 surface: twice the smallest radius";
}

// The surface d = 1 of a segment with unequal radii is the tangent cone-sphere hull: the distance to the cone
// surface, measured along its normal, is zero on the tangent line and the tangent points sit r*sin(theta) from
// the endpoints towards the smaller end (thesis 2.3.3).
TEST(Primitives, LineSegWithUnequalRadiiIsTheConeSphereHull) {
  const float r1 = 0.5f, r2 = 0.2f, L = 2.0f;
  const Primitive p = Primitive::lineSeg({0, 0, 0}, {L, 0, 0}, r1, r2);
  const float sinT = (r1 - r2) / L, cosT = std::sqrt(1 - sinT * sinT);
  for (float s : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f}) {
    // Point on the tangent line between the two tangent points.
    const glm::vec3 a(r1 * sinT, r1 * cosT, 0), b(L + r2 * sinT, r2 * cosT, 0);
    EXPECT_NEAR(p.distance(a + s * (b - a)), 1.0f, 1e-5f) << s;
  }
  // Beyond the tangent points, the end spheres.
  EXPECT_NEAR(p.distance({-r1, 0, 0}), 1.0f, 1e-6f);
  EXPECT_NEAR(p.distance({L + r2, 0, 0}), 1.0f, 1e-6f);
  EXPECT_LT(p.distance({L, r2, 0}), 1.0f);  // the cone bulges past the small sphere's equator
}

// Swept-sphere definition checked by brute force: d(x) = min over s of |x - c(s)|^2 / r(s)^2.
TEST(Primitives, LineSegMatchesBruteForceMinimum) {
  std::mt19937 rng(7);
  const Primitive p = Primitive::lineSeg({0.1f, -0.2f, 0.3f}, {1.2f, 0.7f, -0.4f}, 0.3f, 0.12f);
  for (int n = 0; n < 500; ++n) {
    const glm::vec3 x = randomPoint(rng, 2.0f);
    float best = 1e30f;
    for (int k = 0; k <= 20000; ++k) {
      const float s = p.length * float(k) / 20000.0f;
      const glm::vec3 c = p.p1 + s * p.axis;
      const float r = p.r1 + p.slope * s;
      best = std::min(best, glm::dot(x - c, x - c) / (r * r));
    }
    EXPECT_NEAR(p.distance(x), best, 1e-3f * std::max(1.0f, best)) << x.x << " " << x.y << " " << x.z;
  }
}

// Value and gradient are continuous everywhere, including across the region boundaries of the line segment.
TEST(Primitives, AnalyticGradientsMatchFiniteDifferences) {
  std::mt19937 rng(11);
  const Primitive prims[] = {
      Primitive::metaball({0.2f, 0.1f, -0.3f}, 0.7f),
      Primitive::ellipsoid({0.1f, 0, 0}, glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3))), {0.4f, 0.8f, 1.1f}),
      Primitive::lineSeg({0, 0, 0}, {1, 0.5f, 0}, 0.4f, 0.15f),
      Primitive::lineSeg({0, 0, 0}, {0, 0, 1}, 0.1f, 0.3f),
  };
  for (const Primitive& p : prims)
    for (int n = 0; n < 300; ++n) {
      const glm::vec3 x = randomPoint(rng, 1.5f);
      glm::vec3 g;
      p.distance(x, g);
      const glm::vec3 ng = numericGradient(p, x);
      EXPECT_NEAR(glm::length(g - ng), 0.0f, 2e-2f * std::max(1.0f, glm::length(ng)));
    }
}

TEST(Primitives, LineSegIsContinuousAcrossRegionBoundaries) {
  const Primitive p = Primitive::lineSeg({0, 0, 0}, {1, 0, 0}, 0.4f, 0.1f);
  // Walk along lines parallel to the axis, crossing both region boundaries, and check there is no jump.
  for (float y : {0.05f, 0.3f, 0.6f, 1.2f}) {
    float previous = p.distance({-1.0f, y, 0});
    for (int k = 1; k <= 4000; ++k) {
      const float x = -1.0f + 3.0f * float(k) / 4000.0f;
      const float v = p.distance({x, y, 0});
      EXPECT_LT(std::abs(v - previous), 0.05f) << "jump at x=" << x << " y=" << y;
      previous = v;
    }
  }
}

TEST(Primitives, BoundsEncloseTheRegionAndDistanceBoundsAreConservative) {
  std::mt19937 rng(3);
  const Primitive prims[] = {
      Primitive::metaball({0.2f, 0.1f, -0.3f}, 0.7f),
      Primitive::ellipsoid({0.1f, 0, 0}, glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3))), {0.4f, 0.8f, 1.1f}),
      Primitive::lineSeg({0, 0, 0}, {1, 0.5f, 0}, 0.4f, 0.15f),
  };
  for (const Primitive& p : prims) {
    const Box b = p.bounds(3.0f);
    for (int n = 0; n < 3000; ++n) {
      const glm::vec3 x = randomPoint(rng, 3.0f);
      if (p.distance(x) <= 3.0f) {
        EXPECT_TRUE(b.contains(x));
      }
    }
    for (int n = 0; n < 200; ++n) {
      Box box;
      box.extend(randomPoint(rng, 2.0f));
      box.extend(box.lo + glm::vec3(0.3f, 0.2f, 0.25f));
      const float lo = p.minDistance(box), hi = p.maxDistance(box);
      for (int m = 0; m < 50; ++m) {
        const glm::vec3 t(float(m % 5) / 4, float((m / 5) % 5) / 4, float(m / 25) / 1);
        const glm::vec3 x = box.lo + glm::min(t, glm::vec3(1)) * box.size();
        const float d = p.distance(x);
        EXPECT_LE(lo, d + 1e-4f);
        EXPECT_GE(hi, d - 1e-4f);
      }
    }
  }
}

TEST(Primitives, RigidTransformMovesTheSurface) {
  const Primitive p = Primitive::lineSeg({0, 0, 0}, {1, 0, 0}, 0.2f, 0.2f);
  const glm::quat r = glm::angleAxis(glm::half_pi<float>(), glm::vec3(0, 0, 1));
  const Primitive q = p.transformed(r, {0, 0, 5});
  EXPECT_NEAR(q.distance({0, 0.5f, 5}), 0.0f, 1e-6f);
  EXPECT_NEAR(q.distance({0.2f, 0.5f, 5}), 1.0f, 1e-5f);
}

}  // namespace
}  // namespace imps
