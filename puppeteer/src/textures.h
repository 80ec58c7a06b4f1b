// SPDX-License-Identifier: MIT
// A character's texture images (docs/scene-format.md, *Texturing*): read once from beside the scene file, shared by
// the software renderer, the GL renderer and the exporters.
#pragma once

#include <expected>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "imps/character.h"
#include "imps/mesh.h"
#include "png.h"

namespace imps::app {

// Reads every image of character.textures(), in that order. A missing or unreadable image fails the whole load
// with one error per bad file at its ImageTexture's url in the scene: "cannot read texture 'URL' (PATH): REASON".
// A character without textures gives an empty list without loading the image plugin.
std::expected<std::vector<RgbaImage>, Diagnostics> loadTextures(const Character& character);

// The texel of `image` at (u, v) (u to the right, v up, repeating outside [0, 1]), bilinearly filtered, as linear
// RGB in [0, 1] (the image's bytes are sRGB). A white texel for an empty image.
glm::vec3 sampleTexture(const RgbaImage& image, float u, float v);

// The texture layers of one triangle of a textured mesh (mesh.h): every layer any corner names, with its weight
// at each corner (0 where the corner does not name it) and its (u, v) at each corner (Mesh::layerUv: carried, or
// from its generator), u
// unwrapped across a sphere generator's seam so that no triangle spans it (the image repeats). Renderers blend
// (1 - sum of weights) white + sum of weight x texel, the weights and coordinates interpolated over the triangle.
struct TriangleLayers {
  static constexpr int kMax = 6;  // two per corner
  int count = 0;
  int32_t layer[kMax] = {};
  int32_t image[kMax] = {};      // mesh.layerImages of the layer (-1: none, white)
  glm::vec3 weight[kMax] = {};   // at corners a, b, c
  glm::vec2 uv[kMax][3] = {};

  void gather(const Mesh& mesh, uint32_t a, uint32_t b, uint32_t c);
};

}  // namespace imps::app
