// SPDX-License-Identifier: MIT
// Tests for the particle tesselator (imps/src/tesselator.cpp): convergence, closed meshes, determinism, blend rule,
// recovery after fast motion, no NaN; the update's compute, integration and add/delete phases one at a time; and
// settle()'s cancel flag and progress callback. The triangulation's passes are in tesselator_mesh_test.cpp, the
// seeding in tesselator_seed_test.cpp and the accuracy measure in tesselator_accuracy_test.cpp.
#include "imps/tesselator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "examples.h"
#include "tesselator_sphere.h"
#include "tesselator_state.h"

namespace imps {
namespace {

struct Example {
  Scene scene;
  std::optional<Character> character;
  TesselatorOptions options;
};

// The scene and its character from a read (a file, or text), failing the test on errors.
Example fromRead(std::expected<Scene, Diagnostics> read) {
  Example e;
  if (!read) ADD_FAILURE() << read.error().str();
  e.scene = std::move(*read);
  auto c = Character::fromScene(e.scene);
  if (!c) ADD_FAILURE() << c.error().str();
  e.character = std::move(*c);
  if (const auto* node = std::get_if<Tesselator3MPNode>(&e.scene.polygonizer))
    e.options = TesselatorOptions::fromNode(*node);
  return e;
}

Example load(const std::string& name) {
  return fromRead(readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/" + name));
}

// Max over vertices of |F - iso| / |grad F| (metres): distance to the surface to first order.
float worstSurfaceError(const Field& field, const Mesh& mesh) {
  float worst = 0.0f;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const FieldSample fs = field.sample(mesh.position(v));
    worst = std::max(worst, std::fabs(fs.value - field.iso()) / glm::length(fs.gradient));
  }
  return worst;
}

// Triangles whose winding disagrees with the outward field normal (-gradient) at their centroid: folds and flips.
size_t foldedTriangles(const Field& field, const Mesh& mesh) {
  size_t folded = 0;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::vec3 a = mesh.position(mesh.indices[3 * t]), b = mesh.position(mesh.indices[3 * t + 1]),
                    c = mesh.position(mesh.indices[3 * t + 2]);
    if (glm::dot(glm::cross(b - a, c - a), -field.sample((a + b + c) / 3.0f).gradient) <= 0.0f) ++folded;
  }
  return folded;
}

// worstSurfaceError over the vertices some triangle uses (a particle mesh keeps one vertex per particle, and those no
// triangle uses may be off the surface).
float worstUsedVertexError(const Field& field, const Mesh& mesh) {
  std::vector<uint8_t> used(mesh.vertexCount(), 0);
  for (uint32_t v : mesh.indices) used[v] = 1;
  float worst = 0.0f;
  for (uint32_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    const FieldSample fs = field.sample(mesh.position(v));
    worst = std::max(worst, std::fabs(fs.value - field.iso()) / glm::length(fs.gradient));
  }
  return worst;
}

// The biped's sizes scaled so that about `particles` particles cover it (the file's ~2685 at scale 1).
void scaleToParticles(TesselatorOptions& options, float particles) {
  const float scale = std::sqrt(2685.0f / particles);
  options.desiredRadius *= scale;
  options.queryRadius *= scale;
  options.cubeSize *= scale;
}

// Upper arms and thighs (and forearms with `forearms`) swinging about z, left and right in opposite senses, as a
// triangle wave between -45 and +45 degrees (`puppeteer bench --motion swing:DEG`).
class LimbSwing {
 public:
  LimbSwing(const Character& character, SkeletonCache& skeleton, bool forearms) : skeleton_(skeleton) {
    std::vector<const char*> names = {"L_UpperArm", "R_UpperArm", "L_Thigh", "R_Thigh"};
    if (forearms) names.insert(names.end(), {"L_Forearm", "R_Forearm"});
    for (const char* name : names) {
      ids_.push_back(character.findJoint(name));
      rest_.push_back(skeleton.local(ids_.back()).rotation);
    }
  }
  // Poses the limbs at `degrees` (left side; the right the opposite) and updates the skeleton.
  void pose(float degrees) {
    for (size_t k = 0; k < ids_.size(); ++k) {
      const float a = glm::radians(degrees) * (k % 2 ? -1.0f : 1.0f);
      skeleton_.setRotation(ids_[k], rest_[k] * glm::angleAxis(a, glm::vec3(0, 0, 1)));
    }
    skeleton_.update();
  }
  // Advances the triangle wave by `degrees` and poses the limbs there.
  void advance(float degrees) {
    angle_ += direction_ * degrees;
    if (angle_ > 45.0f) angle_ = 90.0f - angle_, direction_ = -1.0f;
    if (angle_ < -45.0f) angle_ = -90.0f - angle_, direction_ = 1.0f;
    pose(angle_);
  }

