// SPDX-License-Identifier: MIT
// libFuzzer target for scene -> character -> polygonizer settings: whatever scene reads either fails to build a
// character with diagnostics, or builds one whose polygonizer settings are honoured within bounded work: the Marching
// Cubes grid is planned (and refused beyond its cell limit), a small one is meshed closed, and the particle
// tesselator runs a few updates within its particle limit (its carried texture coordinates finite). Never a crash,
// an abort or unbounded memory.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <variant>

#include "fuzz_check.h"
#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "imps/texturing.h"

namespace {

void marchingCubes(const imps::Scene& scene, const imps::Field& field) {
  imps::MarchingCubesOptions o;
  if (const auto* mc = std::get_if<imps::MarchingCubesNode>(&scene.polygonizer)) {
    o.cellSize = mc->cellSize;
    o.gridResolution = {mc->xResolution, mc->yResolution, mc->zResolution};
    o.threads = mc->numThreads;
  }
  o.threads = 1;  // the fuzzer runs single-threaded; the thread count's bound is checked by the reader
  o.maxCells = 32 * 32 * 32;  // keep each input fast: larger grids are planned, then refused
  auto plan = imps::planGrid(field, o);
  const imps::Mesh mesh = imps::polygonize(field, o);
  if (!plan) {
    FUZZ_CHECK(mesh.triangleCount() == 0);
    return;
  }
  FUZZ_CHECK(size_t(plan->x) * size_t(plan->y) * size_t(plan->z) <= o.maxCells);
  const imps::MeshTopology t = imps::analyzeTopology(mesh);
  if (t.boundaryEdges != 0) {
    std::fprintf(stderr, "Marching Cubes mesh has %zu boundary edges\n", t.boundaryEdges);
    std::abort();
  }
}

void particles(const imps::Scene& scene, const imps::SkeletonCache& skeleton) {
  imps::TesselatorOptions o;
  if (const auto* t = std::get_if<imps::Tesselator3MPNode>(&scene.polygonizer))
    o = imps::TesselatorOptions::fromNode(*t);
  o.threads = 1;
  o.maxParticles = 512;
  imps::Tesselator tess(o);
  for (int u = 0; u < 2; ++u) {
    tess.update(skeleton);
    FUZZ_CHECK(tess.particles().size() <= o.maxParticles);
  }
  imps::Mesh mesh;
  tess.triangulate(mesh);
  // One vertex per particle then the surface rows', unless the triangulation could not be closed and Marching Cubes
  // stood in for it (Tesselator::triangulate's fallback, e.g. a radius-3 ball capped at 512 particles).
  FUZZ_CHECK(tess.stats().fallback || mesh.vertexCount() == tess.particles().size() + tess.stats().surfaceRowVertices);
  // Textures (and, with textureMode "carried", the particles' carried coordinates): one more update carries them.
  imps::textureMesh(mesh, skeleton, 1);
  tess.carryTexcoords(mesh);
  FUZZ_CHECK(mesh.layerTexcoords.empty() || mesh.layerTexcoords.size() == 4 * mesh.vertexCount());
  tess.update(skeleton);
  tess.triangulate(mesh);
  imps::textureMesh(mesh, skeleton, 1);
  tess.carryTexcoords(mesh);
  for (const float x : mesh.layerTexcoords) FUZZ_CHECK(std::isfinite(x));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto scene = imps::readScene(text, "fuzz.wrl");
  if (!scene) return 0;
  auto character = imps::Character::fromScene(*scene);
  if (!character) {
    FUZZ_CHECK(character.error().hasErrors());
    return 0;
  }
  if (character->primitives().size() > 64) return 0;  // keeps each input fast; the reader fuzzer covers big scenes
  imps::SkeletonCache skeleton(*character);
  marchingCubes(*scene, skeleton.field());
  particles(*scene, skeleton);
  return 0;
}
