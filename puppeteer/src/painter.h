// SPDX-License-Identifier: MIT
// 3D painting (thesis 3.9, A.2.1): a brush dab where the mouse ray meets the surface goes into the texture of the
// primitive that owns that point, and painted textures are saved beside the scene under new names.
// Pure functions over meshes and images, free of any window or GL (the app's `t` mode calls them; tested alone).
// Based on: K. Russell, "IMPS", MIT 1999, section 3.9 (Im3DPaint, ImBrush, ImRayCast); T. Möller and B. Trumbore,
//           "Fast, Minimum Storage Ray/Triangle Intersection", 1997.
#pragma once

#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "imps/character.h"
#include "imps/mesh.h"
#include "imps/scene.h"
#include "manipulator.h"
#include "png.h"

namespace imps::app {

// The painter's brush: its colour (sRGB bytes) and size key, 1 smallest ... 9, then 0 largest (the thesis's keys).
struct Brush {
  uint8_t color[3] = {200, 30, 40};
  int size = 1;
  // The dab's radius in texels of the painted image for the size key: 1, 2, 3, 5, 7, 10, 14, 20, 28, 40.
  float radiusTexels() const;
};

// Where a ray first meets a mesh: the triangle, the point (world space) and its barycentric weights (of the
// triangle's corners 0, 1, 2). Two-sided; nothing behind the ray's origin.
struct MeshHit {
  size_t triangle = 0;
  glm::vec3 point{0.0f};
  glm::vec3 barycentric{0.0f};
  float distance = 0.0f;
};
std::optional<MeshHit> intersectMesh(const Mesh& mesh, const PickRay& ray);

// One antialiased dab at `hit` on a textured mesh (mesh.h's layers): into the image of the layer that weighs most
// at the point (the owning primitive's texture; layers without an image are skipped), centred on that layer's
// (u, v) there, a disc of brush.radiusTexels() whose edge is blended over one texel by coverage (texel = mix(texel,
// colour, coverage)), repeating across the image's edges as the texture does. Returns the painted image's index
// into `images` (mesh.layerImages' numbering), or -1 when the point has no textured layer.
int paintDab(const Mesh& mesh, const MeshHit& hit, const Brush& brush, std::vector<RgbaImage>& images);

// The file names painted textures are saved under, beside `scenePath`: STEM_NAME.png for the texture whose file
// is NAME.EXT (STEM the saved scene's name without extension), with _2, _3 ... added while the name is one of the
// scene's current texture files or the source image itself, or names any file that exists (a dangling symlink
// included) — so saving never overwrites an original or an unrelated file; each save of a painted texture gets a
// fresh file.
std::vector<std::string> paintedTextureNames(const Character& character, const std::vector<bool>& painted,
                                             const std::string& scenePath);

// Saves the painted textures (PNG, each atomically) under paintedTextureNames(), then `scene` with every
// ImageTexture url naming a painted texture's file pointed at the new file (relative to the saved scene), then
// the scene (atomically) to `scenePath`. Unpainted textures keep their urls (absolute ones, or when the scene is
// saved in its own directory), else get their file's path relative to the saved scene's directory. With nothing
// painted this is the app's plain save: the saved scene still finds its images wherever it is saved. On failure the
// scene is not written and the error is savePng's for an image, or the scene save's "cannot save 'PATH': ..."
// (one error without a location whose message names the file).
std::expected<void, Diagnostics> savePaintedScene(Scene scene, const Character& character,
                                                  const std::vector<RgbaImage>& images,
                                                  const std::vector<bool>& painted, const std::string& scenePath);

}  // namespace imps::app