 private:
  SkeletonCache& skeleton_;
  std::vector<int> ids_;
  std::vector<glm::quat> rest_;
  float angle_ = 0.0f, direction_ = 1.0f;
};

// Max over points of |F - iso| / |grad F| (metres).
float worstSurfaceDistance(const Field& field, std::span<const glm::vec3> points) {
  float worst = 0.0f;
  for (const glm::vec3& x : points) {
    const FieldSample fs = field.sample(x);
    worst = std::max(worst, std::fabs(fs.value - field.iso()) / glm::length(fs.gradient));
  }
  return worst;
}

class PerExample : public ::testing::TestWithParam<const char*> {};

TEST_P(PerExample, ConvergesToClosedMeshOnTheSurface) {
  Example e = load(GetParam());
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh;
  const int updates = tess.settle(skel, mesh, 300);
  const TesselatorStats& st = tess.stats();
  const MeshTopology topo = analyzeTopology(mesh);
  std::printf("%s: %d updates, %zu particles, %zu triangles (%zu filled), boundary %zu, nonmanifold e %zu v %zu, "
              "orient %zu, unfilled loops %zu\n",
              GetParam(), updates, st.particles, st.triangles, st.filledTriangles, topo.boundaryEdges,
              topo.nonManifoldEdges, topo.nonManifoldVertices, topo.orientationConflicts, st.unfilledLoops);
  EXPECT_GT(st.particles, 20u);
  EXPECT_EQ(topo.boundaryEdges, 0u);
  EXPECT_EQ(topo.nonManifoldEdges, 0u);
  EXPECT_EQ(topo.orientationConflicts, 0u);
  EXPECT_EQ(topo.nonManifoldVertices, 0u);
  EXPECT_LT(worstSurfaceError(skel.field(), mesh), 0.01f * e.options.desiredRadius);
  EXPECT_EQ(foldedTriangles(skel.field(), mesh), 0u);
  // Spacing: median edge length near desiredRadius.
  std::vector<float> edges;
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    for (int k = 0; k < 3; ++k)
      edges.push_back(glm::length(mesh.position(mesh.indices[3 * t + size_t(k)]) -
                                  mesh.position(mesh.indices[3 * t + size_t((k + 1) % 3)])));
  std::nth_element(edges.begin(), edges.begin() + std::ptrdiff_t(edges.size() / 2), edges.end());
  const float median = edges[edges.size() / 2] / e.options.desiredRadius;
  std::printf("  median edge / desiredRadius = %.3f\n", double(median));
  EXPECT_GT(median, 0.6f);
  EXPECT_LT(median, 1.6f);
  for (float x : mesh.positions) ASSERT_TRUE(std::isfinite(x));
}

INSTANTIATE_TEST_SUITE_P(Examples, PerExample,
                         ::testing::Values("transformed_blobs.wrl", "textured_blobs.wrl", "beanito.wrl", "flubber.wrl",
                                           "simple_biped.wrl"));

// Runs `updates` frames of the biped, swinging the upper arms, and returns the last mesh.
Mesh runBiped(int threads, uint64_t seed, int updates, std::vector<size_t>* boundary = nullptr) {
  Example e = load("simple_biped.wrl");
  e.options.threads = threads;
  e.options.seed = seed;
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh;
  for (int u = 0; u < updates; ++u) {
    const float a = 0.5f * std::sin(0.1f * float(u));
    skel.setRotation("L_UpperArm", glm::angleAxis(a, glm::vec3(0, 0, 1)));
    skel.setRotation("R_UpperArm", glm::angleAxis(-a, glm::vec3(0, 0, 1)));
    skel.update();
    tess.update(skel);
    if (u % 10 == 9) {
      tess.triangulate(mesh);
      if (boundary) boundary->push_back(tess.stats().boundaryEdges);
    }
  }
  tess.triangulate(mesh);
  return mesh;
}

TEST(Tesselator, OneThreadAndTwoThreadsGiveIdenticalMeshes) {
  const Mesh one = runBiped(1, 7, 60), two = runBiped(2, 7, 60), four = runBiped(4, 7, 60);
  EXPECT_GT(one.triangleCount(), 1000u);
  EXPECT_TRUE(one == two);
  EXPECT_TRUE(one == four);
}

TEST(Tesselator, SameSeedTwiceIsIdenticalAndSeedMatters) {
  const Mesh a = runBiped(2, 3, 60), b = runBiped(2, 3, 60), c = runBiped(2, 4, 60);
  EXPECT_TRUE(a == b);
  EXPECT_FALSE(a == c);  // fission directions and deaths come from the seed
}

TEST(Tesselator, BoundaryEdgesAtEveryTriangulationWhileMovingSlowly) {
  std::vector<size_t> boundary;
  const Mesh mesh = runBiped(2, 1, 120, &boundary);
  // After the first 30 updates (seeding settles), the slowly swinging biped stays closed.
  for (size_t k = 3; k < boundary.size(); ++k) EXPECT_EQ(boundary[k], 0u) << "triangulation " << k;
  for (float x : mesh.positions) ASSERT_TRUE(std::isfinite(x));
}

// The biped swinging its arms (and bending the left elbow), at the file's fidelity (~2650 particles) and at the
// benchmark's coarse one (~900, seven particles around a forearm, where the corners' tangent planes disagree most):
// every triangulation stays closed and manifold, and hardly any triangle folds (winds against the field normal).
// Measured: at most 1 of ~5180 (file) and 5 of ~1610 (coarse) fold in one render; up to 45 at the coarse fidelity
// before lone fan proposals were assembled and island loops opened up.
struct FoldCase {
  float particles;
  size_t foldsPer10k;  // the most folded triangles allowed per 10,000
};
class SwingingBiped : public ::testing::TestWithParam<FoldCase> {};

TEST_P(SwingingBiped, StaysClosedAndHardlyFolds) {
  Example e = load("simple_biped.wrl");
  scaleToParticles(e.options, GetParam().particles);
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh;
  tess.settle(skel, mesh, 300);
  size_t worst = 0;
  for (int u = 0; u < 90; ++u) {
    const float a = 0.6f * std::sin(0.05f * float(u));
    skel.setRotation("L_UpperArm", glm::angleAxis(a, glm::vec3(0, 0, 1)));
    skel.setRotation("R_UpperArm", glm::angleAxis(-a, glm::vec3(0, 0, 1)));
    skel.setRotation("L_LowerArm", glm::angleAxis(a, glm::vec3(1, 0, 0)));
    skel.update();
    tess.update(skel);
    if (u % 3 != 2) continue;
    tess.triangulate(mesh);
    const MeshTopology topo = analyzeTopology(mesh);
    EXPECT_EQ(topo.boundaryEdges, 0u) << "update " << u;
    EXPECT_EQ(topo.nonManifoldEdges, 0u) << "update " << u;
    const size_t folded = foldedTriangles(skel.field(), mesh);
    EXPECT_LE(folded * 10000, GetParam().foldsPer10k * mesh.triangleCount()) << "update " << u;
    worst = std::max(worst, folded);
  }
  std::printf("%.0f particles: at most %zu folded of %zu triangles\n", double(tess.stats().particles), worst,
              mesh.triangleCount());
  EXPECT_GT(double(tess.stats().particles), 0.8 * double(GetParam().particles));
  EXPECT_LT(double(tess.stats().particles), 1.2 * double(GetParam().particles));
}

INSTANTIATE_TEST_SUITE_P(Fidelities, SwingingBiped,
                         ::testing::Values(FoldCase{2650.0f, 5}, FoldCase{900.0f, 100}));

// Arms down against the hips: hands and hips must never trade particles (they are not blend neighbours), and every
// ownership change goes to a blend neighbour.
TEST(Tesselator, BlendRuleRespectedWhenHandsTouchHips) {
  Example e = load("simple_biped.wrl");
  const Character& ch = *e.character;
  SkeletonCache skel(ch);
  Tesselator tess(e.options);
  Mesh mesh;
  tess.settle(skel, mesh, 100);
  auto owners = [&] {
    std::map<uint64_t, int32_t> m;
    const ParticleView v = tess.particles();
    for (size_t i = 0; i < v.size(); ++i) m[v.ids[i]] = v.owners[i];
    return m;
  };
  std::map<uint64_t, int32_t> before = owners();
  size_t checked = 0;
  for (int u = 1; u <= 40; ++u) {
    const float a = std::min(1.0f, float(u) / 20.0f) * 1.45f;  // lower both arms to the sides over 20 updates
    skel.setRotation("L_UpperArm", glm::angleAxis(-a, glm::vec3(0, 0, 1)));
    skel.setRotation("R_UpperArm", glm::angleAxis(a, glm::vec3(0, 0, 1)));
    skel.update();
    tess.update(skel);
    std::map<uint64_t, int32_t> now = owners();
    for (const auto& [id, o] : now) {
      auto it = before.find(id);
      if (it == before.end() || it->second == o || it->second < 0) continue;
      EXPECT_TRUE(ch.blends(size_t(it->second), size_t(o)))
          << ch.primitives()[size_t(it->second)].name << " -> " << ch.primitives()[size_t(o)].name;
      ++checked;
    }
    before = std::move(now);
  }
  EXPECT_GT(checked, 0u);
  tess.triangulate(mesh);
  // The hands' particles sit on the unblended union: no vertex is pulled off the surface, and no hand particle is
  // owned by a hip/pelvis primitive or vice versa (they never blend).
  EXPECT_LT(worstSurfaceError(skel.field(), mesh), 0.01f * e.options.desiredRadius);
  for (float x : mesh.positions) ASSERT_TRUE(std::isfinite(x));
}

// The blend rule in the particles too (thesis 3.7): on a torso -> shoulder -> arm chain coloured red, green and
// blue, torso and arm never blend, so no vertex mixes red with blue, and no particle passes between them.
TEST(Tesselator, ColoursAndOwnershipMixOnlyAcrossBlendingPairs) {
  auto scene = readScene(R"(#VRML V2.0 utf8
Tesselator3MP { desiredRadius 0.03 queryRadius 0.072 numThreads 2
  spatialSubdivision UniformHash { cubeSize 0.072 bitsPerDim 6 }
  blendingFunction ExponentialBlend { variance 2 } sceneGraph RigidTransform { children [
  DEF torso LineSeg { point1 0 0 0 point2 0 0.6 0 radius1 0.12 radius2 0.12 material Material { diffuseColor 1 0 0 } }
  DEF Shoulder RigidTransform { translation 0.24 0.6 0 children [
    DEF shoulder Metaball { radius 0.1 material Material { diffuseColor 0 1 0 } }
    DEF Arm RigidTransform { translation 0 -0.02 0 children [
      DEF arm LineSeg { point1 0 0 0 point2 0 -0.5 0 radius1 0.05 radius2 0.05 material Material { diffuseColor 0 0 1 } }
    ] }
  ] }
] } }
)",
                         "chain.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  auto ch = Character::fromScene(*scene);
  ASSERT_TRUE(ch.has_value()) << ch.error().str();
  SkeletonCache skel(*ch);
  Tesselator tess(TesselatorOptions::fromNode(std::get<Tesselator3MPNode>(scene->polygonizer)));
  Mesh mesh;
  tess.settle(skel, mesh, 80);
  size_t greenish = 0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 c = mesh.color(v);
    EXPECT_LT(std::min(c.r, c.b), 1e-3f) << "vertex " << v << " mixes torso and arm colours";
    greenish += c.g > 0.2f && (c.r > 0.2f || c.b > 0.2f);
  }
  EXPECT_GT(greenish, 10u) << "the shoulder does mix with both neighbours";
  // Swing the arm against the torso and back: no particle of the torso is ever taken over by the arm or back.
  const size_t torso = 0, arm = 2;
  ASSERT_EQ(ch->primitives()[arm].name, "arm");
  std::map<uint64_t, int32_t> before;
  for (int u = 0; u <= 30; ++u) {
    const float a = 0.4f * std::sin(float(u) / 30.0f * 6.2831853f);
    skel.setRotation("Shoulder", glm::angleAxis(a, glm::vec3(0, 0, 1)));
    skel.update();
    tess.update(skel);
    const ParticleView pv = tess.particles();
    std::map<uint64_t, int32_t> now;
    for (size_t i = 0; i < pv.size(); ++i) {
      now[pv.ids[i]] = pv.owners[i];
      auto it = before.find(pv.ids[i]);
      if (it == before.end()) continue;
      const bool torsoToArm = size_t(it->second) == torso && size_t(pv.owners[i]) == arm;
      const bool armToTorso = size_t(it->second) == arm && size_t(pv.owners[i]) == torso;
      EXPECT_FALSE(torsoToArm || armToTorso) << "particle " << pv.ids[i];
    }
    before = std::move(now);
  }
}

