// SPDX-License-Identifier: MIT
// The particle tesselator's carried texture coordinates (TextureMode::Carried): a texture that stretches with the
// skin instead of sliding across it (issue 11; the thesis's open problem 6.1.2).
//
// Based on: K. Russell, "IMPS", MIT 1999, 3.7 (differential transforms) and 3.9 (texture-coordinate generators,
//           and the texture "sliding" over blend regions that this mode avoids).
//
// The coordinates are a field over the particles. A differential transform moves a particle with its owner's joint:
// its coordinates stay, so the texture moves with that skin — where the particle's owner is not the layer's
// primitive (the blend region of an elbow), that is exactly where projective coordinates would slide. The particle's
// own motion (repulsion and the Newton step back onto the surface, which keep the particles evenly spread) is not
// the skin's, so it must not drag the texture along: the coordinates change by what the layer's generator maps the
// step to, i.e. they are advected through the generator's local mapping. (Advecting through the gradient of the
// carried coordinates themselves, fitted over the neighbours, was tried first: it is unstable — noise in the
// neighbours' coordinates feeds back through the fitted gradient, and on the bending biped's elbow some coordinates
// grew to 1e8 within 60 frames.) Fission splits the parent's coordinates by what the two offsets map to; fusion keeps
// the survivor's; a particle without a coordinate for a layer (seeding, or a layer it newly blends) takes the
// generator's.
#include <cmath>

#include "imps/parallel.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "tesselator_state.h"

namespace imps {

void updateTexGens(Tesselator::State& s, const SkeletonCache& skeleton) {
  const size_t prims = skeleton.field().size();
  size_t layers = 0;
  for (size_t i = 0; i < prims; ++i) layers += skeleton.texGen(i) != nullptr;
  if (layers != s.carryLayers) return;  // not the character the coordinates were carried on
  s.texGens.clear();
  for (size_t i = 0; i < prims; ++i)
    if (const TexGen* g = skeleton.texGen(i)) s.texGens.push_back(*g);
}

void advectTexcoords(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.size(), layers = s.texGens.size();
  parallelFor((n + kChunk - 1) / kChunk, o.threads, [&](size_t c) {
    for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      if (s.dead[i]) continue;
      for (size_t k = 0; k < 2; ++k) {
        const size_t a = 2 * i + k;
        const int32_t l = s.texLayer[a];
        if (l < 0 || size_t(l) >= layers) continue;
        const TexGen& gen = s.texGens[size_t(l)];
        const glm::vec2 from = gen.map(s.prevPos[i]);
        glm::vec2 to = gen.map(s.pos[i]);
        to.x -= std::round(to.x - from.x);  // a sphere generator's u wraps
        const glm::vec2 next = s.texUv[a] + (to - from);
        if (std::isfinite(next.x) && std::isfinite(next.y)) s.texUv[a] = next;
      }
    }
  });
}

void Tesselator::carryTexcoords(Mesh& mesh) {
  State& s = *s_;
  if (options_.textureMode != TextureMode::Carried) return;
  if (!mesh.textured()) {
    if (s.carry) s.dropTexcoords();  // no textures: nothing to carry, nothing to pay for
    return;
  }
  // Not a vertex per particle then the surface rows': projective.
  if (stats_.fallback || mesh.vertexCount() != s.size() + s.addedFrom.size()) return;
  if (!s.carry || s.carryLayers != mesh.layerGens.size()) {
    s.dropTexcoords();
    s.carry = true;
    s.carryLayers = mesh.layerGens.size();
    s.resizeParticles(s.size());
  }
  s.texGens = mesh.layerGens;  // the pose of this mesh; update(skeleton) refreshes them
  const size_t n = s.size();
  mesh.layerTexcoords.assign(4 * mesh.vertexCount(), 0.0f);
  parallelFor((n + kChunk - 1) / kChunk, options_.threads, [&](size_t c) {
    for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      const int32_t oldLayer[2] = {s.texLayer[2 * i], s.texLayer[2 * i + 1]};
      const glm::vec2 oldUv[2] = {s.texUv[2 * i], s.texUv[2 * i + 1]};
      for (size_t k = 0; k < 2; ++k) {
        const size_t a = 2 * i + k;
        const int32_t l = mesh.layers[a];
        glm::vec2 uv(0.0f);
        if (l >= 0) {
          const size_t kept = oldLayer[0] == l ? 0 : (oldLayer[1] == l ? 1 : 2);
          uv = kept < 2 ? oldUv[kept] : mesh.layerGens[size_t(l)].map(mesh.position(i));
        }
        s.texLayer[a] = l;
        s.texUv[a] = uv;
        mesh.layerTexcoords[4 * i + 2 * k] = uv.x;
        mesh.layerTexcoords[4 * i + 2 * k + 1] = uv.y;
      }
      if (mesh.layers[2 * i] >= 0) {
        mesh.texcoords[2 * i] = s.texUv[2 * i].x;
        mesh.texcoords[2 * i + 1] = s.texUv[2 * i].y;
      }
    }
  });
  // The surface rows' vertices: the coordinates of the particle each follows, moved by what the layer's generator maps
  // the step from that particle's vertex to it (a sphere generator's u unwrapped, as advectTexcoords does); the
  // generator's own mapping for a layer the particle does not carry.
  for (size_t v = n; v < mesh.vertexCount(); ++v) {
    const uint32_t p = s.addedFrom[v - n];
    for (size_t k = 0; k < 2; ++k) {
      const int32_t l = mesh.layers[2 * v + k];
      glm::vec2 uv(0.0f);
      if (l >= 0) {
        const TexGen& gen = mesh.layerGens[size_t(l)];
        uv = gen.map(mesh.position(v));
        const size_t slot = s.texLayer[2 * p] == l ? 0 : (s.texLayer[2 * p + 1] == l ? 1 : 2);
        if (slot < 2) {
          glm::vec2 step = uv - gen.map(mesh.position(p));
          step.x -= std::round(step.x);
          uv = s.texUv[2 * p + slot] + step;
        }
      }
      mesh.layerTexcoords[4 * v + 2 * k] = uv.x;
      mesh.layerTexcoords[4 * v + 2 * k + 1] = uv.y;
    }
    if (mesh.layers[2 * v] >= 0) {
      mesh.texcoords[2 * v] = mesh.layerTexcoords[4 * v];
      mesh.texcoords[2 * v + 1] = mesh.layerTexcoords[4 * v + 1];
    }
  }
}

}  // namespace imps
