// SPDX-License-Identifier: MIT
// A sphere of particles for the tesselator's passes (imps/src/tesselator_state.h, so only for test binaries given
// imps/src on their include path): a lone metaball whose surface is exactly the unit sphere, options for about n
// particles on it, and n particles spread evenly over it (a Fibonacci spiral) with their neighbour lists.
#pragma once

#include <cmath>
#include <vector>

#include "imps/field.h"
#include "tesselator_state.h"

namespace imps::test {

constexpr float kRadius = 1.0f;

// A lone metaball of radius 1 with a very hard blend: its surface is exactly the unit sphere.
inline Field sphereField() {
  BlendFunction blend;
  blend.defaultParam = -8.0f;
  return Field({Primitive::metaball(glm::vec3(0.0f), kRadius)}, {-8.0f}, {glm::vec3(0.25f, 0.5f, 0.75f)}, blend,
               BlendSets::all(1));
}

// Options for about n particles on the unit sphere.
inline TesselatorOptions sphereOptions(size_t n) {
  TesselatorOptions o;
  o.desiredRadius = std::sqrt(4.0f * 3.14159265f / (0.8660254f * float(n)));
  o.queryRadius = 2.5f * o.desiredRadius;
  o.cubeSize = o.queryRadius;
  o.bitsPerDim = 7;
  return o;
}

// n points spread evenly over the unit sphere (a Fibonacci spiral).
inline std::vector<glm::vec3> fibonacciSphere(size_t n) {
  std::vector<glm::vec3> points;
  for (size_t i = 0; i < n; ++i) {
    const float z = 1.0f - 2.0f * (float(i) + 0.5f) / float(n), r = std::sqrt(1.0f - z * z);
    const float a = 2.39996323f * float(i);
    points.push_back(kRadius * glm::vec3(r * std::cos(a), r * std::sin(a), z));
  }
  return points;
}

// Particles at the given points of the sphere (n evenly spread ones by default), with neighbour lists, ready for the
// passes.
struct Sphere {
  Field field = sphereField();
  TesselatorOptions options;
  Tesselator::State s;
  explicit Sphere(size_t n, int threads = 1) : Sphere(fibonacciSphere(n), sphereOptions(n), threads) {}
  Sphere(const std::vector<glm::vec3>& points, const TesselatorOptions& o, int threads = 1) : options(o), s(options) {
    options.threads = threads;
    for (const glm::vec3& p : points) s.add(p, -p, options.desiredRadius, 0);
    s.field = &field;
    s.eHat = 1.0f;
    findNeighbours(s, options);
  }
  // Passes A-C.
  void fansAndVotes() {
    projectVertices(s, options);
    buildFans(s, options);
    voteTriangles(s, options);
  }
};

}  // namespace imps::test
