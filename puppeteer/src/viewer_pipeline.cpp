// SPDX-License-Identifier: MIT
// The viewer's frame pipeline: pose → skeleton cache → polygonizer → mesh.
#include "viewer_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <utility>
#include <variant>

#include "imps/texturing.h"

namespace imps::app {
namespace {

}  // namespace

ViewerPipeline::ViewerPipeline(Scene scene, Character character, const PipelineOptions& options)
    : scene_(std::move(scene)),
      character_(std::make_unique<Character>(std::move(character))),
      skeleton_(std::make_unique<SkeletonCache>(*character_)),
      options_(options) {
  const Box rest = skeleton_->field().surfaceBounds();
  if (!rest.empty()) restBounds_ = MeshBounds{rest.lo, rest.hi};
  TesselatorOptions t = TesselatorOptions::forScene(scene_, skeleton_->field());
  if (options_.threads >= 0) t.threads = options_.threads;
  if (options_.textureMode) t.textureMode = *options_.textureMode;
  tesselator_ = std::make_unique<Tesselator>(t);
  mcOptions_.resolution = options_.mcResolution;
  mcOptions_.threads = t.threads;
  if (const auto* node = std::get_if<MarchingCubesNode>(&scene_.polygonizer)) {
    mcOptions_.cellSize = node->cellSize;
    mcOptions_.gridResolution = {node->xResolution, node->yResolution, node->zResolution};
    mcOptions_.threads = node->numThreads;
  }
}

void ViewerPipeline::setPlacement(const Rigid& placement) {
  skeleton_->setPlacement(placement);
  skeleton_->update();
  const Box rest = skeleton_->field().surfaceBounds();
  restBounds_ = rest.empty() ? MeshBounds{} : MeshBounds{rest.lo, rest.hi};
}

void ViewerPipeline::setPolygonizer(Polygonizer p) {
  if (p == options_.polygonizer) return;
  options_.polygonizer = p;
  // Particles that sat still while Marching Cubes ran would miss the skipped differential transforms.
  if (p == Polygonizer::Particles) resetPolygonizer();
}

void ViewerPipeline::resetPolygonizer() {
  tesselator_->reset();
  settled_ = false;
}

void ViewerPipeline::frame() {
  const auto start = std::chrono::steady_clock::now();
  if (options_.polygonizer == Polygonizer::Particles) {
    mcValid_ = false;
    if (!settled_) {
      tesselator_->settle(*skeleton_, mesh_, std::max(1, options_.settleUpdates));
      settled_ = true;
    } else {
      tesselator_->frame(*skeleton_, mesh_);
    }
    textureMesh(mesh_, *skeleton_, tesselator_->options().threads);
    tesselator_->carryTexcoords(mesh_);  // a no-op unless the texture mode is carried
    ++meshVersion_;
  } else if (!mcValid_ || mcGeneration_ != skeleton_->generation()) {
    // Marching Cubes is a function of the pose alone: an unchanged skeleton gives the same mesh.
    marchingCubes_.polygonize(skeleton_->field(), mcOptions_, mesh_, &mcStats_);
    textureMesh(mesh_, *skeleton_, mcOptions_.threads);
    mcGeneration_ = skeleton_->generation();
    mcValid_ = true;
    ++meshVersion_;
  }
  lastFrameMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Scene ViewerPipeline::posedScene() const {
  Scene out = scene_;
  writePose(out, pose());
  return out;
}

std::vector<Rigid> ViewerPipeline::pose() const {
  std::vector<Rigid> out(character_->joints().size());
  for (size_t j = 0; j < out.size(); ++j) out[j] = skeleton_->local(int(j));
  return out;
}

std::optional<Diagnostics> ViewerPipeline::setState(DocumentState state) {
  auto compiled = Character::fromScene(state.scene);
  if (!compiled) return compiled.error();
  auto character = std::make_unique<Character>(std::move(*compiled));
  auto skeleton = std::make_unique<SkeletonCache>(*character);
  skeleton->setPlacement(skeleton_->placement());
  for (size_t j = 0; j < character->joints().size() && j < state.pose.size(); ++j) {
    skeleton->setRotation(int(j), state.pose[j].rotation);
    skeleton->setTranslation(int(j), state.pose[j].translation);
  }
  skeleton->update();
  const bool samePrimitives = character->primitives().size() == character_->primitives().size();
  // The old cache goes before the character it points to.
  skeleton_ = std::move(skeleton);
  character_ = std::move(character);
  scene_ = std::move(state.scene);
  if (!samePrimitives) resetPolygonizer();  // particles name their owners by primitive index
  mcValid_ = false;
  return std::nullopt;
}

uint64_t meshHash(const Mesh& mesh) {
  uint64_t h = 14695981039346656037ull;
  auto add = [&h](const void* data, size_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  add(mesh.positions.data(), mesh.positions.size() * sizeof(float));
  add(mesh.normals.data(), mesh.normals.size() * sizeof(float));
  add(mesh.colors.data(), mesh.colors.size() * sizeof(float));
  add(mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
  return h;
}

}  // namespace imps::app