TEST(Tesselator, RecoversAfterSudden45DegreeRotation) {
  Example e = load("simple_biped.wrl");
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh;
  tess.settle(skel, mesh, 100);
  ASSERT_EQ(tess.stats().boundaryEdges, 0u);
  const float q = 0.78539816f;
  skel.setRotation("L_UpperArm", glm::angleAxis(q, glm::vec3(0, 0, 1)));
  skel.setRotation("R_Thigh", glm::angleAxis(q, glm::vec3(1, 0, 0)));
  skel.setRotation("Neck", glm::angleAxis(q, glm::vec3(0, 1, 0)));
  skel.update();
  int recovered = -1;
  for (int u = 1; u <= 30; ++u) {
    tess.update(skel);
    skel.update();  // no further motion: differentials are identity from now on
    tess.triangulate(mesh);
    for (float x : mesh.positions) ASSERT_TRUE(std::isfinite(x));
    if (tess.stats().boundaryEdges == 0 && analyzeTopology(mesh).boundaryEdges == 0) {
      recovered = u;
      break;
    }
  }
  std::printf("recovered after %d updates\n", recovered);
  EXPECT_GT(recovered, 0);
  EXPECT_LE(recovered, 10);
  for (int u = 0; u < 10; ++u) tess.update(skel);
  tess.triangulate(mesh);
  EXPECT_EQ(tess.stats().boundaryEdges, 0u);
  EXPECT_LT(worstSurfaceError(skel.field(), mesh), 0.01f * e.options.desiredRadius);
}

// Live-app motion: one render every 1/60 s with the example's updatesPerRender updates, joints swinging as a
// triangle wave of +-amplitude degrees. Records what the issue's goals are about, per render.
struct MotionRecord {
  size_t renders = 0, rendersWithHoles = 0, maxBoundary = 0;
  int longestOpenRun = 0;          // most consecutive renders with boundary edges
  float worstParticleOff = 0.0f;   // max |F - iso| / |grad F| over particles after each render's updates (metres)
  float worstVertexOff = 0.0f;     // the same over mesh vertices used by triangles
  float worstCentroidOff = 0.0f;   // the same at triangle centroids (a bubble or a spanning triangle shows here)
  float worstRegionCentroidOff = 0.0f;  // the same, triangles with a corner within regionRadius of the region centre
  bool finite = true;
  size_t minRegion = SIZE_MAX, maxRegion = 0;  // particles within regionRadius of the first joint's origin
  size_t settledRegion = 0;
};

float offSurface(const Field& field, const glm::vec3& x) {
  const FieldSample fs = field.sample(x);
  const float g = glm::length(fs.gradient);
  return g > 0.0f ? std::fabs(fs.value - field.iso()) / g : INFINITY;
}

MotionRecord swing(Example& e, const std::vector<std::string>& joints, const glm::vec3& axis, float degPerSecond,
                   float amplitudeDeg, int renders, float regionRadius = 0.0f, glm::vec3 regionOffset = {}) {
  const Character& ch = *e.character;
  SkeletonCache skel(ch);
  Tesselator tess(e.options);
  Mesh mesh;
  tess.settle(skel, mesh, 200);
  std::vector<int> ids;
  std::vector<glm::quat> rest;
  for (const std::string& name : joints) {
    ids.push_back(ch.findJoint(name));
    EXPECT_GE(ids.back(), 0) << name;
    rest.push_back(skel.local(ids.back()).rotation);
  }
  auto regionCount = [&] {
    const glm::vec3 c = skel.world(ids[0]).apply(regionOffset);
    size_t count = 0;
    for (const glm::vec3& p : tess.particles().positions) count += glm::length(p - c) < regionRadius ? 1 : 0;
    return count;
  };
  MotionRecord r;
  r.settledRegion = regionCount();
  const float dt = 1.0f / 60.0f;
  float angle = 0.0f, direction = 1.0f;
  int openRun = 0;
  for (int f = 0; f < renders; ++f) {
    angle += direction * degPerSecond * dt;
    if (angle > amplitudeDeg) angle = 2 * amplitudeDeg - angle, direction = -1.0f;
    if (angle < -amplitudeDeg) angle = -2 * amplitudeDeg - angle, direction = 1.0f;
    for (size_t k = 0; k < ids.size(); ++k) {
      const float a = glm::radians(angle) * (k % 2 == 0 ? 1.0f : -1.0f);
      skel.setRotation(ids[k], rest[k] * glm::angleAxis(a, axis));
    }
    skel.update();
    tess.frame(skel, mesh);
    const Field& field = skel.field();
    const glm::vec3 regionCentre = skel.world(ids[0]).apply(regionOffset);
    for (const glm::vec3& p : tess.particles().positions) {
      r.finite = r.finite && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      r.worstParticleOff = std::max(r.worstParticleOff, offSurface(field, p));
    }
    std::vector<uint8_t> used(mesh.vertexCount(), 0);
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      glm::vec3 centroid(0.0f);
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = mesh.indices[3 * t + size_t(k)];
        used[v] = 1;
        centroid += mesh.position(v) / 3.0f;
      }
      const float off = offSurface(field, centroid);
      r.worstCentroidOff = std::max(r.worstCentroidOff, off);
      if (regionRadius > 0.0f && glm::length(mesh.position(mesh.indices[3 * t]) - regionCentre) < regionRadius)
        r.worstRegionCentroidOff = std::max(r.worstRegionCentroidOff, off);
    }
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
      if (used[v]) r.worstVertexOff = std::max(r.worstVertexOff, offSurface(field, mesh.position(v)));
    const size_t boundary = tess.stats().boundaryEdges;
    EXPECT_EQ(boundary, analyzeTopology(mesh).boundaryEdges);
    ++r.renders;
    r.maxBoundary = std::max(r.maxBoundary, boundary);
    openRun = boundary > 0 ? openRun + 1 : 0;
    r.rendersWithHoles += boundary > 0 ? 1 : 0;
    r.longestOpenRun = std::max(r.longestOpenRun, openRun);
    if (regionRadius > 0.0f) {
      const size_t count = regionCount();
      r.minRegion = std::min(r.minRegion, count);
      r.maxRegion = std::max(r.maxRegion, count);
    }
  }
  return r;
}

