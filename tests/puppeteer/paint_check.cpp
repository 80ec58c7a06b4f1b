// SPDX-License-Identifier: MIT
// Checks a painting session of the live app (tests/puppeteer/paint_app_test.sh): the saved scene reloads, the
// texture it names for primitive PRIM is a new file (the original untouched) holding a stroke — some texels
// changed, all of them in one compact region covering a small part of the image, every other texel as it was.
// Given the brush (colour and radius in texels), the changed texels must be the stroke's footprint (painter.h's
// dabs: discs of that radius, antialiased over one texel): the texels painted fully in the brush colour (the core)
// are one connected region (the image repeats) holding at least one whole disc and more than one dab's worth, and
// every changed texel lies within two texels of the core (the antialiased rim), nothing elsewhere.
// Usage: paint_check SAVED.wrl ORIGINAL.png TEXTURE_INDEX [R,G,B RADIUS]. Exit 0 when every check passes; prints
// what failed.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "textures.h"

int main(int argc, char** argv) {
  using namespace imps;
  if (argc != 4 && argc != 6) {
    std::fprintf(stderr, "usage: paint_check SAVED.wrl ORIGINAL.png TEXTURE_INDEX [R,G,B RADIUS]\n");
    return 2;
  }
  int failures = 0;
  auto fail = [&](const std::string& what) {
    std::printf("FAIL: %s\n", what.c_str());
    ++failures;
  };
  auto scene = readSceneFile(argv[1]);
  if (!scene) return std::printf("FAIL: %s", scene.error().str().c_str()), 1;
  auto character = Character::fromScene(*scene);
  if (!character) return std::printf("FAIL: %s", character.error().str().c_str()), 1;
  auto images = app::loadTextures(*character);
  if (!images) return std::printf("FAIL: %s", images.error().str().c_str()), 1;
  const size_t k = size_t(std::atoi(argv[3]));
  if (k >= images->size()) return std::printf("FAIL: no texture %zu\n", k), 1;
  const std::string painted = character->textures()[k].path;
  if (std::filesystem::equivalent(painted, argv[2])) fail("the saved scene still names the original " + painted);
  const auto read = app::readImage(argv[2]);
  if (!read) return std::printf("FAIL: %s: %s\n", argv[2], read.error().all().front().message.c_str()), 1;
  const app::RgbaImage& original = *read;
  const app::RgbaImage& now = (*images)[k];
  if (now.width != original.width || now.height != original.height) return std::printf("FAIL: size changed\n"), 1;
  size_t changed = 0;
  int x0 = now.width, y0 = now.height, x1 = -1, y1 = -1;
  for (int y = 0; y < now.height; ++y)
    for (int x = 0; x < now.width; ++x) {
      const size_t at = (size_t(y) * size_t(now.width) + size_t(x)) * 4;
      if (now.rgba[at] == original.rgba[at] && now.rgba[at + 1] == original.rgba[at + 1] &&
          now.rgba[at + 2] == original.rgba[at + 2])
        continue;
      ++changed;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  const double fraction = double(changed) / (double(now.width) * double(now.height));
  std::printf("%s: %zu texels painted (%.2f%% of the image) in [%d, %d] x [%d, %d]\n", painted.c_str(), changed,
              100.0 * fraction, x0, x1, y0, y1);
  if (changed < 20) fail("the stroke changed fewer than 20 texels");
  if (fraction > 0.2) fail("more than 20% of the texture changed: not a stroke");
  if (changed > 0 && (x1 - x0 + 1) * (y1 - y0 + 1) > now.width * now.height / 2)
    fail("the changed texels are spread over more than half the image");
  if (argc == 6) {
    int colour[3] = {0, 0, 0};
    if (std::sscanf(argv[4], "%d,%d,%d", &colour[0], &colour[1], &colour[2]) != 3)
      return std::printf("FAIL: bad brush colour %s\n", argv[4]), 2;
    const float r = float(std::atof(argv[5]));
    const int w = now.width, h = now.height;
    auto at = [&](int x, int y) { return (size_t(((y % h) + h) % h) * size_t(w) + size_t(((x % w) + w) % w)); };
    std::vector<uint8_t> core(size_t(w) * size_t(h), 0);
    size_t cores = 0;  // changed texels now exactly in the brush colour
    for (size_t i = 0; i < core.size(); ++i) {
      const uint8_t *p = &now.rgba[4 * i], *o = &original.rgba[4 * i];
      core[i] =
          p[0] == colour[0] && p[1] == colour[1] && p[2] == colour[2] && (o[0] != p[0] || o[1] != p[1] || o[2] != p[2]);
      cores += core[i];
    }
    std::printf("core: %zu changed texels in the brush colour\n", cores);
    const float disc = 3.14159265f * (r - 0.5f) * (r - 0.5f);
    if (float(cores) < 1.5f * disc) fail("fewer core texels than one and a half dabs: not a stroke");
    // One connected core (4-neighbours, repeating across the edges).
    size_t first = core.size();
    for (size_t i = 0; i < core.size() && first == core.size(); ++i)
      if (core[i]) first = i;
    if (first < core.size()) {
      std::vector<uint8_t> seen(core.size(), 0);
      std::vector<size_t> stack{first};
      seen[first] = 1;
      size_t reached = 0;
      while (!stack.empty()) {
        const size_t i = stack.back();
        stack.pop_back();
        ++reached;
        const int x = int(i % size_t(w)), y = int(i / size_t(w));
        for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
          const size_t j = at(x + dx, y + dy);
          if (core[j] && !seen[j]) seen[j] = 1, stack.push_back(j);
        }
      }
      if (reached != cores) fail("the core is in several pieces");
    }
    // A whole disc of radius r - 1.5 around some core texel (the dabs are full discs), and no changed texel further
    // than two texels from the core.
    const int reach = int(std::ceil(r));
    bool wholeDisc = false;
    for (int y = 0; y < h && !wholeDisc; ++y)
      for (int x = 0; x < w && !wholeDisc; ++x) {
        if (!core[at(x, y)]) continue;
        bool full = true;
        for (int dy = -reach; dy <= reach && full; ++dy)
          for (int dx = -reach; dx <= reach && full; ++dx)
            if (float(dx * dx + dy * dy) <= (r - 1.5f) * (r - 1.5f)) full = core[at(x + dx, y + dy)] != 0;
        wholeDisc = full;
      }
    if (!wholeDisc) fail("no whole dab of radius " + std::to_string(r) + " in the core");
    size_t stray = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = at(x, y);
        const uint8_t *p = &now.rgba[4 * i], *o = &original.rgba[4 * i];
        if (p[0] == o[0] && p[1] == o[1] && p[2] == o[2]) continue;
        bool near = false;
        for (int dy = -2; dy <= 2 && !near; ++dy)
          for (int dx = -2; dx <= 2 && !near; ++dx) near = dx * dx + dy * dy <= 4 && core[at(x + dx, y + dy)];
        stray += !near;
      }
    if (stray > 0)
      fail(std::to_string(stray) + " changed texels outside the stroke's footprint (over two texels from its core)");
  }
  return failures == 0 ? 0 : 1;
}
