// SPDX-License-Identifier: MIT
// Texturing (issue 11): what textureMesh adds to a frame of the biped, and the frame without textures (which must
// cost what it did before texturing existed: compare BM_BipedFrame/textured:0 with the same benchmark built from
// the commit before, run interleaved).
// One iteration is one frame of the app's Marching Cubes path: a new elbow angle, the skeleton cache's update,
// polygonize at 0.025 m cells, then textureMesh (a no-op without generators).
#include <benchmark/benchmark.h>

#include <string>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/texturing.h"

namespace {

using namespace imps;

// Every shape of the graph gets a default TexGenSphere and an image (the file is never read here).
void textureEveryShape(SceneNode& node) {
  if (auto* shape = std::get_if<ShapeNode>(&node)) {
    shape->texGen = TexGenNode{};
    shape->texture = ImageTextureNode{"skin.png", {}};
  } else if (auto* t = std::get_if<TransformNode>(&node)) {
    for (SceneNode& child : t->children) textureEveryShape(child);
  } else if (auto* b = std::get_if<BlendNode>(&node)) {
    for (SceneNode& child : b->children) textureEveryShape(child);
  }
}

void BM_BipedFrame(benchmark::State& state) {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  if (!scene) {
    state.SkipWithError("cannot read simple_biped.wrl");
    return;
  }
  if (state.range(0)) textureEveryShape(*scene->sceneGraph());
  auto character = Character::fromScene(*scene);
  SkeletonCache skeleton(*character);
  MarchingCubes mc;
  MarchingCubesOptions options;
  options.cellSize = 0.025f;
  options.threads = 1;
  Mesh mesh;
  int frame = 0;
  const int elbow = character->findJoint("L_Forearm");
  for (auto _ : state) {
    if (elbow >= 0) skeleton.setRotation(elbow, glm::angleAxis(0.01f * float(frame++ % 100), glm::vec3(0, 0, 1)));
    skeleton.update();
    mc.polygonize(skeleton.field(), options, mesh);
    textureMesh(mesh, skeleton, 1);
    benchmark::DoNotOptimize(mesh.indices.data());
  }
  state.counters["vertices"] = double(mesh.vertexCount());
  state.counters["layers"] = double(mesh.layerGens.size());
}
BENCHMARK(BM_BipedFrame)->ArgName("textured")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
