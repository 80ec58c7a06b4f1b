// SPDX-License-Identifier: MIT
// worstDistanceToMesh (imps/src/tesselator_accuracy.cpp): the worst point-to-triangle distance, checked against
// distances worked out by hand: each region of a triangle (face, edges, corners), an octahedron inscribed in a
// sphere (worst at the face centres' directions: R (1 - 1/sqrt 3)), and the searchRadius conventions.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "imps/mesh.h"
#include "imps/tesselator.h"
#include "octahedron.h"

namespace imps {
namespace {

Mesh meshOf(const std::vector<glm::vec3>& vertices, const std::vector<uint32_t>& indices) {
  Mesh mesh;
  for (const glm::vec3& v : vertices) mesh.positions.insert(mesh.positions.end(), {v.x, v.y, v.z});
  mesh.indices = indices;
  return mesh;
}

double worst(const Mesh& mesh, const glm::vec3& p, float searchRadius) {
  const std::vector<glm::vec3> one = {p};
  return worstDistanceToMesh(mesh, one, searchRadius);
}

TEST(TesselatorAccuracy, EveryRegionOfATriangle) {
  // The right triangle a = 0, b = x, c = y in the plane z = 0.
  const Mesh t = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2});
  struct Case {
    glm::vec3 p;
    double distance;
    const char* region;
  };
  const float s2 = std::sqrt(2.0f);
  for (const Case& c :
       {Case{{0.25f, 0.25f, 2}, 2.0, "face (above)"}, Case{{0.25f, 0.25f, -0.5f}, 0.5, "face (below)"},
        Case{{0.2f, 0.3f, 0}, 0.0, "on the face"}, Case{{-1, -1, 0}, s2, "corner a"}, Case{{3, 0, 0}, 2.0, "corner b"},
        Case{{0, 4, 0}, 3.0, "corner c"}, Case{{0.5f, -1, 0}, 1.0, "edge ab"}, Case{{-1, 0.5f, 1}, s2, "edge ca"},
        Case{{1, 1, 0}, 1.0 / s2, "edge bc"}, Case{{2, -1, 0}, s2, "corner b, below edge ab's end"}}) {
    EXPECT_NEAR(worst(t, c.p, 10.0f), c.distance, 1e-5) << c.region;
    // The winding does not matter: a distance is unsigned.
    EXPECT_NEAR(worst(meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 2, 1}), c.p, 10.0f), c.distance, 1e-5) << c.region;
  }
}

TEST(TesselatorAccuracy, InscribedOctahedronAgainstItsSphere) {
  // Anywhere in space, negative cells included, and at a search radius smaller than the mesh.
  for (const glm::vec3 centre : {glm::vec3(0.0f), glm::vec3(-3.3f, 7.1f, -0.4f)}) {
    const float r = 0.75f;
    const Mesh mesh = test::octahedronMesh(centre, r);
    // Points on the sphere: the corners (on the mesh) and the directions of the face centres (farthest from it).
    std::vector<glm::vec3> corners, faceDirections, all;
    for (size_t v = 0; v < 6; ++v) corners.push_back(mesh.position(v));
    for (float x : {-1.0f, 1.0f})
      for (float y : {-1.0f, 1.0f})
        for (float z : {-1.0f, 1.0f}) faceDirections.push_back(centre + r * glm::normalize(glm::vec3(x, y, z)));
    EXPECT_NEAR(worstDistanceToMesh(mesh, corners, r), 0.0, 1e-6);
    const double expected = double(r) * (1.0 - 1.0 / std::sqrt(3.0));
    EXPECT_NEAR(worstDistanceToMesh(mesh, faceDirections, r), expected, 1e-5);
    // The worst of a set is its largest member's: a spiral over the whole sphere never exceeds the face centres'.
    all = corners;
    for (size_t k = 0; k < 500; ++k) {
      const float z = 1.0f - 2.0f * (float(k) + 0.5f) / 500.0f, q = std::sqrt(1.0f - z * z);
      all.push_back(centre + r * glm::vec3(q * std::cos(2.39996f * float(k)), q * std::sin(2.39996f * float(k)), z));
    }
    const double spiral = worstDistanceToMesh(mesh, all, r);
    EXPECT_LE(spiral, expected + 1e-6);
    EXPECT_GT(spiral, 0.9 * expected) << "500 points come close to a face centre's direction";
    all.insert(all.end(), faceDirections.begin(), faceDirections.end());
    EXPECT_NEAR(worstDistanceToMesh(mesh, all, r), expected, 1e-5);
  }
}

TEST(TesselatorAccuracy, SearchRadiusConventions) {
  const Mesh mesh = test::octahedronMesh();
  EXPECT_EQ(worstDistanceToMesh(mesh, {}, 1.0f), 0.0) << "no points: nothing is off";
  const std::vector<glm::vec3> p = {{0, 0, 0.5f}};
  EXPECT_EQ(worstDistanceToMesh(Mesh{}, p, 0.25f), 0.25) << "no triangles: every point counts as searchRadius";
  // A point farther than searchRadius from every triangle counts as searchRadius.
  EXPECT_NEAR(worst(mesh, {0, 0, 5}, 0.5f), 0.5, 1e-6);
  EXPECT_NEAR(worst(mesh, {0, 0, 5}, 10.0f), 4.0, 1e-5);
  // Inside the octahedron: the distance to the nearest face plane, x + y + z = 1 for the centre: 1/sqrt 3.
  EXPECT_NEAR(worst(mesh, {0, 0, 0}, 2.0f), 1.0 / std::sqrt(3.0), 1e-5);
}

}  // namespace
}  // namespace imps
