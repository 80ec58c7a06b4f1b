// The particle tesselator's passes one at a time (imps/src/tesselator_state.h): the triangulation's vertices, fans,
// votes, assembly and hole repair, and the update's compute, integration and add/delete phases, each checked
// against its contract on particles spread evenly over a sphere; and settle()'s cancel flag and progress callback.
#include "tesselator_state.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <set>
#include <thread>
#include <tuple>

#include "examples.h"
#include "imps/mesh.h"
#include "imps/skeleton_cache.h"

namespace imps {
namespace {

constexpr float kRadius = 1.0f;

// A lone metaball of radius 1 with a very hard blend: its surface is exactly the unit sphere.
Field sphereField() {
  BlendFunction blend;
  blend.defaultParam = -8.0f;
  return Field({Primitive::metaball(glm::vec3(0.0f), kRadius)}, {-8.0f}, {glm::vec3(0.25f, 0.5f, 0.75f)}, blend,
               BlendSets::all(1));
}

// Options for about n particles on the unit sphere.
TesselatorOptions sphereOptions(size_t n) {
  TesselatorOptions o;
  o.desiredRadius = std::sqrt(4.0f * 3.14159265f / (0.8660254f * float(n)));
  o.queryRadius = 2.5f * o.desiredRadius;
  o.cubeSize = o.queryRadius;
  o.bitsPerDim = 7;
  return o;
}

// n particles on the sphere (a Fibonacci spiral: even spacing), with neighbour lists, ready for the passes.
struct Sphere {
  Field field = sphereField();
  TesselatorOptions options;
  Tesselator::State s;
  explicit Sphere(size_t n, int threads = 1) : options(sphereOptions(n)), s(options) {
    options.numThreads = threads;
    for (size_t i = 0; i < n; ++i) {
      const float z = 1.0f - 2.0f * (float(i) + 0.5f) / float(n), r = std::sqrt(1.0f - z * z);
      const float a = 2.39996323f * float(i);
      const glm::vec3 p = kRadius * glm::vec3(r * std::cos(a), r * std::sin(a), z);
      s.add(p, -p, options.desiredRadius, 0);
    }
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

TEST(TesselatorPasses, ProjectVerticesPutsEveryVertexOnTheSurfaceWithOutwardNormals) {
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

TEST(TesselatorPasses, ProjectVerticesLeavesOutParticlesFarOffTheSurface) {
  Sphere sphere(600);
  sphere.s.pos[7] *= 1.0f + 2.0f * sphere.options.desiredRadius;  // beyond kVertexOff
  projectVertices(sphere.s, sphere.options);
  EXPECT_FALSE(sphere.s.vok[7]);
  EXPECT_TRUE(sphere.s.vok[8]);
}

TEST(TesselatorPasses, FansAreCounterClockwiseRingsOfNeighbours) {
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

TEST(TesselatorPasses, VotesEmitEachTriangleOnceWithItsCornersCount) {
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

TEST(TesselatorPasses, AssemblyNeverReusesADirectedEdgeAndCountsTheBoundary) {
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

// Passes A-C, then every candidate triangle around the given particles is withdrawn (no votes), so the assembly
// leaves a hole of about six edges around each. (A fan-repeat flag sends it down its sequential path, which reads
// only the candidates.)
void punchHoles(Sphere& sphere, std::initializer_list<uint32_t> centres) {
  auto& s = sphere.s;
  sphere.fansAndVotes();
  for (uint32_t i = 0; i < s.size(); ++i)
    for (size_t k = 0; k < s.candCount[i]; ++k) {
      uint32_t* slot = &s.cand[(size_t(i) * kMaxFan + k) * 3];
      for (uint32_t c : centres)
        if (i == c || slot[0] == c || slot[1] == c) slot[2] = 0;
    }
  s.fanRepeat[0] = 1;
}

TEST(TesselatorPasses, HoleRepairClosesTheHolesAroundMissingTriangles) {
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

TEST(TesselatorPasses, RepairLeavesLoopsLongerThanMaxHoleLoopOpen) {
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

// F: a vertex whose triangles form two closed fans (a square pyramid and a tetrahedron sharing their apex 0: every
// edge has its twin, yet the mesh is pinched at 0) is found, the smaller fan's slots are marked, and the pass leaves
// no pinched vertex, with the larger fan untouched.
TEST(TesselatorPasses, PinchedVertexLosesItsSmallerFan) {
  Sphere sphere(600);
  auto& s = sphere.s;
  projectVertices(s, sphere.options);
  const std::vector<uint32_t> pyramid = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 1, 4, 3, 1, 3, 2};
  const std::vector<uint32_t> tetrahedron = {0, 5, 6, 0, 6, 7, 0, 7, 5, 5, 7, 6};
  const size_t n = s.size();
  s.heTo.assign(n * kMaxHalfEdges, 0);
  s.heThird.assign(n * kMaxHalfEdges, 0);
  s.heCount.assign(n, 0);
  s.openOut.assign(n, 0);
  s.tris = pyramid;
  s.tris.insert(s.tris.end(), tetrahedron.begin(), tetrahedron.end());
  for (size_t t = 0; t < s.tris.size(); t += 3)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t a = s.tris[t + k], slot = uint32_t(a * kMaxHalfEdges + s.heCount[a]++);
      s.heTo[slot] = s.tris[t + (k + 1) % 3];
      s.heThird[slot] = s.tris[t + (k + 2) % 3];
    }
  ASSERT_EQ(markPinchedVertices(s, sphere.options), 1u);
  EXPECT_TRUE(s.openUp[0]);
  size_t dropped = 0;
  for (size_t k = 0; k < s.heCount[0]; ++k) {
    const uint32_t to = s.heTo[k];
    EXPECT_EQ(bool(s.dropSlot[k]), to >= 5) << "slot to " << to << ": only the tetrahedron's (smaller) fan goes";
    dropped += s.dropSlot[k];
  }
  EXPECT_EQ(dropped, 3u);
  size_t boundary = 0, unfilled = 0;
  EXPECT_EQ(unpinchVertices(s, sphere.options, boundary, unfilled), 0u);
  EXPECT_EQ(markPinchedVertices(s, sphere.options), 0u);
  std::set<std::tuple<uint32_t, uint32_t, uint32_t>> left;
  for (size_t t = 0; t < s.tris.size(); t += 3) left.insert({s.tris[t], s.tris[t + 1], s.tris[t + 2]});
  for (size_t t = 0; t < pyramid.size(); t += 3)
    EXPECT_TRUE(left.count({pyramid[t], pyramid[t + 1], pyramid[t + 2]})) << "pyramid triangle " << t / 3;
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    const uint32_t* c = &s.tris[t];
    const bool apex = c[0] == 0 || c[1] == 0 || c[2] == 0, tetra = c[0] >= 5 || c[1] >= 5 || c[2] >= 5;
    EXPECT_FALSE(apex && tetra) << "a tetrahedron triangle at the apex is left";
  }
}

TEST(TesselatorPasses, ComputeForcesKeepsVelocitiesTangentAndMarksStrays) {
  Sphere sphere(600);
  auto& s = sphere.s;
  const size_t stray = 11;
  s.pos[stray] *= 1.5f;  // F is nearly 0 there: off the surface
  computeForces(s, sphere.field, sphere.options, /*cached=*/false);
  ASSERT_EQ(s.dead.size(), s.size());
  EXPECT_TRUE(s.dead[stray]);
  for (size_t i = 0; i < s.size(); ++i) {
    if (i == stray) continue;
    ASSERT_FALSE(s.dead[i]) << i;
    EXPECT_LE(std::abs(glm::dot(s.vel[i], s.nrm[i])), 1e-3f * glm::length(s.vel[i]) + 1e-4f) << i;
    EXPECT_GT(s.energy[i], 0.0f) << i;
    EXPECT_GE(s.fuseCount[i], 1u);
    for (size_t k = 0; k < s.fuseCount[i]; ++k) EXPECT_NE(s.fuse[i * kMaxFuse + k], uint32_t(i));
  }
}

TEST(TesselatorPasses, IntegrationEndsOnTheSurface) {
  Sphere sphere(600);
  auto& s = sphere.s;
  computeForces(s, sphere.field, sphere.options, false);
  integrateParticles(s, sphere.field, sphere.options);
  EXPECT_FALSE(s.nbrValid) << "particles moved";
  for (size_t i = 0; i < s.size(); ++i) {
    EXPECT_NEAR(glm::length(s.pos[i]), kRadius, 0.01f * sphere.options.desiredRadius) << i;
    EXPECT_GE(s.sigma[i], 0.25f * sphere.options.desiredRadius * 0.999f);
    EXPECT_LE(s.sigma[i], 1.5f * sphere.options.desiredRadius * 1.001f);
  }
}

TEST(TesselatorPasses, AddAndDeleteFusesTheYoungerOfTwoAndFissionsTheLargest) {
  Sphere sphere(600);
  auto& s = sphere.s;
  const float h = sphere.options.desiredRadius;
  // Particle "young" sits right next to "old" (and is younger: a larger id); particle "big" is at the largest radius.
  const glm::vec3 p = s.pos[0], t = glm::normalize(glm::cross(p, glm::vec3(0.3f, 0.4f, 0.5f)));
  s.add(glm::normalize(p + 0.1f * h * t) * kRadius, -p, h, 0);
  const uint64_t youngId = s.id.back(), oldId = s.id[0];
  findNeighbours(s, sphere.options);
  computeForces(s, sphere.field, sphere.options, false);
  const size_t big = 42;
  s.sigma[big] = 1.5f * h;
  const uint64_t bigId = s.id[big];
  const size_t before = s.size();
  TesselatorStats stats;
  addAndDeleteParticles(s, sphere.options, stats);
  EXPECT_EQ(stats.fusions, 1u);
  EXPECT_EQ(stats.fissions, 1u);
  EXPECT_EQ(stats.strays, 0u);
  EXPECT_EQ(s.size(), before - 1 - stats.deaths + 1);
  EXPECT_EQ(std::count(s.id.begin(), s.id.end(), youngId), 0) << "the younger one fused";
  EXPECT_EQ(std::count(s.id.begin(), s.id.end(), oldId), 1);
  const size_t parent = size_t(std::find(s.id.begin(), s.id.end(), bigId) - s.id.begin());
  ASSERT_LT(parent, s.size());
  EXPECT_NEAR(s.sigma[parent], 1.5f * h / std::sqrt(2.0f), 1e-5f);
  EXPECT_EQ(s.sigma.back(), s.sigma[parent]) << "the child is appended with the same radius";
  EXPECT_GT(s.id.back(), youngId);
}

// ---- settle(): cancel and progress ------------------------------------------------------------------------------

TEST(TesselatorOptions, SettleReportsProgressOnTheCallingThreadAndStopsOnCancel) {
  const Character& ch = test::exampleCharacter("transformed_blobs");
  SkeletonCache skel(ch);
  TesselatorOptions o;
  o.numThreads = 2;
  std::vector<float> reports;
  bool otherThread = false;
  const auto caller = std::this_thread::get_id();
  std::atomic<bool> cancel{false};
  size_t cancelAfter = 7;  // reports
  o.cancel = &cancel;
  o.progress = [&](float f) {
    reports.push_back(f);
    otherThread |= std::this_thread::get_id() != caller;
    if (reports.size() == cancelAfter) cancel = true;
  };
  Tesselator tess(o);
  Mesh mesh;
  mesh.positions = {1, 2, 3};
  EXPECT_EQ(tess.settle(skel, mesh, 200), 7) << "stops after the update under way";
  EXPECT_TRUE(tess.stats().cancelled);
  EXPECT_EQ(mesh.vertexCount(), 0u);
  EXPECT_EQ(tess.stats().updates, 7u);
  EXPECT_FALSE(otherThread);
  EXPECT_TRUE(std::is_sorted(reports.begin(), reports.end()));
  EXPECT_FLOAT_EQ(reports.back(), 7.0f / 200.0f);

  // Not cancelled: goes on from the particles it has, and ends reporting 1 with a closed mesh.
  cancel = false;
  cancelAfter = 0;
  reports.clear();
  const int updates = tess.settle(skel, mesh, 200);
  EXPECT_FALSE(tess.stats().cancelled);
  EXPECT_GT(updates, 7);
  EXPECT_EQ(reports.back(), 1.0f);
  EXPECT_TRUE(std::is_sorted(reports.begin(), reports.end()));
  EXPECT_GT(mesh.triangleCount(), 0u);
}

TEST(TesselatorOptions, ProgressAndCancelDoNotChangeTheParticles) {
  const Character& ch = test::exampleCharacter("transformed_blobs");
  SkeletonCache skel(ch);
  TesselatorOptions quiet;
  quiet.numThreads = 2;
  TesselatorOptions watched = quiet;
  std::atomic<bool> never{false};
  watched.cancel = &never;
  watched.progress = [](float) {};
  Tesselator a(quiet), b(watched);
  Mesh ma, mb;
  EXPECT_EQ(a.settle(skel, ma, 60), b.settle(skel, mb, 60));
  EXPECT_EQ(ma.positions, mb.positions);
  EXPECT_EQ(ma.indices, mb.indices);
}

}  // namespace
}  // namespace imps
