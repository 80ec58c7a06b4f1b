// textureMesh: per-vertex texture layers and weights from the field's normalised contributions.
#include "imps/texturing.h"

#include <algorithm>
#include <vector>

#include "imps/check.h"
#include "imps/parallel.h"

namespace imps {

namespace {

constexpr size_t kVerticesPerTask = 256;

struct Worker {
  FieldScratch scratch;
  std::vector<std::pair<uint32_t, float>> weights;
};

}  // namespace

void textureMesh(Mesh& mesh, const Field& field, std::span<const TexGen* const> gens, std::span<const int32_t> images,
                 int threads) {
  IMPS_CHECK_EQ(gens.size(), field.size());
  IMPS_CHECK_EQ(images.size(), field.size());
  mesh.clearTextures();
  std::vector<int32_t> layerOf(field.size(), -1);
  for (size_t i = 0; i < gens.size(); ++i) {
    if (!gens[i]) continue;
    layerOf[i] = static_cast<int32_t>(mesh.layerGens.size());
    mesh.layerGens.push_back(*gens[i]);
    mesh.layerImages.push_back(images[i]);
  }
  if (mesh.layerGens.empty()) return;
  const size_t n = mesh.vertexCount();
  mesh.layers.assign(2 * n, -1);
  mesh.layerWeights.assign(2 * n, 0.0f);
  mesh.texcoords.assign(2 * n, 0.0f);
  const size_t tasks = (n + kVerticesPerTask - 1) / kVerticesPerTask;
  std::vector<Worker> workers(static_cast<size_t>(resolveThreads(threads)));
  parallelForWorkers(tasks, threads, [&](size_t task, int w) {
    Worker& worker = workers[static_cast<size_t>(w)];
    const size_t first = task * kVerticesPerTask, last = std::min(n, first + kVerticesPerTask);
    Box region;
    for (size_t v = first; v < last; ++v) region.extend(mesh.position(v));
    field.prepare(region, worker.scratch);
    for (size_t v = first; v < last; ++v) {
      field.contributions(mesh.position(v), worker.scratch, worker.weights);
      float total = 0.0f, textured = 0.0f;
      uint32_t best[2] = {0, 0};
      float bestWeight[2] = {0.0f, 0.0f};
      for (const auto& [i, weight] : worker.weights) {
        total += weight;
        if (layerOf[i] < 0) continue;
        textured += weight;
        if (weight > bestWeight[0]) {
          best[1] = best[0];
          bestWeight[1] = bestWeight[0];
          best[0] = i;
          bestWeight[0] = weight;
        } else if (weight > bestWeight[1]) {
          best[1] = i;
          bestWeight[1] = weight;
        }
      }
      if (!(textured > 0.0f)) continue;
      const float scale = textured / (total * (bestWeight[0] + bestWeight[1]));
      for (int k = 0; k < 2; ++k) {
        if (!(bestWeight[k] > 0.0f)) continue;
        mesh.layers[2 * v + k] = layerOf[best[k]];
        mesh.layerWeights[2 * v + k] = bestWeight[k] * scale;
      }
      const glm::vec2 uv = mesh.layerGens[size_t(layerOf[best[0]])].map(mesh.position(v));
      mesh.texcoords[2 * v] = uv.x;
      mesh.texcoords[2 * v + 1] = uv.y;
    }
  });
}

void textureMesh(Mesh& mesh, const SkeletonCache& cache, int threads) {
  const Character& character = cache.character();
  if (!character.textured()) {
    mesh.clearTextures();
    return;
  }
  const size_t n = character.primitives().size();
  std::vector<const TexGen*> gens(n);
  std::vector<int32_t> images(n);
  for (size_t i = 0; i < n; ++i) {
    gens[i] = cache.texGen(i);
    images[i] = character.primitives()[i].texture;
  }
  textureMesh(mesh, cache.field(), gens, images, threads);
}

}  // namespace imps
