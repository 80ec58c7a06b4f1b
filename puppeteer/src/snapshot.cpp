// SPDX-License-Identifier: MIT
// Software rasteriser for mesh snapshots: z-buffer, perspective-correct attributes, Lambert + rim, supersampling.
// Based on: Juan Pineda, "A Parallel Algorithm for Polygon Rasterization" (1988) (edge functions);
// Paul Heckbert and Henry Moreton, "Interpolation for Polygon Texture Mapping and Shading" (1991)
// (perspective-correct interpolation).
#include "snapshot.h"

#include "textures.h"

#include "png.h"


#include <algorithm>
#include <cmath>
#include <limits>

#include <glm/geometric.hpp>

#include "imps/mesh_io.h"

namespace imps::app {
namespace {

float srgbEncode(float linear) {
  const float c = std::clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

uint8_t toByte(float unit) { return static_cast<uint8_t>(std::clamp(unit, 0.0f, 1.0f) * 255.0f + 0.5f); }

// The camera's orthonormal frame: right, up, forward (towards the target).
struct ViewFrame {
  glm::vec3 eye, right, up, forward;
  float tanHalfFovY, tanHalfFovX;
};

ViewFrame viewFrame(const Camera& camera, float aspect) {
  ViewFrame frame;
  frame.eye = camera.eye;
  const CameraBasis basis = camera.basis();
  frame.forward = basis.forward;
  frame.right = basis.right;
  frame.up = basis.up;
  frame.tanHalfFovY = std::tan(0.5f * camera.verticalFov);
  frame.tanHalfFovX = frame.tanHalfFovY * aspect;
  return frame;
}

// A vertex after projection onto the sample grid.
struct ScreenVertex {
  double x, y;      // sample-grid coordinates (y down)
  float invDepth;   // 1 / distance along the view direction; interpolates linearly on screen
  bool visible;     // in front of the near plane
};

// Twice the signed area of (a, b, p). Evaluated with the endpoints in a canonical order (by vertex index) so that
// both triangles sharing an edge get exactly opposite values, which leaves no cracks between them.
struct Edge {
  double ax, ay, dx, dy, sign;
  Edge(const ScreenVertex* v, uint32_t from, uint32_t to) {
    sign = 1.0;
    if (to < from) {
      std::swap(from, to);
      sign = -1.0;
    }
    ax = v[from].x;
    ay = v[from].y;
    dx = v[to].x - ax;
    dy = v[to].y - ay;
  }
  double at(double px, double py) const { return sign * (dx * (py - ay) - dy * (px - ax)); }
};

}  // namespace

std::vector<uint8_t> renderMesh(const Mesh& mesh, const SnapshotOptions& options) {
  if (options.width <= 0 || options.height <= 0 || options.supersampling <= 0) return {};
  const int ss = options.supersampling;
  const int sw = options.width * ss, sh = options.height * ss;  // sample grid
  const float aspect = static_cast<float>(options.width) / static_cast<float>(options.height);
  const Camera camera = options.camera ? *options.camera : frameMesh(mesh, kFrontThreeQuarter, aspect);
  const ViewFrame frame = viewFrame(camera, aspect);
  const glm::vec3 light = glm::normalize(options.lightDirection);
  const bool hasNormals = !mesh.normals.empty();
  const bool hasColors = !mesh.colors.empty();
  const bool textured = mesh.textured();
  TriangleLayers layers;
  auto imageOf = [&](int i) -> const RgbaImage* {
    const int32_t img = layers.image[i];
    return options.textures && img >= 0 && size_t(img) < options.textures->size() ? &(*options.textures)[size_t(img)]
                                                                                   : nullptr;
  };

  // Pass 1: background gradient and empty depth buffer (depth stored as 1 / distance: larger is nearer).
  const size_t sampleCount = static_cast<size_t>(sw) * static_cast<size_t>(sh);
  std::vector<glm::vec3> color(sampleCount);
  std::vector<float> nearness(sampleCount, 0.0f);
  for (int y = 0; y < sh; ++y) {
    const float t = (static_cast<float>(y) + 0.5f) / static_cast<float>(sh);
    const glm::vec3 background = options.backgroundTop + t * (options.backgroundBottom - options.backgroundTop);
    std::fill_n(color.begin() + static_cast<ptrdiff_t>(y) * sw, sw, background);
  }

  // Pass 2: project every vertex onto the sample grid.
  const float nearPlane = 1e-4f * glm::length(camera.target - camera.eye) + 1e-6f;
  std::vector<ScreenVertex> screen(mesh.vertexCount());
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 d = mesh.position(v) - frame.eye;
    const float depth = glm::dot(d, frame.forward);
    ScreenVertex& s = screen[v];
    s.visible = depth > nearPlane;
    if (!s.visible) continue;
    const float ndcX = glm::dot(d, frame.right) / (depth * frame.tanHalfFovX);
    const float ndcY = glm::dot(d, frame.up) / (depth * frame.tanHalfFovY);
    s.x = (0.5 + 0.5 * static_cast<double>(ndcX)) * sw;
    s.y = (0.5 - 0.5 * static_cast<double>(ndcY)) * sh;
    s.invDepth = 1.0f / depth;
  }

  // Pass 3: rasterise and shade each triangle into the samples it covers and is nearest at.
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t i0 = mesh.indices[3 * t], i1 = mesh.indices[3 * t + 1], i2 = mesh.indices[3 * t + 2];
    const ScreenVertex &a = screen[i0], &b = screen[i1], &c = screen[i2];
    if (!a.visible || !b.visible || !c.visible) continue;
    if (textured) layers.gather(mesh, i0, i1, i2);
    const Edge e0(screen.data(), i1, i2), e1(screen.data(), i2, i0), e2(screen.data(), i0, i1);
    const double area = e0.at(a.x, a.y);
    if (area == 0.0 || !std::isfinite(area)) continue;
    const double invArea = 1.0 / area;