// Issue 3 "fast joints": arms, forearms and thighs swinging +-45 degrees at 90 and 360 degrees per second, rendered at
// 60 Hz with the example's updatesPerRender (3). Every render with a hole must close again within two renders (six
// updates), and no particle may go NaN or leave the surface.
TEST(Tesselator, FastSwingingLimbsKeepTheMeshClosedOrRecoverWithinTwoRenders) {
  for (float speed : {90.0f, 360.0f}) {
    Example e = load("simple_biped.wrl");
    const float h = e.options.desiredRadius;
    const MotionRecord r = swing(e, {"L_UpperArm", "R_UpperArm", "L_Thigh", "R_Thigh", "L_Forearm", "R_Forearm"},
                                 glm::vec3(0, 0, 1), speed, 45.0f, 120);
    std::printf("swing %.0f deg/s: %zu/%zu renders with holes (max %zu boundary edges, longest open run %d), worst "
                "particle off surface %.3f h, vertex %.4f h, centroid %.3f h\n",
                double(speed), r.rendersWithHoles, r.renders, r.maxBoundary, r.longestOpenRun,
                double(r.worstParticleOff / h), double(r.worstVertexOff / h), double(r.worstCentroidOff / h));
    EXPECT_TRUE(r.finite);
    EXPECT_LE(r.longestOpenRun, 2) << speed;
    EXPECT_LE(r.rendersWithHoles * 20, r.renders) << speed;  // at most 5% of renders
    // Where the swinging legs pass through each other (a union, not a blend), a particle can be carried up to ~2
    // desiredRadius into the other leg by one update; it is left out of the mesh and dies as a stray next update.
    EXPECT_LT(r.worstParticleOff, 2.5f * h) << speed;
    EXPECT_LT(r.worstVertexOff, 0.02f * h) << speed;
  }
}

// Issue 3 "the neck of the biped does not bubble when it turns": the Neck (a BlendGroup with both clavicles) turns
// +-60 degrees about the spine and tilts, back and forth at 180 degrees per second. No vertex or triangle may leave
// the true surface (a bubble), and the particle count around the neck stays near its settled value (no clusters,
// no bald patches).
TEST(Tesselator, TurningNeckDoesNotBubble) {
  Example e = load("simple_biped.wrl");
  const float h = e.options.desiredRadius;
  const glm::vec3 axis = glm::normalize(glm::vec3(0.3f, 1.0f, 0.0f));
  const MotionRecord rest = swing(e, {"Neck"}, axis, 0.0f, 60.0f, 60, 0.12f, glm::vec3(0.0f, 0.05f, 0.0f));
  const MotionRecord r = swing(e, {"Neck"}, axis, 180.0f, 60.0f, 160, 0.12f, glm::vec3(0.0f, 0.05f, 0.0f));
  std::printf("neck at rest: worst centroid near the neck %.3f h\n", double(rest.worstRegionCentroidOff / h));
  std::printf("neck: particles near the neck %zu settled, %zu..%zu while turning; %zu/%zu renders with holes; worst "
              "particle off surface %.3f h, vertex %.4f h, centroid near the neck %.3f h (anywhere %.3f h)\n",
              r.settledRegion, r.minRegion, r.maxRegion, r.rendersWithHoles, r.renders, double(r.worstParticleOff / h),
              double(r.worstVertexOff / h), double(r.worstRegionCentroidOff / h), double(r.worstCentroidOff / h));
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.rendersWithHoles, 0u);
  EXPECT_LT(r.worstParticleOff, 0.5f * h);
  EXPECT_LT(r.worstVertexOff, 0.01f * h);
  // Flat triangles across the neck-shoulder and neck-head creases sit off the surface; turning must not make that
  // much worse (a bubble would). Measured: 0.14 h at rest and 1.20 h turning since the repair opens a wrong-way loop
  // by its rim only (before: 1.41 h and 2.08 h; before pinched vertices were repaired, pass F, 1.84 h at rest).
  EXPECT_LT(rest.worstRegionCentroidOff, 0.5f * h);
  EXPECT_LT(r.worstRegionCentroidOff, 1.5f * h);
  EXPECT_GT(double(r.minRegion), 0.8 * double(r.settledRegion));
  EXPECT_LT(double(r.maxRegion), 1.2 * double(r.settledRegion));
}

TEST(Tesselator, ATinyDesiredRadiusStopsAtTheParticleLimit) {
  // desiredRadius 1e-4 m on the biped asked for ~10^8 seed points and grew past a gigabyte; seeding and fission now
  // stop at maxParticles, and the candidates are spaced so that their number stays in proportion to it.
  Example e = load("simple_biped.wrl");
  SkeletonCache skel(*e.character);
  TesselatorOptions o = e.options;
  o.desiredRadius = 1e-4f;
  o.queryRadius = 2.5e-4f;
  o.maxParticles = 2000;
  Tesselator tess(o);
  for (int u = 0; u < 3; ++u) {
    tess.update(skel);
    EXPECT_LE(tess.particles().size(), o.maxParticles) << "update " << u;
  }
  EXPECT_GT(tess.particles().size(), 0u);
}

// Joint translations (issue 10): a jump of the biped's root, 30 cm up and 20 cm sideways in one frame, carries every
// particle with it through the differential transforms (which include translation). Two identical tesselators, one
// whose character jumps and one whose character stays: after the update each particle of the first is where its twin
// is, moved by the jump (the settled particles' own step, a period-2 oscillation of ~0.3 h, is the same in both), and
// the jumped mesh stays closed.
TEST(Tesselator, ParticlesFollowAJointTranslation) {
  Example e = load("simple_biped.wrl");
  const float h = e.options.desiredRadius;
  SkeletonCache still(*e.character), jumping(*e.character);
  Tesselator a(e.options), b(e.options);
  Mesh mesh;
  a.settle(still, mesh);
  b.settle(jumping, mesh);
  const glm::vec3 jump(0.2f, 0.3f, 0.0f);
  const int pelvis = e.character->findJoint("Pelvis");
  jumping.setTranslation(pelvis, e.character->joints()[size_t(pelvis)].rest.translation + jump);
  jumping.update();
  still.update();
  a.update(still);
  b.update(jumping);
  const ParticleView pa = a.particles(), pb = b.particles();
  ASSERT_EQ(pa.size(), pb.size());
  std::map<uint64_t, glm::vec3> twin;
  for (size_t i = 0; i < pa.size(); ++i) twin[pa.ids[i]] = pa.positions[i];
  size_t followed = 0;
  for (size_t i = 0; i < pb.size(); ++i) {
    const auto it = twin.find(pb.ids[i]);
    ASSERT_NE(it, twin.end());
    if (glm::length(pb.positions[i] - (it->second + jump)) < 0.02f * h) ++followed;
  }
  // A few particles sit on the creases where two blend cliques meet (the field is only C0 there), where rounding
  // differences between the two poses send the next step apart; without translation in the differential transforms
  // none would follow.
  EXPECT_GT(double(followed), 0.98 * double(pb.size())) << followed << " of " << pb.size() << " followed the jump";
  EXPECT_LT(worstSurfaceDistance(jumping.field(), pb.positions), 0.5f * h);
  b.triangulate(mesh);
  EXPECT_EQ(analyzeTopology(mesh).boundaryEdges, 0u);
}

