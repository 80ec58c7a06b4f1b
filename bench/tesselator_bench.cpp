// Particle tesselator benchmarks (issue 3 goals): one update plus one triangulation of the settled biped at about
// 900 particles and 4x that, and the cost growth from 1k to 64k particles on a sphere. Report CPU time.
// One iteration is exactly the "update with triangulation": update() then triangulate(), as frame() does with
// updatesPerRender = 1 (the pose is static, so differential transforms are identity).
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"

namespace {

using namespace imps;

// Biped with desiredRadius scaled so that about `particles` particles cover it (2685 at the file's 0.025 m).
void BM_BipedUpdateAndTriangulate(benchmark::State& state) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  if (!scene) {
    state.SkipWithError("cannot read simple_biped.wrl");
    return;
  }
  auto ch = Character::fromScene(*scene);
  TesselatorOptions o = TesselatorOptions::fromNode(std::get<Tesselator3MPNode>(scene->polygonizer));
  const float scale = std::sqrt(2685.0f / float(state.range(0)));
  o.desiredRadius *= scale;
  o.queryRadius *= scale;
  o.cubeSize *= scale;
  o.threads = int(state.range(1));
  SkeletonCache skel(*ch);
  Tesselator tess(o);
  Mesh mesh;
  tess.settle(skel, mesh, 300);
  for (auto _ : state) {
    tess.update(skel);
    tess.triangulate(mesh);
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  state.counters["particles"] = double(tess.stats().particles);
  state.counters["boundary"] = double(tess.stats().boundaryEdges);
  state.counters["updates_per_s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BipedUpdateAndTriangulate)->Args({900, 1})->Args({900, 2})->Args({3600, 2})->Unit(benchmark::kMillisecond);

// One metaball of radius 1 with desiredRadius chosen for about range(0) particles: the cost should grow linearly.
void BM_SphereScaling(benchmark::State& state) {
  const float n = float(state.range(0));
  TesselatorOptions o;
  o.desiredRadius = std::sqrt(4.0f * 3.14159265f / (1.15f * n));
  o.queryRadius = 2.5f * o.desiredRadius;
  o.cubeSize = o.queryRadius;
  o.bitsPerDim = 7;
  o.threads = 2;
  Field field({Primitive::metaball(glm::vec3(0.0f), 1.0f)}, {-1.0f}, {glm::vec3(0.8f)}, BlendFunction{},
              BlendSets::all(1));
  Tesselator tess(o);
  for (int u = 0; u < 60; ++u) tess.update(field);
  Mesh mesh;
  for (auto _ : state) {
    tess.update(field);
    tess.triangulate(mesh);
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  state.counters["particles"] = double(tess.stats().particles);
  state.counters["boundary"] = double(tess.stats().boundaryEdges);
  state.counters["us_per_particle"] =
      benchmark::Counter(double(state.iterations()) * double(tess.stats().particles),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_SphereScaling)->RangeMultiplier(4)->Range(1024, 65536)->Unit(benchmark::kMillisecond);

}  // namespace
