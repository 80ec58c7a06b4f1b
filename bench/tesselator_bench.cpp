// SPDX-License-Identifier: MIT
// Particle tesselator benchmarks (issue 3 goals): one update plus one triangulation of the settled biped at about
// 900 particles and 4x that, the same for the biped swinging its limbs (issue 15's speed guard), and the cost growth
// from 1k to 64k particles on a sphere. Report CPU time.
// One iteration is exactly the "update with triangulation": update() then triangulate(), as frame() does with
// updatesPerRender = 1. In BM_BipedUpdateAndTriangulate the pose is static, so the particles come to rest during the
// warm-up (docs/tesselator.md, "Coming to rest") and an iteration is little more than the triangulation; in
// BM_SwingingBipedUpdateAndTriangulate every iteration poses the limbs anew, so every update does its full work.
#include <benchmark/benchmark.h>

#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"

namespace {

using namespace imps;

// The biped and its tesselator options with desiredRadius scaled so that about `particles` particles cover it
// (2685 at the file's 0.025 m), on `threads` threads; nullopt (and the benchmark skipped) when the file does not read.
std::optional<std::pair<Character, TesselatorOptions>> scaledBiped(benchmark::State& state, int particles,
                                                                   int threads) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  auto ch = scene ? Character::fromScene(*scene) : std::expected<Character, Diagnostics>(std::unexpect);
  if (!ch) {
    state.SkipWithError("cannot read simple_biped.wrl");
    return std::nullopt;
  }
  TesselatorOptions o = TesselatorOptions::fromNode(std::get<Tesselator3MPNode>(scene->polygonizer));
  const float scale = std::sqrt(2685.0f / float(particles));
  o.desiredRadius *= scale;
  o.queryRadius *= scale;
  o.cubeSize *= scale;
  o.threads = threads;
  return std::pair{std::move(*ch), o};
}

// The settled biped: range(0) particles, range(1) threads.
void BM_BipedUpdateAndTriangulate(benchmark::State& state) {
  auto biped = scaledBiped(state, int(state.range(0)), int(state.range(1)));
  if (!biped) return;
  auto& [character, o] = *biped;
  const Character* ch = &character;
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

// The moving biped: arms, forearms and thighs swing +-45 degrees as a triangle wave at 360 degrees per second, one
// 30 Hz step (12 degrees) per iteration, as `puppeteer bench examples/simple_biped.wrl --motion swing:360` does with
// updatesPerRender = 1. Each iteration poses the skeleton (a few microseconds), updates (differential transforms and
// the full dynamics: the field changes shape, so the particles never come to rest) and triangulates (the Marching
// Cubes fallback included when a render needs it; counted in "fallbacks"). range(0): particles as above (2685 is the
// file's own desiredRadius); range(1): threads.
void BM_SwingingBipedUpdateAndTriangulate(benchmark::State& state) {
  auto biped = scaledBiped(state, int(state.range(0)), int(state.range(1)));
  if (!biped) return;
  auto& [character, o] = *biped;
  const Character* ch = &character;
  o.updatesPerRender = 1;
  SkeletonCache skel(*ch);
  std::vector<int> joints;
  std::vector<glm::quat> rest;
  for (const char* name : {"L_UpperArm", "R_UpperArm", "L_Thigh", "R_Thigh", "L_Forearm", "R_Forearm"}) {
    const int j = ch->findJoint(name);
    if (j < 0) {
      state.SkipWithError("simple_biped.wrl lacks a swinging joint");
      return;
    }
    joints.push_back(j);
    rest.push_back(skel.local(j).rotation);
  }
  constexpr double kAmplitude = 45.0, kStep = 360.0 / 30.0;  // degrees; per iteration
  double angle = 0.0, direction = 1.0;
  auto pose = [&] {
    angle += direction * kStep;
    if (angle > kAmplitude) angle = 2 * kAmplitude - angle, direction = -1.0;
    if (angle < -kAmplitude) angle = -2 * kAmplitude - angle, direction = 1.0;
    for (size_t k = 0; k < joints.size(); ++k) {
      const float a = float(glm::radians(angle)) * (k % 2 == 0 ? 1.0f : -1.0f);
      skel.setRotation(joints[k], rest[k] * glm::angleAxis(a, glm::vec3(0, 0, 1)));
    }
    skel.update();
  };
  Tesselator tess(o);
  Mesh mesh;
  tess.settle(skel, mesh, 300);
  for (int warm = 0; warm < 30; ++warm) {  // a full swing cycle is 15 steps: reach the moving steady state
    pose();
    tess.update(skel);
    tess.triangulate(mesh);
  }
  const uint64_t fallbacks0 = tess.stats().fallbacks;
  for (auto _ : state) {
    pose();
    tess.update(skel);
    tess.triangulate(mesh);
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  state.counters["particles"] = double(tess.stats().particles);
  state.counters["fallbacks"] = double(tess.stats().fallbacks - fallbacks0);
  state.counters["updates_per_s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SwingingBipedUpdateAndTriangulate)
    ->Args({900, 1})
    ->Args({900, 2})
    ->Args({2685, 2})
    ->Unit(benchmark::kMillisecond);

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