// Issue 15 "every frame closed and manifold": the biped at the thesis's fidelity (~900 particles) with arms, forearms
// and thighs swinging +-45 degrees at 90, 360 and 720 degrees per second, rendered at 60 Hz (3 updates each). Every
// mesh shown is a closed 2-manifold; the particle triangulation itself has no pinched vertex left (pass F), and the
// Marching Cubes fallback stands in for at most a few renders whose holes the repair could not close. Measured (600
// renders at 60 Hz, `puppeteer bench`): 0-3 fallbacks per speed; before pass F, 77-82 % of renders had 17-25
// non-manifold vertices.
class FastSwingAtThesisFidelity : public ::testing::TestWithParam<float> {};

TEST_P(FastSwingAtThesisFidelity, EveryRenderIsClosedAndManifold) {
  Example e = load("simple_biped.wrl");
  scaleToParticles(e.options, 900.0f);
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh;
  tess.settle(skel, mesh, 200);
  LimbSwing swing(*e.character, skel, true);
  const int renders = 90;
  size_t fallbacks = 0, cutFallbacks = 0, pinched = 0;
  for (int f = 0; f < renders; ++f) {
    swing.advance(GetParam() / 60.0f);
    tess.frame(skel, mesh);
    const MeshTopology t = analyzeTopology(mesh);
    ASSERT_TRUE(t.closedManifold()) << "render " << f << ": " << t.boundaryEdges << " boundary edges, "
                                    << t.nonManifoldEdges << " non-manifold edges, " << t.nonManifoldVertices
                                    << " non-manifold vertices";
    EXPECT_EQ(tess.stats().boundaryEdges, 0u);
    EXPECT_EQ(tess.stats().fallback,
              tess.stats().openEdges > 0 || tess.stats().pinchedVertices > 0 || tess.stats().cutOffParts > 0);
    if (!tess.stats().fallback) {  // a vertex per particle, then the surface rows' (on the surface, checked below)
      EXPECT_EQ(mesh.vertexCount(), tess.particles().size() + tess.stats().surfaceRowVertices);
    }
    // Every vertex a triangle uses is on the surface: |F - iso| / |grad F| within 0.02 desiredRadius.
    EXPECT_LT(worstUsedVertexError(skel.field(), mesh), 0.02f * e.options.desiredRadius) << "render " << f;
    pinched += tess.stats().pinchedVertices;
    fallbacks += tess.stats().fallback && tess.stats().cutOffParts == 0;
    cutFallbacks += tess.stats().cutOffParts > 0;
  }
  std::printf("%.0f deg/s: %zu of %d renders fell back to Marching Cubes for a hole, %zu for a part cut off\n",
              double(GetParam()), fallbacks, renders, cutFallbacks);
  EXPECT_EQ(pinched, 0u);
  EXPECT_LE(fallbacks * 20, size_t(renders));  // at most 5 % for a hole the repair could not close
}

INSTANTIATE_TEST_SUITE_P(Speeds, FastSwingAtThesisFidelity, ::testing::Values(90.0f, 360.0f, 720.0f));

// Folds (triangles winding against the field's outward normal at their centroid) are repaired by pass H, keeping every
// render closed and manifold: over a swing at ~900 particles at most a third of the folds are left (measured
// independently of the tesselator's own count, which never overstates them).
TEST(Tesselator, FoldsAreRepairedAndTheMeshStaysClosed) {
  size_t folds[2] = {0, 0};
  for (bool unfold : {false, true}) {
    Example e = load("simple_biped.wrl");
    scaleToParticles(e.options, 900.0f);
    e.options.unfold = unfold;
    SkeletonCache skel(*e.character);
    Tesselator tess(e.options);
    Mesh mesh;
    tess.settle(skel, mesh, 200);
    LimbSwing swing(*e.character, skel, false);
    for (int f = 0; f < 90; ++f) {
      swing.pose(45.0f * std::sin(float(f) * 0.1f));
      tess.frame(skel, mesh);
      ASSERT_TRUE(analyzeTopology(mesh).closedManifold()) << "render " << f << (unfold ? " with" : " without") << " H";
      const size_t measured = foldedTriangles(skel.field(), mesh);
      EXPECT_LE(tess.stats().foldedTriangles, measured) << "render " << f;
      if (!unfold) {
        EXPECT_EQ(tess.stats().foldedTriangles, 0u);
      }
      folds[unfold] += measured;
    }
  }
  std::printf("folds over 90 renders: %zu without pass H, %zu with\n", folds[0], folds[1]);
  ASSERT_GT(folds[0], 0u) << "the swing must fold some triangles for this test to mean anything";
  EXPECT_LE(6 * folds[1], folds[0]);  // 145 -> 20 (flips and removals alone: 145 -> 32)
}

// At ~900 particles a wrist or an ankle is a tube four to seven particles around, whose neighbours' normals are
// 60-90 degrees apart. The particle triangulation can cut a hand or a foot off at its neck: two closed caps instead of
// a tube, where Marching Cubes of the same field finds one surface. Such a render is shown as the Marching Cubes
// fallback (pass J): no mesh shown has a solid part cut off (against Marching Cubes at half desiredRadius, matched one
// for one every render) or a component missing. The particles' own triangulation still cuts parts off (not solved,
// docs/tesselator.md, "Parts cut off"): this guards what the fans' convex band, the repair's joined tube rims, its
// surface rows, pass F's opened pinches and split rims, the thin parts' local spacing and the wrong-way loops opened
// by their rims gained, 170 -> 102 -> 61 -> 41 -> 21 -> 2 of 300 renders.
TEST(Tesselator, HandsAndFeetStayConnectedAtThesisFidelity) {
  Example e = load("simple_biped.wrl");
  scaleToParticles(e.options, 900.0f);
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh, reference;
  tess.settle(skel, mesh, 200);
  LimbSwing swing(*e.character, skel, true);
  MarchingCubes marchingCubes;
  MarchingCubesOptions mc;
  mc.cellSize = 0.5f * e.options.desiredRadius;
  int cut = 0, particlesCut = 0;
  for (int f = 0; f < 300; ++f) {
    swing.advance(12.0f);
    tess.frame(skel, mesh);
    ASSERT_TRUE(analyzeTopology(mesh).closedManifold()) << "render " << f;
    ASSERT_TRUE(marchingCubes.polygonize(skel.field(), mc, reference));
    const ComponentMatch match = matchComponents(mesh, reference);
    EXPECT_EQ(match.missing, 0u) << "render " << f;
    cut += match.cutOff > match.cutOffCavities;
    particlesCut += tess.stats().cutOffParts > 0;
    EXPECT_EQ(tess.stats().cutOffParts > 0,
              tess.stats().fallback && tess.stats().openEdges == 0 && tess.stats().pinchedVertices == 0)
        << "render " << f << ": a render falls back for a closed triangulation only when it cut a part off";
  }
  std::printf("renders whose particle triangulation cut a part off: %d of 300 (shown cut: %d)\n", particlesCut, cut);
  EXPECT_EQ(cut, 0) << "renders shown with a solid part cut off";
  // The particles' own, measured 2 (against Marching Cubes at desiredRadius, as pass J asks): 18 (21 at half
  // desiredRadius) before the repair opened a wrong-way loop by its rim only, 41 with one spacing on thin parts, 42
  // with surface rows of one count only, 45 before a rim facing two pieces was split between them, 51 when pass F cut a
  // pinch between two pieces, 61 before surface rows and pieces told apart across edges, 66 when rims are joined only
  // straight across, 102 before the repair joined tube rims at all, 170 with fans within 72 degrees only
  EXPECT_GT(particlesCut, 0)
      << "the swing must cut a part off the particle triangulation for this test to mean anything";
  EXPECT_LE(particlesCut, 5);
}

