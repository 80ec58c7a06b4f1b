// SPDX-License-Identifier: MIT
// 3D painting: ray cast, the owning layer's texel under the brush, antialiased dabs, saving under new names.
#include "painter.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include <glm/geometric.hpp>

#include "imps/atomic_file.h"
#include "imps/scene_writer.h"
#include "textures.h"

namespace imps::app {
namespace fs = std::filesystem;

float Brush::radiusTexels() const {
  static constexpr float kRadii[10] = {40, 1, 2, 3, 5, 7, 10, 14, 20, 28};  // index: the key (0 largest)
  return kRadii[std::clamp(size, 0, 9)];
}

std::optional<MeshHit> intersectMesh(const Mesh& mesh, const PickRay& ray) {
  std::optional<MeshHit> best;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::vec3 a = mesh.position(mesh.indices[3 * t]), b = mesh.position(mesh.indices[3 * t + 1]),
                    c = mesh.position(mesh.indices[3 * t + 2]);
    const glm::vec3 e1 = b - a, e2 = c - a;
    const glm::vec3 p = glm::cross(ray.direction, e2);
    const float det = glm::dot(e1, p);
    if (std::abs(det) < 1e-12f) continue;
    const float inv = 1.0f / det;
    const glm::vec3 s = ray.origin - a;
    const float u = glm::dot(s, p) * inv;
    if (u < 0.0f || u > 1.0f) continue;
    const glm::vec3 q = glm::cross(s, e1);
    const float v = glm::dot(ray.direction, q) * inv;
    if (v < 0.0f || u + v > 1.0f) continue;
    const float distance = glm::dot(e2, q) * inv;
    if (distance <= 0.0f || (best && distance >= best->distance)) continue;
    best = MeshHit{t, ray.origin + distance * ray.direction, glm::vec3(1.0f - u - v, u, v), distance};
  }
  return best;
}

int paintDab(const Mesh& mesh, const MeshHit& hit, const Brush& brush, std::vector<RgbaImage>& images) {
  if (!mesh.textured() || hit.triangle >= mesh.triangleCount()) return -1;
  TriangleLayers layers;
  const uint32_t* v = &mesh.indices[3 * hit.triangle];
  layers.gather(mesh, v[0], v[1], v[2]);
  int best = -1;
  float bestWeight = 0.0f;
  for (int i = 0; i < layers.count; ++i) {
    const float w = glm::dot(layers.weight[i], hit.barycentric);
    const int32_t image = layers.image[i];
    if (image < 0 || size_t(image) >= images.size() || images[size_t(image)].width <= 0) continue;
    if (w > bestWeight) {
      bestWeight = w;
      best = i;
    }
  }
  if (best < 0) return -1;
  RgbaImage& image = images[size_t(layers.image[best])];
  // The brush's centre in texel coordinates (x right, y down from the top row), as sampleTexture reads them.
  // Projective: the generator's mapping of the hit point; carried: the corners' coordinates interpolated.
  const glm::vec2 uv = mesh.layerTexcoords.empty()
                           ? mesh.layerGens[size_t(layers.layer[best])].map(hit.point)
                           : hit.barycentric.x * layers.uv[best][0] + hit.barycentric.y * layers.uv[best][1] +
                                 hit.barycentric.z * layers.uv[best][2];
  const float cx = (uv.x - std::floor(uv.x)) * float(image.width);
  const float cy = (1.0f - (uv.y - std::floor(uv.y))) * float(image.height);
  const float r = brush.radiusTexels();
  for (int y = int(std::floor(cy - r - 1)); y <= int(std::ceil(cy + r + 1)); ++y)
    for (int x = int(std::floor(cx - r - 1)); x <= int(std::ceil(cx + r + 1)); ++x) {
      const float d = std::hypot(float(x) + 0.5f - cx, float(y) + 0.5f - cy);
      const float coverage = std::clamp(r + 0.5f - d, 0.0f, 1.0f);  // one texel of antialiased edge
      if (coverage <= 0.0f) continue;
      const int wx = ((x % image.width) + image.width) % image.width;
      const int wy = ((y % image.height) + image.height) % image.height;
      uint8_t* p = &image.rgba[(size_t(wy) * size_t(image.width) + size_t(wx)) * 4];
      for (int k = 0; k < 3; ++k)
        p[k] = uint8_t(std::lround(float(p[k]) + coverage * (float(brush.color[k]) - float(p[k]))));
    }
  return layers.image[best];
}

