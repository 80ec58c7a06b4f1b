// SPDX-License-Identifier: MIT
// The live app's OpenGL 3.3 core renderer: a background gradient, the character's lit per-vertex-coloured
// triangles (Lambert + rim, as snapshot.h) and optional particle points.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "imps/mesh.h"
#include "camera.h"
#include "png.h"
#include "snapshot.h"

namespace imps::app {

// A vertex of a 2D overlay: window pixels (origin top-left, y down) and a linear RGB colour.
struct OverlayVertex {
  glm::vec2 pixel{0.0f};
  glm::vec3 color{1.0f};
};

// Owns the GL objects (program, vertex arrays, buffers). Every call needs the GL 3.3 core context that was current
// at construction to be current; not thread-safe. Colours and lighting follow SnapshotOptions (linear RGB in,
// sRGB out), so the app and `puppeteer mesh --snapshot` pictures look alike.
class Renderer {
 public:
  // Compiles the shaders; on failure ok() is false and error() says why.
  Renderer();
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }

  // Uploads the mesh (buffers orphaned and refilled every call, so the driver never stalls on the previous frame).
  // A textured mesh (mesh.h's layers) is drawn from unshared corners carrying each triangle's three heaviest
  // layers (textures.h's TriangleLayers; a fourth or later layer of one triangle, which needs four primitives
  // blending there, is dropped and its weight left untextured); an untextured one costs what it did before.
  void uploadMesh(const Mesh& mesh);
  // Uploads the images textured meshes name (mesh.layerImages index them) as one mipmapped, repeating sRGB texture
  // array: every image is resampled (bilinear) to the largest width and height among them. Replaces any earlier
  // upload; an empty list removes them (layers then draw white).
  void uploadTextures(const std::vector<RgbaImage>& images);
  // Uploads particle positions (world space, metres) to draw as points.
  void uploadParticles(std::span<const glm::vec3> positions);

  // Clears to the background gradient and draws the mesh (and the particles when `particles`) seen by `camera`
  // (its viewMatrix and projectionMatrix with the scene radius) into a viewport of width x height pixels.
  void draw(const Camera& camera, int width, int height, bool particles);

  // The default framebuffer's back buffer as RGBA8, rows from the top (call after draw(), before swapping).
  // Draws triangles (three vertices each) given in window pixels over everything drawn so far, without depth test:
  // the modeller's handles. Call after draw().
  void drawOverlay(std::span<const OverlayVertex> triangles, int width, int height);
  // Diameter of the particle points in pixels; <= 0: the default (4, or 3 below 600 pixels of height).
  void setPointSize(float pixels) { pointSize_ = pixels; }

  static std::vector<uint8_t> readPixels(int width, int height);

  // Radius of the uploaded mesh's bounding sphere around the camera target, used for the clip planes
  // (Camera::projectionMatrix).
  void setSceneRadius(float radius) { sceneRadius_ = radius; }

 private:
  void uploadTexturedMesh(const Mesh& mesh);
  std::string error_;
  unsigned meshProgram_ = 0, pointProgram_ = 0, backgroundProgram_ = 0, overlayProgram_ = 0;
  unsigned meshVao_ = 0, pointVao_ = 0, backgroundVao_ = 0, overlayVao_ = 0, overlayBuffer_ = 0;
  float pointSize_ = 0.0f;
  unsigned positionBuffer_ = 0, normalBuffer_ = 0, colorBuffer_ = 0, indexBuffer_ = 0, pointBuffer_ = 0;
  int32_t indexCount_ = 0, pointCount_ = 0;
  bool meshHasNormals_ = false, meshHasColors_ = false;
  unsigned texturedProgram_ = 0, texturedVao_ = 0, texturedBuffer_ = 0, textureArray_ = 0;
  int32_t texturedCount_ = 0;  // corners of the textured mesh (0: the mesh is drawn indexed, untextured)
  int32_t textureLayers_ = 0;
  float sceneRadius_ = 2.0f;
  SnapshotOptions look_;
};

}  // namespace imps::app
