// SPDX-License-Identifier: MIT
// `puppeteer stretch`: a dot painted on a joint, bent and brought back, in the projective and the carried texture
// modes.
#include "texture_stretch.h"

#include <cmath>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>

#include "imps/skeleton_cache.h"
#include "imps/texturing.h"
#include "manipulator.h"
#include "painter.h"
#include "snapshot.h"
#include "textures.h"

namespace imps::app {

namespace {

// Whether vertex v blends layer l (a slot names it with a positive weight).
bool blendsLayer(const Mesh& mesh, uint32_t v, int32_t l) {
  for (size_t k = 0; k < 2; ++k)
    if (mesh.layers[2 * v + k] == l && mesh.layerWeights[2 * v + k] > 0.0f) return true;
  return false;
}

// One frame as the app draws it: updatesPerRender updates, triangulation, texture layers, carried coordinates.
void drawFrame(Tesselator& tess, const SkeletonCache& cache, Mesh& mesh) {
  tess.frame(cache, mesh);
  textureMesh(mesh, cache, tess.options().threads);
  tess.carryTexcoords(mesh);
}

// The skin's material point: moved as a particle without repulsion (tesselator.cpp's differential transform,
// Newton projection and ownership rule).
struct SkinMarker {
  glm::vec3 p{0.0f};
  int owner = -1;

  void follow(const SkeletonCache& cache) {
    if (owner >= 0) p = cache.primitiveDifferential(size_t(owner)).apply(p);
    const Field& field = cache.field();
    for (int k = 0; k < 4; ++k) {
      const FieldSample fs = field.sample(p);
      const float g2 = glm::dot(fs.gradient, fs.gradient);
      if (!(g2 > 1e-20f)) break;
      p += (field.iso() - fs.value) / g2 * fs.gradient;
    }
    const int want = field.sample(p).owner;
    if (want >= 0 && (owner < 0 || cache.character().blends(size_t(owner), size_t(want)))) owner = want;
  }
};

}  // namespace

std::optional<glm::vec3> surfacePointOfUv(const Mesh& mesh, int32_t layer, glm::vec2 uv, const glm::vec3& near) {
  std::optional<glm::vec3> best;
  float bestD2 = std::numeric_limits<float>::infinity();
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* v = &mesh.indices[3 * t];
    if (!blendsLayer(mesh, v[0], layer) || !blendsLayer(mesh, v[1], layer) || !blendsLayer(mesh, v[2], layer)) continue;
    // u modulo 1: the corners unwrapped next to the first (as the renderers do), the triangle next to the dot.
    glm::vec2 q[3];
    for (int c = 0; c < 3; ++c) q[c] = mesh.layerUv(v[c], layer);
    for (int c = 1; c < 3; ++c) q[c].x -= std::round(q[c].x - q[0].x);
    const float shift = std::round(q[0].x - uv.x);
    for (glm::vec2& corner : q) corner.x -= shift;
    const glm::vec2 e1 = q[1] - q[0], e2 = q[2] - q[0], d = uv - q[0];
    const float det = e1.x * e2.y - e1.y * e2.x;
    if (!(std::fabs(det) > 1e-12f)) continue;
    const float b1 = (d.x * e2.y - d.y * e2.x) / det, b2 = (e1.x * d.y - e1.y * d.x) / det, b0 = 1.0f - b1 - b2;
    constexpr float kSlack = -1e-4f;
    if (b0 < kSlack || b1 < kSlack || b2 < kSlack) continue;
    const glm::vec3 p = b0 * mesh.position(v[0]) + b1 * mesh.position(v[1]) + b2 * mesh.position(v[2]);
    const float d2 = glm::dot(p - near, p - near);
    if (d2 < bestD2) {
      bestD2 = d2;
      best = p;
    }
  }
  return best;
}