// The file's fidelity (~2650 particles) at 30 Hz: swing:360 advances 12 degrees per render. Over 600 renders every
// mesh is closed and manifold, every used vertex of a particle triangulation lies within the stated 0.03
// desiredRadius of the surface, at most 2 % of renders fall back to Marching Cubes, no render keeps more than 10
// folded triangles, and no component is missing (docs/tesselator.md, "Every render checked"). At most one render may
// mesh a part apart from the body (Marching Cubes at half desiredRadius finds one surface where the mesh has two
// pieces): where the crossing feet pass through each other.
TEST(Tesselator, SixHundredRendersAtTheFilesFidelityAndThirtyHertz) {
  Example e = load("simple_biped.wrl");
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  Mesh mesh, reference;
  tess.settle(skel, mesh, 200);
  LimbSwing swing(*e.character, skel, true);
  MarchingCubes marchingCubes;
  MarchingCubesOptions mc;
  mc.cellSize = 0.5f * e.options.desiredRadius;
  size_t fallbacks = 0, worstFolds = 0, cut = 0;
  float worstOffset = 0.0f;
  for (int f = 0; f < 600; ++f) {
    swing.advance(360.0f / 30.0f);
    tess.frame(skel, mesh);
    const MeshTopology t = analyzeTopology(mesh);
    ASSERT_TRUE(t.closedManifold()) << "render " << f << ": " << t.boundaryEdges << " boundary edges, "
                                    << t.nonManifoldEdges << " non-manifold edges, " << t.nonManifoldVertices
                                    << " non-manifold vertices";
    fallbacks += tess.stats().fallback ? 1 : 0;
    worstFolds = std::max(worstFolds, foldedTriangles(skel.field(), mesh));
    if (!tess.stats().fallback) worstOffset = std::max(worstOffset, worstUsedVertexError(skel.field(), mesh));
    ASSERT_TRUE(marchingCubes.polygonize(skel.field(), mc, reference));
    const ComponentMatch match = matchComponents(mesh, reference);
    EXPECT_EQ(match.missing, 0u) << "render " << f;
    cut += match.cutOff > 0;
  }
  std::printf(
      "600 renders: %zu fell back, at most %zu folded, worst vertex %.4f desiredRadius off, %zu with a part cut "
      "off\n",
      fallbacks, worstFolds, double(worstOffset / e.options.desiredRadius), cut);
  // measured 0; 2 when pass F cut a pinch that was all that joined two pieces, 6 when the tube's rims were joined
  // through one middle ring at most (the head cut off at a neck opened up over several rings)
  EXPECT_LE(cut, 1u);
  EXPECT_LE(fallbacks * 50, 600u);
  EXPECT_LE(worstFolds, 10u);
  EXPECT_LT(worstOffset, 0.03f * e.options.desiredRadius);
}

// The fallback: a triangulation left open (here: the arms jump 60 degrees under particles that do not follow, and no
// hole may be filled) is replaced by Marching Cubes of the
// same field at cell desiredRadius, closed and manifold; without closedFallback the open triangulation is returned.
TEST(Tesselator, AnOpenTriangulationFallsBackToMarchingCubes) {
  Example e = load("simple_biped.wrl");
  SkeletonCache skel(*e.character);
  e.options.maxHoleLoop = 0;  // no hole is filled
  for (bool fallback : {true, false}) {
    e.options.closedFallback = fallback;
    Tesselator tess(e.options);
    Mesh mesh;
    tess.settle(skel, mesh, 100);
    SkeletonCache jumped(*e.character);
    jumped.setRotation("L_UpperArm", glm::angleAxis(1.0f, glm::vec3(0, 0, 1)));
    jumped.setRotation("R_UpperArm", glm::angleAxis(-1.0f, glm::vec3(0, 0, 1)));
    jumped.update();
    tess.update(jumped.field());  // a bare field: no differential transforms
    tess.triangulate(mesh);
    ASSERT_GT(tess.stats().openEdges, 0u) << "the case must leave the particle triangulation open";
    EXPECT_EQ(tess.stats().fallback, fallback);
    EXPECT_EQ(tess.stats().fallbacks > 0, fallback);
    const MeshTopology t = analyzeTopology(mesh);
    EXPECT_EQ(t.closedManifold(), fallback);
    EXPECT_EQ(tess.stats().boundaryEdges, t.boundaryEdges);
    if (fallback) EXPECT_LT(worstSurfaceError(jumped.field(), mesh), 0.25f * e.options.desiredRadius);
    else EXPECT_EQ(mesh.vertexCount(), tess.particles().size());
  }
}

// Issue 15 "still means still": on a static pose the settled biped comes to rest within a bounded number of updates
// (at the thesis's ~900 particles and at the file's ~2650): then no fission, fusion or death, no particle moves by
// 1 % of desiredRadius, and every triangulation gives the same triangles. Before the rest schedule a period-2
// oscillation moved particles ~0.55 desiredRadius per update with ~7 (900) and ~30 (2650) fissions and fusions per
// update. When a limb moves, the particles move again, and when it stops they come back to rest.
TEST(Tesselator, AStillBipedComesToRestAndWakesWhenALimbMoves) {
  for (float particles : {900.0f, 2650.0f}) {
    Example e = load("simple_biped.wrl");
    scaleToParticles(e.options, particles);
    const float h = e.options.desiredRadius;
    SkeletonCache skel(*e.character);
    Tesselator tess(e.options);
    Mesh mesh, previous;
    const int settled = tess.settle(skel, mesh, 300);
    // Updates until the mesh and the particles stop changing, and how much they do per update once they have.
    auto stillAfter = [&](int limit) {
      int still = 0, u = 0;
      for (; u < limit && still < 10; ++u) {
        const std::vector<glm::vec3> before(tess.particles().positions.begin(), tess.particles().positions.end());
        const TesselatorStats s0 = tess.stats();
        previous = mesh;
        tess.update(skel);
        tess.triangulate(mesh);
        const ParticleView p = tess.particles();
        float motion = p.size() == before.size() ? 0.0f : h;
        for (size_t i = 0; i < p.size() && p.size() == before.size(); ++i)
          motion = std::max(motion, glm::length(p.positions[i] - before[i]));
        const bool quiet = tess.stats().fissions == s0.fissions && tess.stats().fusions == s0.fusions &&
                           tess.stats().deaths == s0.deaths && motion < 0.01f * h && mesh == previous;
        still = quiet ? still + 1 : 0;
        EXPECT_EQ(analyzeTopology(mesh).closedManifold(), true);
      }
      return still == 10 ? u - 10 : -1;
    };
    const int rest = stillAfter(100);
    std::printf("%.0f particles: settled after %d updates, still %d updates later\n", double(particles), settled, rest);
    ASSERT_GE(rest, 0) << particles << " particles never came to rest";
    EXPECT_LE(rest, 40);
    // A limb moves: the particles follow and work again (not frozen), then come back to rest.
    const TesselatorStats s0 = tess.stats();
    for (int u = 0; u < 10; ++u) {
      skel.setRotation("L_UpperArm", glm::angleAxis(0.05f * float(u + 1), glm::vec3(0, 0, 1)));
      skel.update();
      tess.update(skel);
    }
    EXPECT_GT(tess.stats().fissions + tess.stats().fusions + tess.stats().deaths,
              s0.fissions + s0.fusions + s0.deaths) << particles;
    tess.triangulate(mesh);
    EXPECT_GE(stillAfter(100), 0) << particles << " particles did not come back to rest";
  }
}

