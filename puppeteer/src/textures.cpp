// SPDX-License-Identifier: MIT
// Texture images: loading beside the scene file, and bilinear sampling for the software renderer.
#include "textures.h"

#include <array>
#include <cmath>
#include <filesystem>
#include <system_error>

namespace imps::app {

namespace {

float srgbToLinear(uint8_t byte) {
  const float c = static_cast<float>(byte) / 255.0f;
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// A table is much cheaper than pow() per texel.
const std::array<float, 256>& linearTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(uint8_t(i));
    return t;
  }();
  return table;
}

}  // namespace

std::expected<std::vector<RgbaImage>, Diagnostics> loadTextures(const Character& character) {
  std::vector<RgbaImage> images;
  Diagnostics errors;
  for (const CharacterTexture& t : character.textures()) {
    RgbaImage image;
    std::string reason;
    std::error_code ec;
    if (!std::filesystem::exists(t.path, ec)) {
      reason = "No such file or directory";
    } else if (std::filesystem::is_directory(t.path, ec)) {
      reason = "Is a directory";
    } else if (auto read = readImage(t.path); !read) {
      reason = read.error().all().front().message;
    } else {
      image = std::move(*read);
    }
    if (!reason.empty()) errors.error(t.loc, "cannot read texture '" + t.url + "' (" + t.path + "): " + reason);
    images.push_back(std::move(image));
  }
  if (errors.hasErrors()) return std::unexpected(std::move(errors));
  return images;
}

glm::vec3 sampleTexture(const RgbaImage& image, float u, float v) {
  if (image.width <= 0 || image.height <= 0) return glm::vec3(1.0f);
  // Texel centres at (i + 1/2) / width; v = 1 is the top row.
  const float x = (u - std::floor(u)) * float(image.width) - 0.5f;
  const float y = (1.0f - (v - std::floor(v))) * float(image.height) - 0.5f;
  const float fx = std::floor(x), fy = std::floor(y);
  const float ax = x - fx, ay = y - fy;
  auto wrap = [](int i, int n) { return ((i % n) + n) % n; };
  const int x0 = wrap(int(fx), image.width), x1 = wrap(int(fx) + 1, image.width);
  const int y0 = wrap(int(fy), image.height), y1 = wrap(int(fy) + 1, image.height);
  const auto& lin = linearTable();
  auto texel = [&](int i, int j) {
    const uint8_t* p = image.rgba.data() + (size_t(j) * size_t(image.width) + size_t(i)) * 4;
    return glm::vec3(lin[p[0]], lin[p[1]], lin[p[2]]);
  };
  return (1 - ay) * ((1 - ax) * texel(x0, y0) + ax * texel(x1, y0)) +
         ay * ((1 - ax) * texel(x0, y1) + ax * texel(x1, y1));
}

void TriangleLayers::gather(const Mesh& mesh, uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t corner[3] = {a, b, c};
  count = 0;
  for (int k = 0; k < 3; ++k)
    for (int slot = 0; slot < 2; ++slot) {
      const int32_t l = mesh.layers[2 * corner[k] + slot];
      if (l < 0) continue;
      int i = 0;
      while (i < count && layer[i] != l) ++i;
      if (i == count) {
        layer[i] = l;
        image[i] = mesh.layerImages[size_t(l)];
        weight[i] = glm::vec3(0.0f);
        for (int q = 0; q < 3; ++q) uv[i][q] = mesh.layerUv(corner[q], l);
        for (int q = 1; q < 3; ++q) uv[i][q].x -= std::round(uv[i][q].x - uv[i][0].x);
        ++count;
      }
      weight[i][k] += mesh.layerWeights[2 * corner[k] + slot];
    }
}

}  // namespace imps::app
