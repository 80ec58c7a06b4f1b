// SPDX-License-Identifier: MIT
// The tesselator's triangulation passes (imps/src/tesselator_mesh.cpp, declared in tesselator_state.h) one at a
// time: A vertices, B fans, C votes, D assembly, E hole repair and F pinches, each checked against its contract on
// particles spread evenly over a sphere, and the half-edge bookkeeping on hand-built meshes (a closed octahedron, one
// with a hole, a vertex pinched between two closed fans).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "imps/mesh.h"
#include "octahedron.h"
#include "tesselator_sphere.h"
#include "tesselator_state.h"

namespace imps {
namespace {

using test::kRadius;
using test::Sphere;

bool fanHolds(const Tesselator::State& s, uint32_t a, uint32_t b, uint32_t c) {
  const size_t m = s.fanCount[a];
  for (size_t k = 0; k < m; ++k)
    if (s.fan[a * kMaxFan + k] == int32_t(b) && s.fan[a * kMaxFan + (k + 1) % m] == int32_t(c)) return true;
  return false;
}

// Directed edges of s.tris: every one used once at most; returns those without a twin.
size_t openEdges(const Tesselator::State& s) {
  std::map<std::pair<uint32_t, uint32_t>, int> used;
  for (size_t t = 0; t < s.tris.size(); t += 3)
    for (size_t k = 0; k < 3; ++k) ++used[{s.tris[t + k], s.tris[t + (k + 1) % 3]}];
  size_t open = 0;
  for (const auto& [e, count] : used) {
    EXPECT_EQ(count, 1) << "directed edge " << e.first << " -> " << e.second << " used twice";
    open += used.count({e.second, e.first}) == 0;
  }
  return open;
}

// Replaces s's triangles by `tris` and builds the half-edge table from them as the assembly leaves it (every vertex
// flagged in s.openOut: a superset of those with an open outgoing edge, as the passes allow).
void setTriangles(Tesselator::State& s, const std::vector<uint32_t>& tris) {
  const size_t n = s.size();
  s.heTo.assign(n * kMaxHalfEdges, 0);
  s.heThird.assign(n * kMaxHalfEdges, 0);
  s.heCount.assign(n, 0);
  s.openOut.assign(n, 1);
  s.tris = tris;
  for (size_t t = 0; t < s.tris.size(); t += 3)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t a = s.tris[t + k], slot = uint32_t(a * kMaxHalfEdges + s.heCount[a]++);
      s.heTo[slot] = s.tris[t + (k + 1) % 3];
      s.heThird[slot] = s.tris[t + (k + 2) % 3];
    }
}

using Triangle = std::tuple<uint32_t, uint32_t, uint32_t>;

// Triangles as sets of rotations: (a, b, c), (b, c, a) and (c, a, b) are one triangle; (a, c, b) is another.
std::set<Triangle> triangleSet(const std::vector<uint32_t>& tris) {
  std::set<Triangle> out;
  for (size_t t = 0; t < tris.size(); t += 3) {
    const uint32_t* c = &tris[t];
    const size_t r = size_t(std::min_element(c, c + 3) - c);
    out.insert({c[r], c[(r + 1) % 3], c[(r + 2) % 3]});
  }
  return out;
}

TEST(TesselatorMesh, ProjectVerticesPutsEveryVertexOnTheSurfaceWithOutwardNormals) {
  Sphere sphere(600);
  auto& s = sphere.s;
  for (size_t i = 0; i < s.size(); ++i) s.pos[i] *= 1.02f;  // a little off the surface
  projectVertices(s, sphere.options);
  ASSERT_EQ(s.vpos.size(), s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    ASSERT_TRUE(s.vok[i]) << i;
    EXPECT_NEAR(glm::length(s.vpos[i]), kRadius, 1e-3f * sphere.options.desiredRadius) << i;
    EXPECT_GT(glm::dot(s.nrm[i], glm::normalize(s.vpos[i])), 0.9999f) << i;
    EXPECT_NEAR(s.vcol[i].z, 0.75f, 1e-5f) << "the only primitive's colour";
    EXPECT_EQ(s.cacheValue[i], sphere.field.value(s.pos[i])) << "the sample at the particle is kept";
  }
  EXPECT_TRUE(s.cacheValid);
}

TEST(TesselatorMesh, ProjectVerticesLeavesOutParticlesFarOffTheSurface) {
  Sphere sphere(600);
  sphere.s.pos[7] *= 1.0f + 2.0f * sphere.options.desiredRadius;  // beyond kVertexOff
  projectVertices(sphere.s, sphere.options);
  EXPECT_FALSE(sphere.s.vok[7]);
  EXPECT_TRUE(sphere.s.vok[8]);
}

TEST(TesselatorMesh, FansAreCounterClockwiseRingsOfNeighbours) {
  Sphere sphere(600);
  auto& s = sphere.s;
  projectVertices(s, sphere.options);
  buildFans(s, sphere.options);
  for (size_t i = 0; i < s.size(); ++i) {
    const size_t m = s.fanCount[i];
    ASSERT_GE(m, 4u) << i;
    ASSERT_LE(m, kMaxFan);
    std::set<int32_t> labels;
    for (size_t k = 0; k < m; ++k) {
      const int32_t a = s.fan[i * kMaxFan + k], b = s.fan[i * kMaxFan + (k + 1) % m];
      ASSERT_GE(a, 0) << "an evenly sampled sphere closes every cell with neighbours";
      EXPECT_NE(a, int32_t(i));
      labels.insert(a);
      const glm::vec3 ea = s.vpos[size_t(a)] - s.vpos[i], eb = s.vpos[size_t(b)] - s.vpos[i];
      EXPECT_GT(glm::dot(glm::cross(ea, eb), s.nrm[i]), 0.0f) << "counter-clockwise seen from outside, particle " << i;
      EXPECT_LT(glm::length(ea), kFanRadius * sphere.options.desiredRadius);
    }
    EXPECT_EQ(labels.size(), m) << "no label twice";
  }
}

TEST(TesselatorMesh, VotesEmitEachTriangleOnceWithItsCornersCount) {
  Sphere sphere(600);
  auto& s = sphere.s;
  sphere.fansAndVotes();
  std::set<std::tuple<uint32_t, uint32_t, uint32_t>> emitted;  // rotated so the smallest corner comes first
  size_t unanimous = 0;
  for (uint32_t i = 0; i < s.size(); ++i)
    for (size_t k = 0; k < s.candCount[i]; ++k) {
      const uint32_t* slot = &s.cand[(size_t(i) * kMaxFan + k) * 3];
      const uint32_t a = slot[0], b = slot[1];
      ASSERT_TRUE(fanHolds(s, i, a, b)) << "the emitter proposes it";
      const bool byA = fanHolds(s, a, b, i), byB = fanHolds(s, b, i, a);
      EXPECT_EQ(slot[2], 1u + byA + byB) << "votes: the corners whose fans hold it";
      EXPECT_TRUE(!(byA && a < i) && !(byB && b < i)) << "emitted by its smallest proposer";
      EXPECT_TRUE(s.candVotes[i] >> slot[2] & 1u);
      const uint32_t lo = std::min({i, a, b});
      const auto key = lo == i ? std::tuple(i, a, b) : lo == a ? std::tuple(a, b, i) : std::tuple(b, i, a);
      EXPECT_TRUE(emitted.insert(key).second) << "emitted twice";
      unanimous += slot[2] == 3;
    }
  size_t counted = 0;
  for (size_t c = 1; c < s.chunkUnanimous.size(); ++c) counted += s.chunkUnanimous[c];
  EXPECT_EQ(counted, unanimous);
  EXPECT_GT(unanimous, s.size()) << "on an even sampling most triangles are unanimous (about 2 per particle)";
}

TEST(TesselatorMesh, AssemblyNeverReusesADirectedEdgeAndCountsTheBoundary) {
  for (int threads : {1, 2}) {
    Sphere sphere(600, threads);
    auto& s = sphere.s;
    sphere.fansAndVotes();
    const size_t boundary = assembleTriangles(s, sphere.options);
    EXPECT_EQ(boundary, openEdges(s));
    EXPECT_GT(s.tris.size() / 3, 2 * s.size() - 40) << "nearly closed already (a sphere has 2n - 4)";
    for (size_t i = 0; i < s.size(); ++i) {
      size_t outgoing = 0;
      for (size_t t = 0; t < s.tris.size(); ++t) outgoing += s.tris[t] == i;
      EXPECT_EQ(s.heCount[i], outgoing) << "the half-edge table holds every outgoing edge of " << i;
    }
  }
}

// After passes A-C: every candidate triangle with a corner marked is withdrawn (no votes), so the assembly leaves the
// marked particles out. (A fan-repeat flag sends it down its sequential path, which reads only the candidates.)
void withdrawAround(Sphere& sphere, const std::vector<uint8_t>& marked) {
  auto& s = sphere.s;
  for (uint32_t i = 0; i < s.size(); ++i)
    for (size_t k = 0; k < s.candCount[i]; ++k) {
      uint32_t* slot = &s.cand[(size_t(i) * kMaxFan + k) * 3];
      if (marked[i] || marked[slot[0]] || marked[slot[1]]) slot[2] = 0;
    }
  s.fanRepeat[0] = 1;
}

// Passes A-C, then a hole of about six edges around each of the given particles.
void punchHoles(Sphere& sphere, std::initializer_list<uint32_t> centres) {
  sphere.fansAndVotes();
  std::vector<uint8_t> marked(sphere.s.size(), 0);
  for (uint32_t c : centres)
    if (c < marked.size()) marked[c] = 1;
  withdrawAround(sphere, marked);
}

// Passes A-C, then every triangle touching a particle of the band |z| < desiredRadius / 2 round the equator withdrawn
// and the rest assembled: two caps whose rims face each other across the band (as a neck or wrist whose ring of
// particles made no triangle). Returns the band's particle count; `boundary` gets the assembly's open edges.
size_t assembleWithoutEquator(Sphere& sphere, size_t& boundary) {
  auto& s = sphere.s;
  sphere.fansAndVotes();
  std::vector<uint8_t> inBand(s.size(), 0);
  size_t banded = 0;
  for (uint32_t i = 0; i < s.size(); ++i) banded += inBand[i] = std::fabs(s.vpos[i].z) < 0.5f * sphere.options.desiredRadius;
  withdrawAround(sphere, inBand);
  boundary = assembleTriangles(s, sphere.options);
  return banded;
}

// The topology of the mesh pass G would write from s.
MeshTopology topologyOf(const Sphere& sphere) {
  Mesh mesh;
  writeMesh(sphere.s, sphere.options, mesh);
  return analyzeTopology(mesh);
}

TEST(TesselatorMesh, HoleRepairClosesTheHolesAroundMissingTriangles) {
  Sphere sphere(600);
  auto& s = sphere.s;
  punchHoles(sphere, {5, 300, 301});
  size_t boundary = assembleTriangles(s, sphere.options);
  ASSERT_GE(boundary, 9u) << "holes to repair (two of the three may share one)";
  EXPECT_EQ(boundary, openEdges(s));
  const size_t assembled = s.tris.size() / 3;
  const size_t unfilled = repairHoles(s, sphere.options, boundary);
  EXPECT_EQ(unfilled, 0u);
  EXPECT_EQ(boundary, 0u);
  EXPECT_EQ(openEdges(s), 0u);
  EXPECT_GT(s.tris.size() / 3, assembled);
  Mesh mesh;
  writeMesh(s, sphere.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.orientationConflicts, 0u);
  EXPECT_LE(t.unusedVertices, 3u) << "at most the three centres are left out";
}

TEST(TesselatorMesh, RepairLeavesLoopsLongerThanMaxHoleLoopOpen) {
  Sphere sphere(600);
  auto& s = sphere.s;
  sphere.options.maxHoleLoop = 3;
  punchHoles(sphere, {5});  // a hole of about six edges
  size_t boundary = assembleTriangles(s, sphere.options);
  ASSERT_GT(boundary, 3u);
  EXPECT_GT(repairHoles(s, sphere.options, boundary), 0u);
  EXPECT_GT(boundary, 0u);
  EXPECT_EQ(boundary, openEdges(s));
}

// E, tubes: every triangle touching a particle of a band round the sphere's equator is withdrawn, so the assembly
// leaves two caps whose rims face each other across the band (as a neck or wrist whose ring of particles made no
// triangle). Capping each rim would mesh the sphere as two pieces; the repair joins the rims by a strip and the sphere
// stays one closed surface of Euler characteristic 2, every strip triangle near the surface.
TEST(TesselatorMesh, HoleRepairJoinsTheTwoRimsOfATubeInsteadOfCappingThem) {
  Sphere sphere(300);
  auto& s = sphere.s;
  const float h = sphere.options.desiredRadius;
  size_t boundary = 0;
  const size_t banded = assembleWithoutEquator(sphere, boundary);
  ASSERT_GT(banded, 5u);
  ASSERT_EQ(topologyOf(sphere).components, 2u) << "the band cuts the sphere in two";
  const size_t assembled = s.tris.size() / 3;
  EXPECT_EQ(repairHoles(s, sphere.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  Mesh mesh;
  writeMesh(s, sphere.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.nonManifoldVertices, 0u);
  EXPECT_EQ(t.orientationConflicts, 0u);
  EXPECT_EQ(t.components, 1u) << "the rims were capped: the sphere is meshed as two pieces";
  EXPECT_EQ(t.eulerCharacteristic, 2);
  EXPECT_EQ(t.unusedVertices, banded) << "only the band's particles are left out";
  for (size_t k = assembled; k < s.tris.size() / 3; ++k) {  // the strip: outward, and near the sphere
    const glm::vec3 a = s.vpos[s.tris[3 * k]], b = s.vpos[s.tris[3 * k + 1]], c = s.vpos[s.tris[3 * k + 2]];
    const glm::vec3 centroid = (a + b + c) / 3.0f;
    EXPECT_GT(glm::dot(glm::cross(b - a, c - a), centroid), 0.0f) << "strip triangle " << k << " faces inward";
    EXPECT_LT(kRadius - glm::length(centroid), 0.5f * h) << "strip triangle " << k;
  }
}

// E, tube rims on pieces that touch at one vertex: the sphere's two caps of the test above, with the south pole's
// particle merged into the north pole's (the lower cap's fan at it now has that corner too: a vertex with two fans, as
// where the repair's caps met at the biped's chin). The caps are still two pieces across their edges, so the rims are
// joined by a strip; pass F then cuts the pinch, and the sphere stays one closed surface (capping the rims would have
// left two).
TEST(TesselatorMesh, HoleRepairJoinsTubeRimsWhosePiecesTouchOnlyAtAVertex) {
  Sphere sphere(300);
  auto& s = sphere.s;
  size_t boundary = 0;
  assembleWithoutEquator(sphere, boundary);
  uint32_t north = 0, south = 0;
  for (uint32_t i = 0; i < s.size(); ++i) {
    if (s.vpos[i].z > s.vpos[north].z) north = i;
    if (s.vpos[i].z < s.vpos[south].z) south = i;
  }
  std::vector<uint32_t> tris = s.tris;
  std::replace(tris.begin(), tris.end(), south, north);
  setTriangles(s, tris);
  boundary = openEdges(s);
  ASSERT_EQ(markPinchedVertices(s, sphere.options), 1u) << "the poles' merge is the one pinch";
  size_t unfilled = repairHoles(s, sphere.options, boundary);
  EXPECT_EQ(unfilled, 0u);
  EXPECT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  EXPECT_EQ(boundary, 0u);
  const MeshTopology t = topologyOf(sphere);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 1u) << "the rims were capped: the sphere is meshed as two pieces";
}

// F, a pinch that is all that joins two pieces: the sphere's band withdrawn as above, but each half capped on its own
// (as when the repair saw no partner for either rim), and a vertex of the lower cap merged into the upper cap's
// nearest: two fans at it, on two pieces. Cutting the smaller fan would leave the halves apart; pass F takes every
// triangle round the pinch instead, so that the repair joins the two holes there as the rims of a tube: one closed
// surface.
TEST(TesselatorMesh, APinchThatIsAllThatJoinsTwoPiecesIsOpenedAndTheHolesJoined) {
  Sphere sphere(300);
  auto& s = sphere.s;
  size_t assembledBoundary = 0;
  assembleWithoutEquator(sphere, assembledBoundary);
  const std::vector<uint32_t> assembled = s.tris;
  std::vector<uint32_t> halves[2];  // each half, capped alone
  for (int upper = 0; upper < 2; ++upper) {
    std::vector<uint32_t> half;
    for (size_t t = 0; t < assembled.size(); t += 3)
      if ((s.vpos[assembled[t]].z > 0.0f) == (upper == 1)) half.insert(half.end(), &assembled[t], &assembled[t] + 3);
    // Its one hole loop (each open edge a -> b gives the hole edge b -> a), capped by a zigzag (no vertex gets more
    // than a few of the cap's triangles: the half-edge table has room for kMaxHalfEdges).
    std::map<uint32_t, uint32_t> hole;
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (size_t t = 0; t < half.size(); t += 3)
      for (size_t k = 0; k < 3; ++k) edges.insert({half[t + k], half[t + (k + 1) % 3]});
    for (const auto& [a, b] : edges)
      if (!edges.count({b, a})) hole[b] = a;
    ASSERT_GE(hole.size(), 3u);
    std::vector<uint32_t> loop{hole.begin()->first};
    while (hole.at(loop.back()) != loop.front()) loop.push_back(hole.at(loop.back()));
    ASSERT_EQ(loop.size(), hole.size()) << "one hole loop";
    for (size_t l = 0, r = loop.size() - 1, k = 0; r - l >= 2; ++k)
      if (k % 2 == 0) {
        half.insert(half.end(), {loop[l], loop[l + 1], loop[r]});
        ++l;
      } else {
        half.insert(half.end(), {loop[l], loop[r - 1], loop[r]});
        --r;
      }
    halves[upper] = half;
  }
  size_t pinchedBefore = 0;  // (the assembly beside the band leaves a few pinches of its own, within each half)
  {
    std::vector<uint32_t> both = halves[1];
    both.insert(both.end(), halves[0].begin(), halves[0].end());
    setTriangles(s, both);
    ASSERT_EQ(openEdges(s), 0u);
    pinchedBefore = markPinchedVertices(s, sphere.options);
  }
  // The upper piece's lowest vertex and the lower piece's highest: the lower's merged into the upper's.
  uint32_t top = halves[1][0], bottom = halves[0][0];
  for (uint32_t v : halves[1]) top = s.vpos[v].z < s.vpos[top].z ? v : top;
  for (uint32_t v : halves[0]) bottom = s.vpos[v].z > s.vpos[bottom].z ? v : bottom;
  std::replace(halves[0].begin(), halves[0].end(), bottom, top);
  std::vector<uint32_t> both = halves[1];
  both.insert(both.end(), halves[0].begin(), halves[0].end());
  setTriangles(s, both);
  size_t boundary = openEdges(s), unfilled = 0;
  ASSERT_EQ(boundary, 0u);
  ASSERT_EQ(markPinchedVertices(s, sphere.options), pinchedBefore + 1) << "the merged vertex is one more pinch";
  EXPECT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  EXPECT_EQ(boundary, 0u);
  const MeshTopology t = topologyOf(sphere);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 1u) << "the pinch's smaller fan was cut: the halves are apart";
}

// E, a rim facing two pieces: a body (a unit metaball) with two heads (metaballs of radius 0.35 at x = +-0.6, z = 1.1,
// all blended) whose particles are withdrawn from z = 0.7 to 1.05: the body's one hole faces both heads' rims, on two
// more pieces. Joined greedily, the nearer head takes the whole hole and the other is capped apart; the repair splits
// the body's rim by a chord into one half for each head (forkTube) and the surface stays one closed piece.
TEST(TesselatorMesh, HoleRepairSplitsARimFacingTwoPiecesBetweenThem) {
  BlendFunction blend;
  blend.defaultParam = -3.0f;
  const Field field({Primitive::metaball(glm::vec3(0.0f), 1.0f), Primitive::metaball(glm::vec3(-0.6f, 0, 1.1f), 0.35f),
                     Primitive::metaball(glm::vec3(0.6f, 0, 1.1f), 0.35f)},
                    {-3.0f, -3.0f, -3.0f}, {glm::vec3(0.5f), glm::vec3(0.5f), glm::vec3(0.5f)}, blend,
                    BlendSets::all(3));
  const size_t n = 600;
  const float spacing = 0.5f * test::sphereOptions(n).desiredRadius;
  std::vector<glm::vec3> points;  // each ball's Fibonacci points moved onto the surface, none closer than `spacing`
  for (const auto& [centre, radius] : {std::pair{glm::vec3(0.0f), 1.0f}, std::pair{glm::vec3(-0.6f, 0, 1.1f), 0.35f},
                                       std::pair{glm::vec3(0.6f, 0, 1.1f), 0.35f}})
    for (const glm::vec3& p : test::fibonacciSphere(size_t(float(n) * radius * radius))) {
      glm::vec3 q = centre + radius * p;
      for (int it = 0; it < 20; ++it) {
        const FieldSample fs = field.sample(q);
        const float g2 = glm::dot(fs.gradient, fs.gradient);
        if (!(g2 > 1e-12f)) break;
        q += (1.0f - fs.value) / g2 * fs.gradient;
      }
      const bool near = std::ranges::any_of(points, [&](const glm::vec3& o) { return glm::length(o - q) < spacing; });
      if (std::fabs(field.value(q) - 1.0f) < 1e-3f && !near && (q.z < 0.7f || q.z > 1.05f)) points.push_back(q);
    }
  Sphere body(points, test::sphereOptions(n));
  body.field = field;
  auto& s = body.s;
  s.field = &body.field;
  body.fansAndVotes();
  size_t boundary = assembleTriangles(s, body.options);
  ASSERT_EQ(topologyOf(body).components, 3u) << "the body and the two heads are meshed apart";
  size_t unfilled = repairHoles(s, body.options, boundary);
  EXPECT_EQ(unfilled, 0u);
  EXPECT_EQ(unpinchVertices(s, body.options, boundary, unfilled), 0u);
  EXPECT_EQ(boundary, 0u);
  const MeshTopology t = topologyOf(body);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 1u) << "a head was capped apart";
  EXPECT_EQ(t.eulerCharacteristic, 2);
}