TEST(Tesselator, FlatFieldWithoutSkeletonAndReset) {
  Example e = load("textured_blobs.wrl");
  SkeletonCache skel(*e.character);
  Tesselator tess(e.options);
  for (int u = 0; u < 60; ++u) tess.update(skel.field());
  Mesh mesh;
  tess.triangulate(mesh);
  EXPECT_EQ(analyzeTopology(mesh).boundaryEdges, 0u);
  tess.reset();
  EXPECT_EQ(tess.particles().size(), 0u);
  tess.triangulate(mesh);
  EXPECT_EQ(mesh.triangleCount(), 0u);
}

// Issue 15 "any scene": sixteen of swarm_1000.wrl's balls, those within 0.6 m of an air pocket 5-6 cm across that
// they enclose. Its wall's particles, 5 cm apart, are 80-110 degrees apart round it, and the fans take no neighbour
// in front of the tangent plane, so before pass I (closePockets) the mesh missed the pocket: 1 component where
// Marching Cubes finds 2. Now its particles get their hull, facing into the pocket: matched one for one, on 1 and 2
// threads alike.
TEST(Tesselator, AnAirPocketInsideTheSwarmIsMeshedInsideOut) {
  const char* balls[] = {"0.6079 -1.7000 -0.8317 radius 0.3087",  "0.3643 -1.3259 -0.0453 radius 0.2937",
                         "0.6306 -1.1158 -0.6018 radius 0.2583",  "0.5320 -1.5324 -0.1632 radius 0.2815",
                         "0.2514 -1.2637 -0.7819 radius 0.2952",  "0.8281 -1.6283 -0.5042 radius 0.3418",
                         "-0.0075 -1.2346 -0.8166 radius 0.1577", "0.8146 -1.3566 -0.5919 radius 0.2616",
                         "0.0969 -1.7058 -0.9485 radius 0.2615",  "0.1709 -1.3484 -0.4078 radius 0.3118",
                         "0.5933 -1.6803 -0.9900 radius 0.2567",  "0.4301 -1.2528 -0.0334 radius 0.1859",
                         "0.4903 -1.7432 -0.3790 radius 0.2852",  "0.6812 -1.7421 -0.4046 radius 0.1641",
                         "0.1889 -1.2941 -0.3841 radius 0.2241",  "0.2384 -1.1953 -0.2919 radius 0.3342"};
  std::string text =
      "#VRML V2.0 utf8\nMarchingCubes {\n  cellSize 0.025\n  sceneGraph ExponentialBlend {\n"
      "    variance 0.25\n    children [\n";
  for (const char* b : balls) text += std::string("      Metaball { center ") + b + " }\n";
  text += "    ]\n  }\n}\n";
  Example e = fromRead(readScene(text, "swarm_pocket.wrl"));
  ASSERT_TRUE(e.character);
  SkeletonCache skel(*e.character);
  TesselatorOptions o = TesselatorOptions::forScene(e.scene, skel.field());
  EXPECT_FLOAT_EQ(o.desiredRadius, 0.05f);  // twice the scene's cellSize, as the swarm's
  MarchingCubesOptions mc;
  mc.cellSize = 0.5f * o.desiredRadius;
  const Mesh referenceMesh = polygonize(skel.field(), mc);
  const ComponentMatch itself = matchComponents(referenceMesh, referenceMesh);
  ASSERT_EQ(itself.components, 2u);
  std::vector<uint32_t> indices[2];
  for (int threads : {1, 2}) {
    o.threads = threads;
    o.closedFallback = false;  // the particles' own triangulation
    Tesselator tess(o);
    Mesh mesh;
    tess.settle(skel, mesh, 400);
    EXPECT_TRUE(analyzeTopology(mesh).closedManifold()) << threads << " threads";
    const ComponentMatch match = matchComponents(mesh, referenceMesh);
    EXPECT_EQ(match.components, 2u) << threads << " threads";
    EXPECT_EQ(match.missing, 0u) << threads << " threads";
    EXPECT_EQ(match.cutOff, 0u) << threads << " threads";
    // The pocket faces into itself: the mesh's volume is the solid's less the pocket's.
    Mesh outer = mesh, pocket = mesh;
    outer.indices.clear(), pocket.indices.clear();
    std::vector<uint32_t> label;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
      const glm::vec3 c = (mesh.position(mesh.indices[3 * t]) + mesh.position(mesh.indices[3 * t + 1]) +
                           mesh.position(mesh.indices[3 * t + 2])) /
                          3.0f;
      Mesh& to = glm::length(c - glm::vec3(0.486f, -1.432f, -0.585f)) < 0.06f ? pocket : outer;
      to.indices.insert(to.indices.end(), &mesh.indices[3 * t], &mesh.indices[3 * t + 3]);
    }
    ASSERT_GT(pocket.triangleCount(), 3u) << threads << " threads";
    EXPECT_TRUE(analyzeTopology(pocket).closedManifold()) << threads << " threads";
    EXPECT_LT(signedVolume(pocket), 0.0) << threads << " threads";
    EXPECT_GT(signedVolume(outer), 0.0) << threads << " threads";
    indices[threads - 1] = mesh.indices;
  }
  EXPECT_EQ(indices[0], indices[1]) << "the same triangles on 1 and 2 threads";
}

// Issue 15, "any scene": a scene without a Tesselator3MP node gets its lengths from its feature size
// (TesselatorOptions::forField). Twelve separate small metaballs (radii 0.15-0.35 m, 1.2 m apart) and two clusters of
// five blended ones, variance 0.25 like swarm_1000.wrl: with the old default desiredRadius of 0.3 m the small balls
// had 3-10 particles and no triangle; now settle() gives a closed, manifold mesh with as many components as Marching
// Cubes finds at half desiredRadius (14), every particle but a few in a triangle, on 1 and 2 threads alike.
// A straight limb 0.6 m long of the given radius, alone, and the options its thin-parts tests run it with
// (desiredRadius 0.05 m, the query radius and hash cube in the file's proportions).
Example straightLimb(float radius) {
  const std::string r = std::to_string(radius);
  return fromRead(
      readScene("#VRML V2.0 utf8\nExponentialBlend { variance 0.25 children [\n"
                "  LineSeg { point1 0 0 0 point2 0 0.6 0 radius1 " +
                    r + " radius2 " + r + " }\n] }\n",
                "limb.wrl"));
}
TesselatorOptions limbOptions(bool resolveThinParts) {
  TesselatorOptions o;
  o.desiredRadius = 0.05f;
  o.queryRadius = 0.05f * 0.8f / 0.3f;
  o.cubeSize = 0.1f;
  o.resolveThinParts = resolveThinParts;
  return o;
}

