// SPDX-License-Identifier: MIT
// Tests for imps/mesh.h: topology checks, signed volume, bounds and appendMesh.
#include "imps/mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <utility>

namespace imps {
namespace {

Mesh tetrahedron() {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  mesh.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  return mesh;
}

// Unit cube [0,1]^3 shifted by `offset`; vertex i sits at (i & 1, (i >> 1) & 1, (i >> 2) & 1) + offset.
Mesh cube(glm::vec3 offset = glm::vec3(0.0f)) {
  Mesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.push_back(static_cast<float>(i & 1) + offset.x);
    mesh.positions.push_back(static_cast<float>((i >> 1) & 1) + offset.y);
    mesh.positions.push_back(static_cast<float>((i >> 2) & 1) + offset.z);
  }
  const uint32_t quads[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& q : quads) mesh.indices.insert(mesh.indices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  return mesh;
}

// n x n quads on the unit square in the z = 0 plane, facing +z.
Mesh grid(uint32_t n) {
  Mesh mesh;
  for (uint32_t y = 0; y <= n; ++y) {
    for (uint32_t x = 0; x <= n; ++x) {
      mesh.positions.insert(mesh.positions.end(), {static_cast<float>(x) / static_cast<float>(n),
                                                   static_cast<float>(y) / static_cast<float>(n), 0.0f});
    }
  }
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  return mesh;
}

TEST(MeshTopology, TetrahedronIsClosedManifold) {
  const Mesh mesh = tetrahedron();
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.unusedVertices, 0u);
  EXPECT_EQ(t.eulerCharacteristic, 2);
  EXPECT_NEAR(signedVolume(mesh), 1.0 / 6.0, 1e-12);
}

TEST(MeshTopology, CubeIsClosedManifoldWithUnitVolume) {
  const Mesh mesh = cube();
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.eulerCharacteristic, 2);  // 8 - 18 + 12
  EXPECT_NEAR(signedVolume(mesh), 1.0, 1e-12);
  // The volume does not depend on where the cube is.
  EXPECT_NEAR(signedVolume(cube({100.0f, -50.0f, 7.0f})), 1.0, 1e-6);
}

TEST(MeshTopology, RemovedTriangleLeavesThreeBoundaryEdges) {
  Mesh mesh = cube();
  mesh.indices.erase(mesh.indices.begin() + 6, mesh.indices.begin() + 9);  // first triangle of the +x face
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_FALSE(t.closedManifold());
  EXPECT_EQ(t.boundaryEdges, 3u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.nonManifoldVertices, 0u);  // a hole's rim is a half-disk, which is manifold
  EXPECT_EQ(t.orientationConflicts, 0u);
  EXPECT_EQ(t.eulerCharacteristic, 1);  // 8 - 18 + 11
}

TEST(MeshTopology, OpenGridHasItsRimAsBoundary) {
  const uint32_t n = 7;
  const MeshTopology t = analyzeTopology(grid(n));
  EXPECT_EQ(t.boundaryEdges, 4u * n);
  EXPECT_EQ(t.eulerCharacteristic, 1);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.nonManifoldVertices, 0u);
  EXPECT_EQ(t.orientationConflicts, 0u);
}

TEST(MeshTopology, FlippedTriangleGivesOrientationConflicts) {
  Mesh mesh = cube();
  std::swap(mesh.indices[7], mesh.indices[8]);  // triangle (1, 3, 7) on the +x face
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_FALSE(t.closedManifold());
  EXPECT_EQ(t.orientationConflicts, 3u);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.nonManifoldVertices, 0u);
  EXPECT_LT(signedVolume(mesh), 1.0 - 1e-3);
}

TEST(MeshTopology, InsideOutCubeHasNegativeVolumeButNoConflicts) {
  Mesh mesh = cube();
  for (size_t t = 0; t < mesh.triangleCount(); ++t) std::swap(mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]);
  EXPECT_TRUE(analyzeTopology(mesh).closedManifold());
  EXPECT_NEAR(signedVolume(mesh), -1.0, 1e-12);
}

TEST(MeshTopology, ThreeTrianglesOnAnEdgeAreNonManifold) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0.5f, 1, 0, 0.5f, -1, 0, 0.5f, 0, 1};
  mesh.indices = {0, 1, 2, 1, 0, 3, 0, 1, 4};
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.nonManifoldEdges, 1u);
  EXPECT_EQ(t.boundaryEdges, 6u);
  EXPECT_EQ(t.nonManifoldVertices, 2u);  // both ends of the shared edge
  EXPECT_EQ(t.components, 1u);
  EXPECT_FALSE(t.closedManifold());
}