    // Two-sided lighting. `facing` is +1 when the camera sees the side the normals point to, else -1 and the
    // normals are flipped. The side is decided per triangle (by the winding, corrected when the vertex normals
    // disagree with it), not per sample, so interpolated normals that tip slightly away near a silhouette stay.
    const glm::vec3 p0 = mesh.position(i0);
    glm::vec3 faceNormal = glm::cross(mesh.position(i1) - p0, mesh.position(i2) - p0);
    float facing = glm::dot(faceNormal, frame.eye - p0) >= 0.0f ? 1.0f : -1.0f;
    if (hasNormals && glm::dot(faceNormal, mesh.normal(i0) + mesh.normal(i1) + mesh.normal(i2)) < 0.0f)
      facing = -facing;
    const float faceLength = glm::length(faceNormal);
    faceNormal = faceLength > 0.0f ? faceNormal / faceLength : -frame.forward;
    if (glm::dot(faceNormal, frame.eye - p0) < 0.0f) faceNormal = -faceNormal;  // the side the camera sees

    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({a.x, b.x, c.x}))));
    const int x1 = std::min(sw - 1, static_cast<int>(std::ceil(std::max({a.x, b.x, c.x}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y, b.y, c.y}))));
    const int y1 = std::min(sh - 1, static_cast<int>(std::ceil(std::max({a.y, b.y, c.y}))));
    for (int y = y0; y <= y1; ++y) {
      const double py = y + 0.5;
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5;
        // Barycentric weights, all >= 0 inside (the sign of `area` absorbs the winding).
        const double w0 = e0.at(px, py) * invArea, w1 = e1.at(px, py) * invArea, w2 = e2.at(px, py) * invArea;
        if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
        const float inv = static_cast<float>(w0 * a.invDepth + w1 * b.invDepth + w2 * c.invDepth);
        const size_t s = static_cast<size_t>(y) * static_cast<size_t>(sw) + static_cast<size_t>(x);
        if (!(inv > nearness[s])) continue;
        nearness[s] = inv;
        // Perspective-correct weights for the vertex attributes.
        const float q0 = static_cast<float>(w0) * a.invDepth / inv;
        const float q1 = static_cast<float>(w1) * b.invDepth / inv;
        const float q2 = static_cast<float>(w2) * c.invDepth / inv;
        glm::vec3 n = faceNormal;
        if (hasNormals) {
          const glm::vec3 interpolated = q0 * mesh.normal(i0) + q1 * mesh.normal(i1) + q2 * mesh.normal(i2);
          const float length = glm::length(interpolated);
          if (length > 0.0f) n = interpolated * (facing / length);
        }
        glm::vec3 albedo =
            hasColors ? q0 * mesh.color(i0) + q1 * mesh.color(i1) + q2 * mesh.color(i2) : options.defaultColor;
        if (textured && layers.count > 0) {
          glm::vec3 factor(0.0f);
          float total = 0.0f;
          for (int i = 0; i < layers.count; ++i) {
            const float w = q0 * layers.weight[i][0] + q1 * layers.weight[i][1] + q2 * layers.weight[i][2];
            if (!(w > 0.0f)) continue;
            total += w;
            const glm::vec2 uv = q0 * layers.uv[i][0] + q1 * layers.uv[i][1] + q2 * layers.uv[i][2];
            const RgbaImage* image = imageOf(i);
            factor += w * (image ? sampleTexture(*image, uv.x, uv.y) : glm::vec3(1.0f));
          }
          albedo *= factor + glm::vec3(std::max(0.0f, 1.0f - total));
        }
        // Shade in camera space: x right, y up, z towards the viewer.
        const glm::vec3 nc(glm::dot(n, frame.right), glm::dot(n, frame.up), -glm::dot(n, frame.forward));
        const float diffuse = std::max(glm::dot(nc, light), 0.0f);
        const float rimTerm = std::pow(1.0f - std::clamp(nc.z, 0.0f, 1.0f), 3.0f);
        color[s] = albedo * (options.ambient + (1.0f - options.ambient) * diffuse) + glm::vec3(options.rim * rimTerm);
      }
    }
  }

  // Pass 4: average each pixel's samples in linear light, encode sRGB.
  std::vector<uint8_t> pixels(static_cast<size_t>(options.width) * static_cast<size_t>(options.height) * 4);
  const float weight = 1.0f / static_cast<float>(ss * ss);
  for (int y = 0; y < options.height; ++y) {
    for (int x = 0; x < options.width; ++x) {
      glm::vec3 sum(0.0f);
      for (int j = 0; j < ss; ++j) {
        for (int i = 0; i < ss; ++i) {
          sum += color[static_cast<size_t>(y * ss + j) * static_cast<size_t>(sw) + static_cast<size_t>(x * ss + i)];
        }
      }
      uint8_t* p = &pixels[(static_cast<size_t>(y) * static_cast<size_t>(options.width) + static_cast<size_t>(x)) * 4];
      p[0] = toByte(srgbEncode(sum.x * weight));
      p[1] = toByte(srgbEncode(sum.y * weight));
      p[2] = toByte(srgbEncode(sum.z * weight));
      p[3] = 255;
    }
  }
  return pixels;
}

std::expected<void, Diagnostics> renderMeshToPng(const Mesh& mesh, const SnapshotOptions& options,
                                                 const std::string& path) {
  const std::vector<uint8_t> pixels = renderMesh(mesh, options);
  if (pixels.empty()) return std::unexpected(singleError({}, path + ": image size and supersampling must be positive"));
  return savePng(pixels, options.width, options.height, path);
}

}  // namespace imps::app