// A limb thinner than desiredRadius (radius 0.6 of it): with the thin-parts rule its particles split at the scaled
// radius, so that about five of them ring it (and it meshes closed as one piece); with the thesis's one spacing about
// three, too few for a tube. The ring is counted from the particles of a slab across the limb's middle, averaged over
// 20 updates: a hexagonal packing of n particles on the slab's area A has spacing s = sqrt(A / (n sqrt(3) / 2)), and
// 2 pi r / s of them round the limb.
TEST(Tesselator, AThinLimbIsRingedByFiveParticlesNotThree) {
  const float r = 0.03f, slab = 0.2f;
  const Example e = straightLimb(r);
  ASSERT_TRUE(e.character);
  SkeletonCache skel(*e.character);
  auto ring = [&](bool resolve, MeshTopology& t) {
    TesselatorOptions o = limbOptions(resolve);
    o.closedFallback = false;
    Tesselator tess(o);
    Mesh mesh;
    EXPECT_LT(tess.settle(skel, mesh, 400), 400);
    t = analyzeTopology(mesh);
    double n = 0.0;
    for (int update = 0; update < 20; ++update) {
      tess.update(skel.field());
      for (const glm::vec3& p : tess.particles().positions) n += std::abs(p.y - 0.3f) < 0.5f * slab;
    }
    n /= 20.0;
    const double spacing = std::sqrt(2.0 * 3.14159265 * r * slab / (n * std::sqrt(3.0) / 2.0));
    return 2.0 * 3.14159265 * r / spacing;
  };
  MeshTopology thin, uniform;
  const double withRule = ring(true, thin), without = ring(false, uniform);
  EXPECT_TRUE(thin.closedManifold()) << thin.boundaryEdges << " boundary edges";
  EXPECT_EQ(thin.components, 1u);
  EXPECT_GT(withRule, 4.5) << "particles round the limb with the rule";
  EXPECT_LT(without, 3.6) << "and with the one spacing";
}

// The thin-parts rule's knee: a limb just under desiredRadius thick (radius 0.96 of it) keeps the full spacing, so the
// rule changes nothing there: the same particles and triangles, bit for bit, as with the one spacing (with the scale
// equal to the thickness up to 1, such a part packed a few per cent denser than the body it joins, and flubber's arms
// folded more often; docs/tesselator.md, "Thin parts").
TEST(Tesselator, ALimbNearlyAsThickAsTheSpacingKeepsTheOneSpacing) {
  const Example e = straightLimb(0.048f);
  ASSERT_TRUE(e.character);
  SkeletonCache skel(*e.character);
  auto settle = [&](bool resolve, std::vector<glm::vec3>& positions) {
    Tesselator tess(limbOptions(resolve));
    Mesh mesh;
    tess.settle(skel, mesh, 200);
    positions.assign(tess.particles().positions.begin(), tess.particles().positions.end());
    return mesh;
  };
  std::vector<glm::vec3> withRule, without;
  const Mesh a = settle(true, withRule), b = settle(false, without);
  ASSERT_GT(withRule.size(), 50u);
  EXPECT_EQ(withRule, without) << withRule.size() << " against " << without.size() << " particles";
  EXPECT_EQ(a.indices, b.indices);
  EXPECT_TRUE(analyzeTopology(a).closedManifold());
}

TEST(Tesselator, ManySmallBlobsMeshClosedWithEveryComponent) {
  std::string text = "#VRML V2.0 utf8\nExponentialBlend {\n  variance 0.25\n  children [\n";
  uint32_t rng = 12345u;
  auto uniform = [&](float lo, float hi) {
    rng = rng * 1664525u + 1013904223u;
    return lo + (hi - lo) * float(rng >> 8) / float(1u << 24);
  };
  auto ball = [&](float x, float y, float z, float r) {
    text += "    Metaball { center " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) +
            " radius " + std::to_string(r) + " }\n";
  };
  for (int i = 0; i < 12; ++i) ball(1.2f * float(i % 4), 1.2f * float(i / 4), 0.0f, uniform(0.15f, 0.35f));
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < 5; ++k)
      ball(2.0f * float(c) + uniform(-0.3f, 0.3f), uniform(-0.3f, 0.3f), 2.0f + uniform(-0.3f, 0.3f),
           uniform(0.15f, 0.35f));
  text += "  ]\n}\n";
  Example e = fromRead(readScene(text, "many_blobs.wrl"));
  ASSERT_TRUE(e.character);
  SkeletonCache skel(*e.character);

  TesselatorOptions o = TesselatorOptions::forField(skel.field());
  EXPECT_NEAR(o.desiredRadius, 0.5f * 0.15f, 0.5f * 0.05f);  // half the smallest radius (>= 0.15 m)
  EXPECT_FLOAT_EQ(o.queryRadius / o.desiredRadius, 0.8f / 0.3f);
  EXPECT_GE(float(1 << o.bitsPerDim) * o.cubeSize, 4.0f);  // the hash spans the scene
  MarchingCubesOptions mc;
  mc.cellSize = 0.5f * o.desiredRadius;
  const Mesh referenceMesh = polygonize(skel.field(), mc);
  const size_t reference = analyzeTopology(referenceMesh).components;
  EXPECT_EQ(reference, 14u);

  std::vector<uint32_t> indices[2];
  for (int threads : {1, 2}) {
    o.threads = threads;
    o.closedFallback = false;  // the particles' own triangulation
    Tesselator tess(o);
    Mesh mesh;
    const int updates = tess.settle(skel, mesh, 400);
    EXPECT_LT(updates, 400) << threads << " threads";
    const MeshTopology t = analyzeTopology(mesh);
    EXPECT_TRUE(t.closedManifold()) << t.boundaryEdges << " boundary edges, " << t.nonManifoldVertices
                                    << " non-manifold vertices";
    EXPECT_EQ(t.components, reference);
    const ComponentMatch match = matchComponents(mesh, referenceMesh);  // one for one, not just as many
    EXPECT_EQ(match.missing, 0u) << threads << " threads";
    EXPECT_EQ(match.cutOff, 0u) << threads << " threads";
    EXPECT_LE(t.unusedVertices * 50, mesh.vertexCount()) << t.unusedVertices << " of " << mesh.vertexCount();
    indices[threads - 1] = mesh.indices;
  }
  EXPECT_EQ(indices[0], indices[1]);

  // The old default spacing (0.3 m, as large as the blobs) missed components (what issue 15 measured on the swarm).
  // It reaches every one now that particles split at a scaled radius on parts thinner than desiredRadius.
  TesselatorOptions coarse;
  coarse.closedFallback = false;
  Tesselator tess(coarse);
  Mesh mesh;
  tess.settle(skel, mesh, 200);
  const MeshTopology t = analyzeTopology(mesh);
  EXPECT_TRUE(t.closedManifold()) << t.boundaryEdges << " boundary edges";
  EXPECT_EQ(t.components, reference);
  EXPECT_EQ(matchComponents(mesh, referenceMesh).missing, 0u);
}

// ---- The update's phases one at a time (tesselator_state.h), on particles spread evenly over a sphere ---------

TEST(TesselatorPhases, ComputeForcesKeepsVelocitiesTangentAndMarksStrays) {
  test::Sphere sphere(600);
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

TEST(TesselatorPhases, IntegrationEndsOnTheSurface) {
  test::Sphere sphere(600);
  auto& s = sphere.s;
  computeForces(s, sphere.field, sphere.options, false);
  integrateParticles(s, sphere.field, sphere.options);
  EXPECT_FALSE(s.nbrValid) << "particles moved";
  for (size_t i = 0; i < s.size(); ++i) {
    EXPECT_NEAR(glm::length(s.pos[i]), test::kRadius, 0.01f * sphere.options.desiredRadius) << i;
    EXPECT_GE(s.sigma[i], 0.25f * sphere.options.desiredRadius * 0.999f);
    EXPECT_LE(s.sigma[i], 1.5f * sphere.options.desiredRadius * 1.001f);
  }
}

TEST(TesselatorPhases, AddAndDeleteFusesTheYoungerOfTwoAndFissionsTheLargest) {
  test::Sphere sphere(600);
  auto& s = sphere.s;
  const float h = sphere.options.desiredRadius;
  // Particle "young" sits right next to "old" (and is younger: a larger id); particle "big" is at the largest radius.
  const glm::vec3 p = s.pos[0], t = glm::normalize(glm::cross(p, glm::vec3(0.3f, 0.4f, 0.5f)));
  s.add(glm::normalize(p + 0.1f * h * t) * test::kRadius, -p, h, 0);
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
  o.threads = 2;
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
  quiet.threads = 2;
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