TEST(MeshTopology, CubesSharingOneVertexMakeANonManifoldVertex) {
  // Cube B's corner 0 is moved onto cube A's corner 7 by index, leaving B's own vertex 0 (index 8) unused.
  Mesh mesh = cube();
  appendMesh(mesh, cube({1.0f, 1.0f, 1.0f}));
  for (size_t i = 36; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] == 8) mesh.indices[i] = 7;
  }
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.nonManifoldVertices, 1u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.orientationConflicts, 0u);
  EXPECT_EQ(t.components, 2u);  // components connect through edges, not single vertices
  EXPECT_EQ(t.unusedVertices, 1u);
  EXPECT_EQ(t.eulerCharacteristic, 15 - 36 + 24);
  EXPECT_FALSE(t.closedManifold());
}

TEST(MeshTopology, DisjointCubesAreTwoComponents) {
  Mesh mesh = cube();
  appendMesh(mesh, cube({3.0f, 0.0f, 0.0f}));
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.eulerCharacteristic, 4);
  EXPECT_NEAR(signedVolume(mesh), 2.0, 1e-12);
}

// A bar [0,3] x [0,1]^2 and a unit cube at x = 10 (the reference), against the bar meshed as two unit cubes at its
// ends and no cube at x = 10: the same two components, but one part cut off and one missing.
TEST(MatchComponents, FindsPartsCutOffAndPartsMissingThatTheCountHides) {
  Mesh bar = cube();
  for (size_t v = 0; v < bar.vertexCount(); ++v) bar.positions[3 * v] *= 3.0f;
  Mesh reference = bar;
  appendMesh(reference, cube({10.0f, 0.0f, 0.0f}));
  Mesh pieces = cube();
  appendMesh(pieces, cube({2.0f, 0.0f, 0.0f}));
  pieces.positions.insert(pieces.positions.end(), {10.5f, 0.5f, 0.5f});  // an unused vertex beside the missing cube
  const ComponentMatch m = matchComponents(pieces, reference);
  EXPECT_EQ(m.components, 2u);
  EXPECT_EQ(m.referenceComponents, 2u);
  EXPECT_EQ(m.cutOff, 1u);
  EXPECT_EQ(m.missing, 1u);
  EXPECT_FLOAT_EQ(m.largestMissing, std::sqrt(3.0f)) << "the unit cube's diagonal";
  const ComponentMatch same = matchComponents(reference, reference);
  EXPECT_EQ(same.components, 2u);
  EXPECT_EQ(same.cutOff, 0u);
  EXPECT_EQ(same.missing, 0u);
  EXPECT_EQ(same.largestMissing, 0.0f);
  const ComponentMatch none = matchComponents(Mesh{}, reference);
  EXPECT_EQ(none.components, 0u);
  EXPECT_EQ(none.missing, 2u);
  EXPECT_FLOAT_EQ(none.largestMissing, std::sqrt(11.0f)) << "the 3 x 1 x 1 bar's diagonal";
  EXPECT_EQ(none.missingCavities, 0u);
}

// A missing component, or a piece cut off, that faces inward (negative signed volume) is a cavity: air enclosed by the
// solid.
TEST(MatchComponents, ToldCavitiesFromSolidsAmongTheMissingAndTheCutOff) {
  Mesh box = cube();
  for (float& x : box.positions) x = 4.0f * x - 1.5f;  // [-1.5, 2.5]^3, round the cavity
  Mesh cavity = cube();
  for (size_t t = 0; t < cavity.triangleCount(); ++t) std::swap(cavity.indices[3 * t + 1], cavity.indices[3 * t + 2]);
  Mesh reference = box;
  appendMesh(reference, cavity);
  appendMesh(reference, cube({10.0f, 0.0f, 0.0f}));
  ASSERT_LT(signedVolume(cavity), 0.0);
  const ComponentMatch m = matchComponents(box, reference);
  EXPECT_EQ(m.referenceComponents, 3u);
  EXPECT_EQ(m.missing, 2u);
  EXPECT_EQ(m.missingCavities, 1u);
  EXPECT_EQ(m.cutOff, 0u);
  const ComponentMatch withCavity = matchComponents(reference, reference);
  EXPECT_EQ(withCavity.missing, 0u);
  EXPECT_EQ(withCavity.missingCavities, 0u);
  // A pocket closed where the reference is one surface: a piece cut off that faces inward.
  Mesh pocket = cube({0.25f, 0.25f, 0.25f});
  for (float& x : pocket.positions) x *= 0.5f;
  for (size_t t = 0; t < pocket.triangleCount(); ++t) std::swap(pocket.indices[3 * t + 1], pocket.indices[3 * t + 2]);
  Mesh closed = box;
  appendMesh(closed, pocket);
  const ComponentMatch pocketed = matchComponents(closed, box);
  EXPECT_EQ(pocketed.cutOff, 1u);
  EXPECT_EQ(pocketed.cutOffCavities, 1u);
  EXPECT_EQ(m.cutOffCavities, 0u);
}