// E, surface rows: a peanut (two unit metaballs a distance 2 apart, blended: a waist of radius 0.29 between lobes of
// radius 1) with particles on the lobes only, none within 0.8 of the waist's plane. The rims (radius 0.98, 1.6 apart,
// nine desiredRadius) are too far apart for one strip (it would pass 0.7 outside the waist) and there are no particles
// between them for rows of their own: the repair joins them through rows of new vertices on the surface, and the
// peanut stays one closed surface whose every vertex lies on it. (Without the surface rows: two pieces.)
TEST(TesselatorMesh, HoleRepairJoinsRimsWithNoParticlesBetweenThroughSurfaceRows) {
  const size_t perLobe = 400;
  std::vector<glm::vec3> points;
  for (const float side : {-1.0f, 1.0f})
    for (const glm::vec3& p : test::fibonacciSphere(perLobe)) {
      const glm::vec3 q = p + glm::vec3(side, 0.0f, 0.0f);
      if (q.x * side > 0.8f) points.push_back(q);  // the lobe's far side, clear of the waist
    }
  Sphere peanut(points, test::sphereOptions(perLobe));
  BlendFunction blend;
  blend.defaultParam = -8.0f;
  peanut.field =
      Field({Primitive::metaball(glm::vec3(-1, 0, 0), kRadius), Primitive::metaball(glm::vec3(1, 0, 0), kRadius)},
            {-8.0f, -8.0f}, {glm::vec3(0.5f), glm::vec3(0.5f)}, blend, BlendSets::all(2));
  auto& s = peanut.s;
  s.field = &peanut.field;
  const float h = peanut.options.desiredRadius;
  peanut.fansAndVotes();
  size_t boundary = assembleTriangles(s, peanut.options);
  {
    Mesh before;
    writeMesh(s, peanut.options, before);
    ASSERT_EQ(analyzeTopology(before).components, 2u) << "the lobes are meshed apart";
  }
  const size_t particles = s.size(), assembled = s.tris.size() / 3;
  EXPECT_EQ(repairHoles(s, peanut.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  ASSERT_GT(s.vertexCount(), particles) << "no surface rows were added";
  EXPECT_EQ(s.addedFrom.size(), s.vertexCount() - particles);
  for (uint32_t p : s.addedFrom) EXPECT_LT(p, particles) << "a surface-row vertex follows a particle";
  Mesh mesh;
  writeMesh(s, peanut.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(t.components, 1u) << "the rims were capped: the peanut is meshed as two pieces";
  EXPECT_EQ(t.eulerCharacteristic, 2);
  EXPECT_EQ(mesh.vertexCount(), s.vertexCount());
  for (size_t v = particles; v < mesh.vertexCount(); ++v) {  // on the surface, outward normals, the field's colour
    const FieldSample fs = peanut.field.sample(mesh.position(v));
    EXPECT_LT(std::fabs(fs.value - 1.0f) / glm::length(fs.gradient), 1e-3f * h) << "vertex " << v;
    EXPECT_GT(glm::dot(mesh.normal(v), -glm::normalize(fs.gradient)), 0.999f) << "vertex " << v;
    EXPECT_EQ(mesh.color(v), glm::vec3(0.5f)) << "vertex " << v;
  }
  size_t waist = 0;
  for (size_t k = assembled; k < s.tris.size() / 3; ++k) {  // the strips: outward, and near the surface
    const glm::vec3 a = s.vpos[s.tris[3 * k]], b = s.vpos[s.tris[3 * k + 1]], c = s.vpos[s.tris[3 * k + 2]];
    const glm::vec3 centroid = (a + b + c) / 3.0f;
    const FieldSample fs = peanut.field.sample(centroid);
    EXPECT_LT(glm::dot(glm::cross(b - a, c - a), fs.gradient), 0.0f) << "strip triangle " << k << " faces inward";
    EXPECT_LT(std::fabs(fs.value - 1.0f) / glm::length(fs.gradient), 2.0f * h) << "strip triangle " << k;
    waist += std::fabs(centroid.x) < 0.1f;
  }
  EXPECT_GT(waist, 0u) << "no triangle runs round the waist";
}

// ... but two holes that face each other on two bodies (two spheres 0.1 apart, the holes on their facing sides) are not
// the rims of a tube: the air between them is no solid to join across. Each is capped; the bodies stay two.
TEST(TesselatorMesh, HoleRepairDoesNotJoinHolesFacingEachOtherAcrossAGap) {
  const size_t n = 300;
  const float gap = 0.1f, shift = kRadius + 0.5f * gap;
  std::vector<glm::vec3> points;
  for (const float side : {-1.0f, 1.0f})
    for (const glm::vec3& p : test::fibonacciSphere(n)) points.push_back(p + glm::vec3(side * shift, 0.0f, 0.0f));
  Sphere two(points, test::sphereOptions(n));
  BlendFunction blend;
  blend.defaultParam = -8.0f;
  two.field = Field(
      {Primitive::metaball(glm::vec3(-shift, 0, 0), kRadius), Primitive::metaball(glm::vec3(shift, 0, 0), kRadius)},
      {-8.0f, -8.0f}, {glm::vec3(0.5f), glm::vec3(0.5f)}, blend, BlendSets::all(2));
  auto& s = two.s;
  s.field = &two.field;
  const float h = two.options.desiredRadius;
  two.fansAndVotes();
  std::vector<uint8_t> facing(s.size(), 0);  // the particles within 0.3 h of the gap, on either sphere
  for (uint32_t i = 0; i < s.size(); ++i) facing[i] = std::fabs(s.vpos[i].x) < 0.5f * gap + 0.3f * h;
  withdrawAround(two, facing);
  size_t boundary = assembleTriangles(s, two.options);
  ASSERT_GT(boundary, 6u);
  EXPECT_EQ(repairHoles(s, two.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  Mesh mesh;
  writeMesh(s, two.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.components, 2u) << "the two spheres were joined across the gap";
  for (size_t k = 0; k < s.tris.size(); k += 3)  // no triangle spans the gap
    EXPECT_GT(s.vpos[s.tris[k]].x * s.vpos[s.tris[k + 1]].x, 0.0f);
}

// Pass I on a blob: four particles on a sphere (neighbours 109 degrees apart) are beyond even the fans' convex band, so
// A-F leave them without a triangle; closePockets gives them their hull, a tetrahedron facing outward.
TEST(TesselatorMesh, ABlobOfFourParticlesGetsItsHull) {
  Sphere blob(4);
  auto& s = blob.s;
  blob.fansAndVotes();
  size_t boundary = assembleTriangles(s, blob.options);
  size_t unfilled = repairHoles(s, blob.options, boundary);
  unpinchVertices(s, blob.options, boundary, unfilled);
  ASSERT_EQ(s.tris.size(), 0u) << "the fans must leave the blob for pass I to mean anything";
  EXPECT_EQ(closePockets(s, blob.options, boundary), 1u);
  Mesh mesh;
  writeMesh(s, blob.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold());
  EXPECT_EQ(mesh.triangleCount(), 4u);
  EXPECT_EQ(t.unusedVertices, 0u);
  EXPECT_GT(signedVolume(mesh), 0.0) << "a blob's surface faces outward";
}

// Pass I (closePockets; the pocket it closes: Tesselator.AnAirPocketInsideTheSwarmIsMeshedInsideOut). Particles left
// without a triangle in a hole of a larger surface are not a sheet of their own (they are joined, by chords behind
// both tangent planes through the solid, to particles in triangles): pass I leaves them to the repair.
TEST(TesselatorMesh, ParticlesInAHoleOfALargerSurfaceAreNoPocket) {
  Sphere sphere(300);
  auto& s = sphere.s;
  sphere.options.maxHoleLoop = 0;  // the hole stays
  std::vector<uint8_t> marked(s.size(), 0);
  size_t capped = 0;
  for (uint32_t i = 0; i < s.size(); ++i) capped += marked[i] = s.pos[i].z > 0.9f;  // a cap
  ASSERT_GE(capped, 4u);
  ASSERT_LE(capped, kMaxPocket) << "small enough to be a pocket by its size";
  sphere.fansAndVotes();
  withdrawAround(sphere, marked);
  size_t boundary = assembleTriangles(s, sphere.options);
  ASSERT_GT(boundary, 0u);
  const size_t before = s.tris.size();
  EXPECT_EQ(closePockets(s, sphere.options, boundary), 0u);
  EXPECT_EQ(s.tris.size(), before);
}

// F: a vertex whose triangles form two fans of one piece (the closed sphere with a particle of its southern half merged
// into its north pole's: every edge has its twin, yet the mesh is pinched there) is found, the smaller fan's slots are
// marked, and the pass leaves no pinched vertex, with the larger fan untouched.
TEST(TesselatorMesh, PinchedVertexLosesItsSmallerFan) {
  Sphere sphere(300);
  auto& s = sphere.s;
  sphere.fansAndVotes();
  size_t boundary = assembleTriangles(s, sphere.options), unfilled = repairHoles(s, sphere.options, boundary);
  ASSERT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  ASSERT_EQ(boundary, 0u) << "a closed sphere to start from";
  // The north pole, and the southernmost vertex with another number of triangles.
  uint32_t north = 0;
  for (uint32_t i = 0; i < s.size(); ++i) north = s.vpos[i].z > s.vpos[north].z ? i : north;
  uint32_t south = north;
  for (uint32_t i = 0; i < s.size(); ++i)
    if (s.heCount[i] != s.heCount[north] && (south == north || s.vpos[i].z < s.vpos[south].z)) south = i;
  ASSERT_LT(s.vpos[south].z, 0.0f);
  std::vector<uint32_t> tris = s.tris, northFan, southFan;
  for (size_t t = 0; t < tris.size(); t += 3)
    for (const auto& [pole, fan] : {std::pair{north, &northFan}, std::pair{south, &southFan}})
      if (tris[t] == pole || tris[t + 1] == pole || tris[t + 2] == pole)
        fan->insert(fan->end(), &tris[t], &tris[t] + 3);
  std::replace(tris.begin(), tris.end(), south, north);
  setTriangles(s, tris);
  ASSERT_EQ(markPinchedVertices(s, sphere.options), 1u);
  EXPECT_TRUE(s.openUp[north]);
  const bool northLarger = northFan.size() > southFan.size();
  size_t dropped = 0;
  for (size_t k = 0; k < s.heCount[north]; ++k) dropped += s.dropSlot[size_t(north) * kMaxHalfEdges + k];
  EXPECT_EQ(dropped, (northLarger ? southFan : northFan).size() / 3) << "only the smaller fan's slots are marked";
  EXPECT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  EXPECT_EQ(boundary, 0u);
  std::vector<uint32_t> larger = northLarger ? northFan : southFan;
  if (!northLarger) std::replace(larger.begin(), larger.end(), south, north);
  const auto left = triangleSet(s.tris);
  for (const auto& t : triangleSet(larger)) EXPECT_TRUE(left.count(t)) << "a triangle of the larger fan is gone";
}

// F: a vertex whose fans lie on two closed bodies (a square pyramid and a tetrahedron sharing their apex 0) is all that
// joins them: every triangle round it goes (not only the smaller fan's), the repair closes what is left, and no
// pinched vertex remains; vertex 0 is in no triangle any more.
TEST(TesselatorMesh, APinchBetweenTwoBodiesLosesEveryTriangleRoundIt) {
  Sphere sphere(600);
  auto& s = sphere.s;
  projectVertices(s, sphere.options);
  const std::vector<uint32_t> pyramid = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 1, 4, 3, 1, 3, 2};
  const std::vector<uint32_t> tetrahedron = {0, 5, 6, 0, 6, 7, 0, 7, 5, 5, 7, 6};
  std::vector<uint32_t> both = pyramid;
  both.insert(both.end(), tetrahedron.begin(), tetrahedron.end());
  setTriangles(s, both);
  ASSERT_EQ(markPinchedVertices(s, sphere.options), 1u);
  EXPECT_TRUE(s.openUp[0]);
  size_t boundary = 0, unfilled = 0;
  EXPECT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  EXPECT_EQ(boundary, 0u);
  EXPECT_EQ(markPinchedVertices(s, sphere.options), 0u);
  for (size_t t = 0; t < s.tris.size(); t += 3)
    EXPECT_FALSE(s.tris[t] == 0 || s.tris[t + 1] == 0 || s.tris[t + 2] == 0) << "a triangle at the pinch is left";
  Mesh mesh;
  writeMesh(s, sphere.options, mesh);
  EXPECT_TRUE(analyzeTopology(mesh).closedManifold());
}

// ---- Hand-built meshes: the octahedron on the unit sphere (vertices +x -x +y -y +z -z) --------------------------

struct Octahedron : Sphere {
  std::vector<uint32_t> corner;  // the particle at each axis point (findNeighbours sorts the particles)
  Octahedron() : Sphere({{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}}, test::sphereOptions(6)) {
    projectVertices(s, options);
    for (const glm::vec3& axis : test::octahedronAxes())
      for (uint32_t i = 0; i < s.size(); ++i)
        if (glm::length(s.pos[i] - axis) < 1e-3f) corner.push_back(i);
    EXPECT_EQ(corner.size(), 6u);
  }
  // Triangles over axis points (0..5: +x -x +y -y +z -z) as triangles over particles.
  std::vector<uint32_t> particles(const std::vector<uint32_t>& axisTris) const {
    std::vector<uint32_t> out;
    for (uint32_t a : axisTris) out.push_back(corner[a]);
    return out;
  }
  std::vector<uint32_t> faces() const { return particles(test::octahedronFaces()); }
  // The octahedron without the given faces (over axis points, each as triangleSet writes it: its smallest corner
  // first).
  void buildWithout(const std::set<Triangle>& missing) {
    std::vector<uint32_t> kept;
    const std::vector<uint32_t> all = test::octahedronFaces();
    for (size_t t = 0; t < all.size(); t += 3) {
      const std::vector<uint32_t> face(all.begin() + long(t), all.begin() + long(t) + 3);
      if (!missing.count(*triangleSet(face).begin())) kept.insert(kept.end(), face.begin(), face.end());
    }
    ASSERT_EQ(kept.size(), all.size() - 3 * missing.size()) << "every missing face is an octahedron face";
    setTriangles(s, particles(kept));
  }
};

TEST(TesselatorMesh, OctahedronFacesAreOutwardAndClosed) {
  // The test's own construction, checked before the passes are: outward windings, every directed edge twinned.
  Octahedron o;
  const std::vector<uint32_t> faces = o.faces();
  for (size_t t = 0; t < faces.size(); t += 3) {
    const glm::vec3 a = o.s.vpos[faces[t]], b = o.s.vpos[faces[t + 1]], c = o.s.vpos[faces[t + 2]];
    EXPECT_GT(glm::dot(glm::cross(b - a, c - a), a + b + c), 0.0f) << "face " << t / 3;
  }
  setTriangles(o.s, faces);
  EXPECT_EQ(openEdges(o.s), 0u);
}

// Pass J's count: the pieces of the triangulation (triangles joined by corners) that face outward. The octahedron is
// one; the same octahedron turned inside out (an air pocket's hull) is none; a second octahedron beside it, apart, is
// a second piece, and its inside-out copy inside the first (a pocket in it) is none.
TEST(TesselatorMesh, SolidPiecesCountsTheOutwardPiecesOnly) {
  Octahedron o;
  setTriangles(o.s, o.faces());
  EXPECT_EQ(solidPieces(o.s), 1u);
  std::vector<uint32_t> inward = o.faces();
  for (size_t t = 0; t < inward.size(); t += 3) std::swap(inward[t + 1], inward[t + 2]);
  o.s.tris = inward;
  EXPECT_EQ(solidPieces(o.s), 0u) << "an inside-out piece is no solid";
  // Six more vertices (as the hole repair's surface rows add them): a second octahedron, at 3 along x or inside.
  const std::vector<uint32_t> faces = o.faces();
  for (const glm::vec3 centre : {glm::vec3(3, 0, 0), glm::vec3(0, 0, 0)}) {
    o.s.vpos.resize(o.s.size());
    for (uint32_t c : o.corner) o.s.vpos.push_back(centre + 0.5f * o.s.vpos[c]);
    std::vector<uint32_t> tris = faces;
    for (size_t t = 0; t < faces.size(); t += 3) {
      uint32_t second[3];
      for (size_t k = 0; k < 3; ++k)
        second[k] = uint32_t(o.s.size()) +
                    uint32_t(std::find(o.corner.begin(), o.corner.end(), faces[t + k]) - o.corner.begin());
      const bool pocket = centre == glm::vec3(0.0f);  // inside the first: turned inside out, as pass I orients it
      tris.insert(tris.end(), {second[0], pocket ? second[2] : second[1], pocket ? second[1] : second[2]});
    }
    o.s.tris = tris;
    EXPECT_EQ(solidPieces(o.s), centre.x > 0.0f ? 2u : 1u) << "a second octahedron at x = " << centre.x;
  }
}

TEST(TesselatorMesh, ClosedMeshHasNoPinchAndRepairLeavesItAlone) {
  Octahedron o;
  setTriangles(o.s, o.faces());
  EXPECT_EQ(markPinchedVertices(o.s, o.options), 0u) << "every vertex's four triangles form one disk";
  size_t boundary = 0;
  EXPECT_EQ(repairHoles(o.s, o.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  EXPECT_EQ(triangleSet(o.s.tris), triangleSet(o.faces()));
  size_t unfilled = 0;
  EXPECT_EQ(unpinchVertices(o.s, o.options, boundary, unfilled), 0u);
  EXPECT_EQ(o.s.tris.size(), o.faces().size()) << "nothing to unpinch: no triangle removed";
}

TEST(TesselatorMesh, ATriangularHoleIsClosedWithTheMissingFace) {
  Octahedron o;
  o.buildWithout({{0, 2, 4}});
  size_t boundary = openEdges(o.s);
  ASSERT_EQ(boundary, 3u);
  EXPECT_EQ(markPinchedVertices(o.s, o.options), 0u) << "a half-disk on the boundary is not a pinch";
  EXPECT_EQ(repairHoles(o.s, o.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  EXPECT_EQ(openEdges(o.s), 0u);
  EXPECT_EQ(triangleSet(o.s.tris), triangleSet(o.faces())) << "the only face that closes it, wound outward";
  for (uint32_t v : o.corner) EXPECT_EQ(o.s.heCount[v], 4u) << "the half-edge table follows the new face";
}

TEST(TesselatorMesh, ASquareHoleIsClosedByTwoOutwardTriangles) {
  Octahedron o;
  o.buildWithout({{0, 2, 4}, {0, 5, 2}});  // the two faces on edge +x +y: a loop 0 4 2 5 ... of four edges
  size_t boundary = openEdges(o.s);
  ASSERT_EQ(boundary, 4u);
  EXPECT_EQ(repairHoles(o.s, o.options, boundary), 0u);
  EXPECT_EQ(boundary, 0u);
  EXPECT_EQ(openEdges(o.s), 0u);
  ASSERT_EQ(o.s.tris.size(), 8u * 3);
  for (size_t t = 0; t < o.s.tris.size(); t += 3) {
    const glm::vec3 a = o.s.vpos[o.s.tris[t]], b = o.s.vpos[o.s.tris[t + 1]], c = o.s.vpos[o.s.tris[t + 2]];
    EXPECT_GT(glm::dot(glm::cross(b - a, c - a), a + b + c), 0.0f) << "triangle " << t / 3 << " faces outward";
  }
  Mesh mesh;
  writeMesh(o.s, o.options, mesh);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_EQ(t.boundaryEdges, 0u);
  EXPECT_EQ(t.nonManifoldEdges, 0u);
  EXPECT_EQ(t.orientationConflicts, 0u);
  EXPECT_EQ(t.eulerCharacteristic, 2) << "a sphere";
  EXPECT_EQ(mesh.vertexCount(), 6u) << "writeMesh: one vertex per particle";
}

}  // namespace
}  // namespace imps
