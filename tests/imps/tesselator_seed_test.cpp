// SPDX-License-Identifier: MIT
// seedParticles (imps/src/tesselator_seed.cpp): particles seeded from every primitive's own surface, projected onto
// the blended surface and thinned. Every component of a field with several separate blobs gets particles (issue 3:
// seeding never depends on one random point finding the surface), each on the surface and owned by its blob, no two
// closer than 0.8 desiredRadius, no part of a blob left bare, and never more than maxParticles.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "tesselator_sphere.h"
#include "tesselator_state.h"

namespace imps {
namespace {

// Four blobs five metres apart (far beyond each other's influence), of every primitive kind, one small.
struct Blobs {
  std::vector<Primitive> primitives = {
      Primitive::metaball({0, 0, 0}, 0.5f),
      Primitive::metaball({5, 0, 0}, 0.15f),
      Primitive::ellipsoid({0, 5, 0}, glm::angleAxis(0.7f, glm::normalize(glm::vec3(1, 2, 3))), {0.6f, 0.3f, 0.2f}),
      Primitive::lineSeg({0, 0, 5}, {1, 0, 5}, 0.2f, 0.3f),
  };
  std::vector<glm::vec3> anchors = {{0, 0, 0}, {5, 0, 0}, {0, 5, 0}, {0.5f, 0, 5}};  // a point inside each
  Field field;
  Blobs() {
    BlendFunction blend;
    blend.defaultParam = -8.0f;
    field = Field(primitives, std::vector<float>(4, -8.0f), std::vector<glm::vec3>(4, glm::vec3(0.5f)), blend,
                  BlendSets::all(4));
  }
  // The blob nearest x (the blobs are far apart, so this is the one x lies on).
  size_t blobOf(const glm::vec3& x) const {
    size_t best = 0;
    for (size_t b = 1; b < anchors.size(); ++b)
      if (glm::length(x - anchors[b]) < glm::length(x - anchors[best])) best = b;
    return best;
  }
};

TesselatorOptions seedOptions(float h) {
  TesselatorOptions o;
  o.desiredRadius = h;
  o.queryRadius = 2.5f * h;
  o.cubeSize = o.queryRadius;
  return o;
}

// The particles seedParticles places on the blobs at desiredRadius h.
Tesselator::State seeded(const Blobs& blobs, float h) {
  const TesselatorOptions o = seedOptions(h);
  Tesselator::State s(o);
  seedParticles(s, blobs.field, o);
  return s;
}

TEST(TesselatorSeed, EveryBlobGetsParticlesOnItsSurface) {
  const Blobs blobs;
  const float h = 0.08f;
  const Tesselator::State s = seeded(blobs, h);
  ASSERT_GT(s.size(), 0u);
  std::vector<size_t> perBlob(blobs.anchors.size(), 0);
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t b = blobs.blobOf(s.pos[i]);
    ++perBlob[b];
    const FieldSample fs = blobs.field.sample(s.pos[i]);
    ASSERT_GT(glm::length(fs.gradient), 0.0f) << i;
    EXPECT_LE(std::fabs(fs.value - blobs.field.iso()) / glm::length(fs.gradient), 1e-3f * h)
        << "particle " << i << " is on the surface";
    EXPECT_EQ(s.owner[i], int32_t(b)) << "particle " << i << " is owned by the blob it lies on";
    EXPECT_GT(glm::dot(s.grad[i], fs.gradient), 0.0f) << "the gradient there is kept";
  }
  for (size_t b = 0; b < perBlob.size(); ++b) EXPECT_GE(perBlob[b], 8u) << "blob " << b;
  // A lone metaball's surface is its sphere: the analytic check of the first two blobs.
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t b = blobs.blobOf(s.pos[i]);
    if (b >= 2) continue;
    EXPECT_NEAR(glm::length(s.pos[i] - blobs.primitives[b].center), blobs.primitives[b].radius, 1e-3f * h);
  }
}

TEST(TesselatorSeed, ParticlesAreThinnedButLeaveNoPartBare) {
  const Blobs blobs;
  const float h = 0.08f;
  const Tesselator::State s = seeded(blobs, h);
  for (size_t i = 0; i < s.size(); ++i)
    for (size_t j = i + 1; j < s.size(); ++j)
      ASSERT_GE(glm::length(s.pos[i] - s.pos[j]), 0.8f * h * (1.0f - 1e-5f)) << i << " and " << j;
  // Every point of the first sphere has a particle within two desired radii (the candidates are 0.8 h apart and
  // each is either kept or within 0.8 h of one kept).
  for (const glm::vec3& u : test::fibonacciSphere(400)) {
    const glm::vec3 x = blobs.primitives[0].center + blobs.primitives[0].radius * u;
    float nearest = 1e9f;
    for (size_t i = 0; i < s.size(); ++i) nearest = std::min(nearest, glm::length(s.pos[i] - x));
    EXPECT_LT(nearest, 2.0f * h) << "a bare patch at " << x.x << " " << x.y << " " << x.z;
  }
}

TEST(TesselatorSeed, NeverMoreThanMaxParticlesAndDeterministic) {
  const Blobs blobs;
  TesselatorOptions o = seedOptions(0.02f);  // many thousands of candidates
  o.maxParticles = 50;
  Tesselator::State s(o);
  seedParticles(s, blobs.field, o);
  EXPECT_EQ(s.size(), 50u) << "the limit is reached, not passed";
  Tesselator::State again(o);
  seedParticles(again, blobs.field, o);
  ASSERT_EQ(again.size(), s.size());
  for (size_t i = 0; i < s.size(); ++i) EXPECT_EQ(again.pos[i], s.pos[i]) << i;
}

}  // namespace
}  // namespace imps
