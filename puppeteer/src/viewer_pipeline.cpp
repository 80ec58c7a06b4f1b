// The viewer's frame pipeline: pose → skeleton cache → polygonizer → mesh.
#include "viewer_pipeline.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <utility>
#include <variant>

namespace imps::app {
namespace {

// Writes local joint transforms into every named RigidTransform under `node`.
void writePose(SceneNode& node, const Character& character, const SkeletonCache& skeleton) {
  if (auto* t = std::get_if<TransformNode>(&node)) {
    const int j = t->name.empty() ? -1 : character.findJoint(t->name);
    if (j >= 0) {
      const Rigid& local = skeleton.local(j);
      t->translation = local.translation;
      const glm::quat q = glm::normalize(local.rotation);
      const float angle = 2.0f * std::acos(std::clamp(q.w, -1.0f, 1.0f));
      const glm::vec3 v(q.x, q.y, q.z);
      const float s = glm::length(v);
      t->rotation = s > 1e-7f ? Rotation{v / s, angle} : Rotation{glm::vec3(0, 0, 1), 0.0f};
    }
    for (SceneNode& c : t->children) writePose(c, character, skeleton);
  } else if (auto* b = std::get_if<BlendNode>(&node)) {
    for (SceneNode& c : b->children) writePose(c, character, skeleton);
  }
}

}  // namespace

ViewerPipeline::ViewerPipeline(Scene scene, Character character, const PipelineOptions& options)
    : scene_(std::move(scene)),
      character_(std::make_unique<Character>(std::move(character))),
      skeleton_(std::make_unique<SkeletonCache>(*character_)),
      options_(options) {
  const Box rest = skeleton_->field().surfaceBounds();
  if (!rest.empty()) restBounds_ = MeshBounds{rest.lo, rest.hi};
  TesselatorOptions t;
  if (const auto* node = std::get_if<Tesselator3MPNode>(&scene_.polygonizer)) t = TesselatorOptions::fromNode(*node);
  if (options_.threads >= 0) t.numThreads = options_.threads;
  tesselator_ = std::make_unique<Tesselator>(t);
  mcOptions_.resolution = options_.mcResolution;
  mcOptions_.threads = t.numThreads;
  if (const auto* node = std::get_if<MarchingCubesNode>(&scene_.polygonizer)) {
    mcOptions_.cellSize = node->cellSize;
    mcOptions_.gridResolution = {node->xResolution, node->yResolution, node->zResolution};
    mcOptions_.threads = node->numThreads;
  }
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
    ++meshVersion_;
  } else if (!mcValid_ || mcGeneration_ != skeleton_->generation()) {
    // Marching Cubes is a function of the pose alone: an unchanged skeleton gives the same mesh.
    marchingCubes_.polygonize(skeleton_->field(), mcOptions_, mesh_, &mcStats_);
    mcGeneration_ = skeleton_->generation();
    mcValid_ = true;
    ++meshVersion_;
  }
  lastFrameMs_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

Scene ViewerPipeline::posedScene() const {
  Scene out = scene_;
  if (SceneNode* root = out.sceneGraph()) writePose(*root, *character_, *skeleton_);
  return out;
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