TEST(MeshTopology, DegenerateTrianglesAndUnusedVerticesAreCounted) {
  Mesh mesh = cube();
  mesh.positions.insert(mesh.positions.end(), {5, 5, 5, 6, 6, 6});  // vertices 8 and 9, unused
  mesh.indices.insert(mesh.indices.end(), {0, 0, 1, 2, 3, 2});     // two degenerate triangles
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.degenerateTriangles, 2u);
  EXPECT_EQ(t.unusedVertices, 2u);
  EXPECT_FALSE(t.closedManifold());
  // Degenerate triangles add no edges or faces: the rest is still a closed sphere.
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.eulerCharacteristic, 2);
  EXPECT_EQ(t.components, 1u);
}

TEST(MeshTopology, EmptyMeshHasNothing) {
  const MeshTopology t = analyzeTopology(Mesh{});
  EXPECT_EQ(t.components, 0u);
  EXPECT_EQ(t.eulerCharacteristic, 0);
  EXPECT_EQ(signedVolume(Mesh{}), 0.0);
}

TEST(MeshBounds, CoversAllVertices) {
  Mesh mesh = cube({-2.0f, 1.0f, 0.5f});
  mesh.positions.insert(mesh.positions.end(), {10, -10, 0});  // unused vertices count too
  const MeshBounds box = bounds(mesh);
  EXPECT_FALSE(box.empty());
  EXPECT_EQ(box.min, glm::vec3(-2.0f, -10.0f, 0.0f));
  EXPECT_EQ(box.max, glm::vec3(10.0f, 2.0f, 1.5f));
  EXPECT_TRUE(bounds(Mesh{}).empty());
}

TEST(AppendMesh, OffsetsIndicesAndDropsAttributesOnlyOneSideHas) {
  Mesh a = tetrahedron();
  a.normals.assign(a.positions.size(), 0.5f);
  a.colors.assign(a.positions.size(), 0.25f);
  Mesh b = cube();
  b.colors.assign(b.positions.size(), 1.0f);
  Mesh merged = a;
  appendMesh(merged, b);
  EXPECT_EQ(merged.vertexCount(), 12u);
  EXPECT_EQ(merged.triangleCount(), 16u);
  EXPECT_EQ(merged.indices[12], b.indices[0] + 4);
  EXPECT_TRUE(merged.normals.empty());
  ASSERT_EQ(merged.colors.size(), merged.positions.size());
  EXPECT_EQ(merged.colors.front(), 0.25f);
  EXPECT_EQ(merged.colors.back(), 1.0f);
  Mesh fromEmpty;
  appendMesh(fromEmpty, a);
  EXPECT_EQ(fromEmpty, a);
}

// A prop (untextured) appended to a textured character keeps the character's textures; two textured meshes with
// different layers keep both, the source's layer indices moved past the target's.
TEST(AppendMesh, KeepsTextureLayersOfEitherSide) {
  Mesh textured = tetrahedron();
  textured.layerGens = {TexGen{}};
  textured.layerImages = {0};
  textured.layers.assign(2 * textured.vertexCount(), -1);
  textured.layerWeights.assign(2 * textured.vertexCount(), 0.0f);
  textured.texcoords.assign(2 * textured.vertexCount(), 0.5f);
  for (size_t v = 0; v < textured.vertexCount(); ++v) textured.layers[2 * v] = 0, textured.layerWeights[2 * v] = 1.0f;

  Mesh withProp = textured;
  appendMesh(withProp, cube());
  ASSERT_TRUE(withProp.textured());
  ASSERT_EQ(withProp.layers.size(), 2 * withProp.vertexCount());
  ASSERT_EQ(withProp.layerWeights.size(), 2 * withProp.vertexCount());
  ASSERT_EQ(withProp.texcoords.size(), 2 * withProp.vertexCount());
  EXPECT_EQ(withProp.layers[0], 0);
  EXPECT_EQ(withProp.layers[2 * 4], -1);  // the cube's first vertex: no layer, weight 0
  EXPECT_EQ(withProp.layerWeights[2 * 4], 0.0f);

  Mesh propFirst = cube();
  appendMesh(propFirst, textured);
  ASSERT_EQ(propFirst.layers.size(), 2 * propFirst.vertexCount());
  EXPECT_EQ(propFirst.layers[0], -1);
  EXPECT_EQ(propFirst.layers[2 * 8], 0);

  Mesh other = textured;
  other.layerImages = {1};
  Mesh both = textured;
  appendMesh(both, other);
  ASSERT_EQ(both.layerGens.size(), 2u);
  EXPECT_EQ(both.layerImages, (std::vector<int32_t>{0, 1}));
  EXPECT_EQ(both.layers[0], 0);
  EXPECT_EQ(both.layers[2 * 4], 1);  // the second tetrahedron's layer follows the first's
  Mesh same = textured;
  appendMesh(same, textured);
  EXPECT_EQ(same.layerGens.size(), 1u);
  EXPECT_EQ(same.layers[2 * 4], 0);
}

}  // namespace
}  // namespace imps
