// SPDX-License-Identifier: MIT
// Headless software rendering of a mesh to RGBA8 pixels or a PNG file, for docs, CLI snapshots and tests.
#pragma once

#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "camera.h"
#include "imps/mesh.h"
#include "png.h"

namespace imps::app {

// How to render a snapshot. Colours are linear RGB in [0, 1] (like Mesh::colors); the image is sRGB-encoded.
struct SnapshotOptions {
  int width = 640;   // pixels, > 0
  int height = 480;  // pixels, > 0
  // nullopt: frameMesh(mesh, kFrontThreeQuarter, width / height).
  std::optional<Camera> camera;
  // Samples per pixel along each axis (2 = 2x2 supersampling), averaged in linear light. >= 1.
  int supersampling = 2;
  // Albedo of meshes without per-vertex colours.
  glm::vec3 defaultColor{0.75f, 0.75f, 0.75f};
  // Direction towards the light in camera space (x right, y up, z towards the viewer): upper left, in front.
  glm::vec3 lightDirection{-0.4f, 0.6f, 0.7f};
  // Lambert shading: albedo * (ambient + (1 - ambient) * max(n.l, 0)), plus a white rim light
  // rim * (1 - n.v)^3 that brightens silhouettes.
  float ambient = 0.15f;
  float rim = 0.25f;
  // Background: a vertical gradient from top to bottom.
  glm::vec3 backgroundTop{0.80f, 0.80f, 0.82f};
  glm::vec3 backgroundBottom{0.52f, 0.52f, 0.54f};
  // The images a textured mesh's layers name (mesh.layerImages index them; textures.h's loadTextures). Null, or a
  // layer without an image: that layer is white. Not owned; must outlive the call.
  const std::vector<RgbaImage>* textures = nullptr;
};

// Renders `mesh` and returns width * height RGBA8 pixels, rows from the top, alpha 255. Triangles are z-buffered,
// drawn two-sided (back faces are lit as if they faced the camera), with perspective-correct interpolation of the
// vertex normals and colours (face normals when the mesh has none). A textured mesh's colours are modulated by its
// layers' textures: (1 - sum of weights) + sum of weight * texel, each layer's weight interpolated and its (u, v)
// taken from its generator at the corners (unwrapped across a sphere's seam). Triangles reaching behind the camera's
// near plane are skipped, not clipped. An empty mesh gives just the background. Thread-safe (no shared state). Returns
// an empty vector when width, height or supersampling are not positive.
std::vector<uint8_t> renderMesh(const Mesh& mesh, const SnapshotOptions& options);

// Renders as renderMesh() and saves an RGBA8 PNG (OpenImageIO) to `path`, which must end in ".png", atomically
// (temporary file, fsync, rename). On failure leaves `path` untouched and fails as savePng (png.h) does: one error
// without a location, "path: reason" or "cannot save 'path': ...".
std::expected<void, Diagnostics> renderMeshToPng(const Mesh& mesh, const SnapshotOptions& options,
                                                 const std::string& path);

}  // namespace imps::app
