// Tests for the particle tesselator (imps/src/tesselator*.cpp): convergence, closed meshes, determinism, blend rule,
// recovery after fast motion, no NaN.
#include "imps/tesselator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"

namespace imps {
namespace {

struct Example {
  Scene scene;
  std::optional<Character> character;
  TesselatorOptions options;
};

Example load(const std::string& name) {
  Example e;
  auto read = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/" + name);
  if (!read) ADD_FAILURE() << read.error().str();
  e.scene = std::move(*read);
  auto c = Character::fromScene(e.scene);
  if (!c) ADD_FAILURE() << c.error().str();
  e.character = std::move(*c);
  if (const auto* node = std::get_if<Tesselator3MPNode>(&e.scene.polygonizer)) e.options = TesselatorOptions::fromNode(*node);
  return e;
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
  EXPECT_LT(worstSurfaceError(skel.field(), mesh), 0.01f * e.options.desiredRadius);
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
  e.options.numThreads = threads;
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
      const auto& nb = ch.blendNeighbours(size_t(it->second));
      EXPECT_TRUE(std::binary_search(nb.begin(), nb.end(), uint32_t(o)))
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

}  // namespace
}  // namespace imps
