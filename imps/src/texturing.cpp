// SPDX-License-Identifier: MIT
// textureMesh: per-vertex texture layers and weights from the field's normalised contributions.
#include "imps/texturing.h"

#include <algorithm>
#include <cmath>
#include <map>
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

namespace {

// The layer weighing most in triangle t (summed over its corners), or -1.
int32_t heaviestLayer(const Mesh& mesh, size_t t) {
  int32_t layer[6];
  float weight[6];
  int count = 0;
  for (int c = 0; c < 3; ++c) {
    const uint32_t v = mesh.indices[3 * t + size_t(c)];
    for (int k = 0; k < 2; ++k) {
      const int32_t l = mesh.layers[2 * v + size_t(k)];
      if (l < 0) continue;
      int i = 0;
      while (i < count && layer[i] != l) ++i;
      if (i == count) {
        layer[count] = l;
        weight[count++] = 0.0f;
      }
      weight[i] += mesh.layerWeights[2 * v + size_t(k)];
    }
  }
  int32_t best = -1;
  float bestWeight = 0.0f;
  for (int i = 0; i < count; ++i)
    if (weight[i] > bestWeight || (weight[i] == bestWeight && best >= 0 && layer[i] < best)) {
      best = layer[i];
      bestWeight = weight[i];
    }
  return best;
}

void copyVertex(const Mesh& from, uint32_t v, Mesh& to) {
  to.positions.insert(to.positions.end(),
                      {from.positions[3 * v], from.positions[3 * v + 1], from.positions[3 * v + 2]});
  if (!from.normals.empty())
    to.normals.insert(to.normals.end(), {from.normals[3 * v], from.normals[3 * v + 1], from.normals[3 * v + 2]});
  if (!from.colors.empty())
    to.colors.insert(to.colors.end(), {from.colors[3 * v], from.colors[3 * v + 1], from.colors[3 * v + 2]});
}

}  // namespace

std::vector<TexturedPart> splitByTexture(const Mesh& mesh) {
  // Triangles by part: the image of their heaviest layer (its generator decides the coordinates).
  std::map<int32_t, std::vector<std::pair<size_t, int32_t>>> byImage;  // image -> (triangle, layer)
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const int32_t layer = mesh.textured() ? heaviestLayer(mesh, t) : -1;
    const int32_t image = layer >= 0 ? mesh.layerImages[size_t(layer)] : -1;
    byImage[image].emplace_back(t, image >= 0 ? layer : -1);
  }
  std::vector<TexturedPart> parts;
  for (const auto& [image, triangles] : byImage) {
    TexturedPart part;
    part.image = image;
    std::map<std::pair<uint32_t, int32_t>, uint32_t> shared;  // (vertex, layer) -> part vertex
    for (const auto& [t, layer] : triangles) {
      glm::vec2 uv[3];
      for (int c = 0; c < 3; ++c)
        uv[c] = layer >= 0 ? mesh.layerUv(mesh.indices[3 * t + size_t(c)], layer) : glm::vec2(0.0f);
      // Only a sphere generator's u wraps (longitude); a plane projector's u runs on past 1 and must stay as it is.
      const bool wraps = layer >= 0 && mesh.layerGens[size_t(layer)].type == TexGenType::Sphere;
      bool seam = false;
      for (int c = 1; c < 3 && wraps; ++c) {
        const float shift = std::round(uv[c].x - uv[0].x);
        if (shift != 0.0f) {
          uv[c].x -= shift;
          seam = true;
        }
      }
      for (int c = 0; c < 3; ++c) {
        const uint32_t v = mesh.indices[3 * t + size_t(c)];
        uint32_t at;
        const auto found = seam ? shared.end() : shared.find({v, layer});
        if (found != shared.end()) {
          at = found->second;
        } else {
          at = static_cast<uint32_t>(part.mesh.vertexCount());
          copyVertex(mesh, v, part.mesh);
          part.uvs.insert(part.uvs.end(), {uv[c].x, uv[c].y});
          if (!seam) shared.emplace(std::pair{v, layer}, at);
        }
        part.mesh.indices.push_back(at);
      }
    }
    parts.push_back(std::move(part));
  }
  return parts;
}

}  // namespace imps