std::vector<std::string> paintedTextureNames(const Character& character, const std::vector<bool>& painted,
                                             const std::string& scenePath) {
  const fs::path dir = fs::path(scenePath).parent_path();
  const std::string stem = fs::path(scenePath).stem().string();
  std::set<std::string> taken;
  for (const CharacterTexture& t : character.textures()) taken.insert(fs::absolute(t.path).lexically_normal().string());
  std::vector<std::string> names(character.textures().size());
  for (size_t k = 0; k < names.size(); ++k) {
    if (k >= painted.size() || !painted[k]) continue;
    const std::string base = stem + "_" + fs::path(character.textures()[k].path).stem().string();
    std::string name = base + ".png";
    // Never a name of the scene's textures, nor of any file already there (an unrelated image, or an earlier save).
    auto busy = [&](const std::string& candidate) {
      std::error_code ec;
      const fs::path full = fs::absolute(dir / candidate).lexically_normal();
      return taken.contains(full.string()) || fs::exists(fs::symlink_status(full, ec));
    };
    for (int n = 2; busy(name); ++n) name = base + "_" + std::to_string(n) + ".png";
    taken.insert(fs::absolute(dir / name).lexically_normal().string());
    names[k] = (dir / name).string();
  }
  return names;
}

namespace {

// Every ImageTexture of the graph whose resolved file is `from` gets `url`.
void retarget(SceneNode& node, const fs::path& sceneDir, const std::string& from, const std::string& url) {
  if (auto* shape = std::get_if<ShapeNode>(&node)) {
    if (!shape->texture) return;
    const fs::path u(shape->texture->url);
    const fs::path resolved = u.is_absolute() ? u : sceneDir / u;
    if (fs::absolute(resolved).lexically_normal() == fs::absolute(from).lexically_normal()) shape->texture->url = url;
  } else if (auto* t = std::get_if<TransformNode>(&node)) {
    for (SceneNode& child : t->children) retarget(child, sceneDir, from, url);
  } else if (auto* b = std::get_if<BlendNode>(&node)) {
    for (SceneNode& child : b->children) retarget(child, sceneDir, from, url);
  }
}

}  // namespace

std::expected<void, Diagnostics> savePaintedScene(Scene scene, const Character& character,
                                                  const std::vector<RgbaImage>& images,
                                                  const std::vector<bool>& painted, const std::string& scenePath) {
  const std::vector<std::string> names = paintedTextureNames(character, painted, scenePath);
  const fs::path originalDir = fs::path(scene.fileName).parent_path();
  const fs::path savedDir = fs::absolute(fs::path(scenePath).parent_path()).lexically_normal();
  SceneNode* graph = scene.sceneGraph();
  for (size_t k = 0; k < character.textures().size(); ++k) {
    const CharacterTexture& t = character.textures()[k];
    std::string url;
    if (!names[k].empty()) {
      const RgbaImage& image = images[k];
      if (auto saved = savePng(image.rgba, image.width, image.height, names[k]); !saved) return saved;
      url = fs::path(names[k]).filename().string();
    } else if (fs::path(t.url).is_absolute() ||
               fs::absolute(originalDir).lexically_normal() == savedDir) {
      continue;  // the url still names the file from where the scene is saved
    } else {
      url = fs::absolute(t.path).lexically_normal().lexically_relative(savedDir).string();
    }
    if (graph) retarget(*graph, originalDir, t.path, url);
  }
  if (auto saved = saveSceneFile(scene, scenePath); !saved)
    return std::unexpected(singleError({}, saved.error().message));
  return {};
}

}  // namespace imps::app