std::expected<StretchResult, Diagnostics> measureStretch(const Character& character, TesselatorOptions tesselator,
                                                         TextureMode mode, const StretchOptions& options) {
  const auto fail = [](std::string why) { return std::unexpected(singleError({}, std::move(why))); };
  const int joint = character.findJoint(options.joint);
  if (joint < 0) return fail("no joint named '" + options.joint + "'");
  if (!character.textured()) return fail("no primitive has a texture generator");
  if (!(glm::length(options.axis) > 0.0f) || !(glm::length(options.dotDirection) > 0.0f))
    return fail("the bend's axis and the dot's direction must not be zero");
  tesselator.textureMode = mode;
  tesselator.cancel = nullptr;
  tesselator.progress = nullptr;
  SkeletonCache cache(character);
  cache.update();
  Tesselator tess(tesselator);
  Mesh mesh;
  tess.settle(cache, mesh);
  textureMesh(mesh, cache, tess.options().threads);
  tess.carryTexcoords(mesh);
  for (int f = 0; f < options.restFrames; ++f) drawFrame(tess, cache, mesh);
  if (!mesh.textured()) return fail("the mesh has no texture layers");

  // Paint: the dot's centre where the ray from the joint leaves the surface, in the layer weighing most there.
  StretchResult r;
  r.mode = mode;
  r.radius = tess.options().desiredRadius;
  const glm::vec3 origin = cache.world(joint).translation;
  const glm::vec3 dir = glm::normalize(options.dotDirection);
  // The joint's origin is inside the limb: the first hit on the way out is the limb's surface.
  const auto hit = intersectMesh(mesh, PickRay{origin, dir});
  if (!hit) return fail("no surface along the dot's direction from joint '" + options.joint + "'");
  const uint32_t* v = &mesh.indices[3 * hit->triangle];
  float bestWeight = 0.0f;
  for (int c = 0; c < 3; ++c)
    for (size_t k = 0; k < 2; ++k) {
      const int32_t l = mesh.layers[2 * v[c] + k];
      if (l < 0) continue;
      float w = 0.0f;
      for (int e = 0; e < 3; ++e)
        for (size_t m = 0; m < 2; ++m)
          if (mesh.layers[2 * v[e] + m] == l) w += hit->barycentric[e] * mesh.layerWeights[2 * v[e] + m];
      if (w > bestWeight) {
        bestWeight = w;
        r.layer = l;
      }
    }
  if (r.layer < 0) return fail("the surface at the dot has no texture");
  // The centre's coordinates: those the texture shows at the hit point.
  r.dotUv = mesh.layerUv(v[0], r.layer);
  {
    glm::vec2 uv = hit->barycentric[0] * r.dotUv;
    for (int c = 1; c < 3; ++c) {
      glm::vec2 q = mesh.layerUv(v[c], r.layer);
      q.x -= std::round(q.x - r.dotUv.x);
      uv += hit->barycentric[c] * q;
    }
    r.dotUv = uv;
  }
  const auto rest = surfacePointOfUv(mesh, r.layer, r.dotUv, hit->point);
  if (!rest) return fail("the dot's coordinates are on no triangle blending its layer");
  r.dotRest = *rest;

  // Pictures: the dot painted into the image, the joint seen from the outside of the bend.
  std::vector<RgbaImage> images;
  if (!options.pictures.empty()) {
    auto loaded = loadTextures(character);
    if (!loaded) return std::unexpected(loaded.error());
    images = std::move(*loaded);
    Brush brush;
    brush.size = 5;  // 7 texels
    paintDab(mesh, *hit, brush, images);
  }
  const glm::vec3 view = glm::normalize(glm::vec3(0.1f, -1.3f, 1.0f)) * 0.4f;  // from below the front
  auto picture = [&](const char* stage) -> std::string {
    if (options.pictures.empty()) return "";
    SnapshotOptions so;
    so.textures = &images;
    Camera camera;
    camera.target = cache.world(joint).translation;
    camera.eye = camera.target + view;
    so.camera = camera;
    const std::string path = options.pictures + "_" + (mode == TextureMode::Carried ? "carried" : "projective") +
                             "_" + stage + ".png";
    auto saved = renderMeshToPng(mesh, so, path);
    return saved ? "" : path + ": " + saved.error().all().front().message;
  };
  if (auto e = picture("rest"); !e.empty()) return fail(e);

  SkinMarker marker{r.dotRest, cache.field().sample(r.dotRest).owner};
  const glm::quat restRotation = cache.local(joint).rotation;
  const glm::vec3 axis = glm::normalize(options.axis);
  const float radians = glm::radians(options.degrees);
  const int frames = std::max(options.frames, 1);
  auto pose = [&](float fraction) {
    cache.setRotation(joint, glm::angleAxis(fraction * radians, axis) * restRotation);
    cache.update();
    marker.follow(cache);
    drawFrame(tess, cache, mesh);
  };
  for (int f = 1; f <= frames; ++f) pose(float(f) / float(frames));
  r.skinBent = marker.p;
  const auto bent = surfacePointOfUv(mesh, r.layer, r.dotUv, r.skinBent);
  if (!bent) return fail("the dot vanished at the bent pose");
  r.dotBent = *bent;
  if (auto e = picture("bent"); !e.empty()) return fail(e);
  for (int f = frames - 1; f >= 0; --f) pose(float(f) / float(frames));
  for (int f = 0; f < options.restFrames; ++f) drawFrame(tess, cache, mesh);
  const auto back = surfacePointOfUv(mesh, r.layer, r.dotUv, r.dotRest);
  if (!back) return fail("the dot vanished after coming back");
  r.dotBack = *back;
  if (auto e = picture("back"); !e.empty()) return fail(e);
  r.skinBack = marker.p;
  r.roundTrip = glm::length(r.dotBack - r.dotRest);
  r.skinRoundTrip = glm::length(r.skinBack - r.dotRest);
  r.slideBack = glm::length(r.dotBack - r.skinBack);
  r.slideBent = glm::length(r.dotBent - r.skinBent);
  r.particles = tess.stats().particles;
  return r;
}

}  // namespace imps::app
