// Checks a painting session of the live app (tests/puppeteer/paint_app_test.sh): the saved scene reloads, the
// texture it names for primitive PRIM is a new file (the original untouched) holding a stroke — some texels
// changed, all of them in one compact region covering a small part of the image, every other texel as it was.
// Usage: paint_check SAVED.wrl ORIGINAL.png TEXTURE_INDEX. Exit 0 when every check passes; prints what failed.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "textures.h"

int main(int argc, char** argv) {
  using namespace imps;
  if (argc != 4) {
    std::fprintf(stderr, "usage: paint_check SAVED.wrl ORIGINAL.png TEXTURE_INDEX\n");
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
  if (!images) return std::printf("FAIL: %s\n", images.error().c_str()), 1;
  const size_t k = size_t(std::atoi(argv[3]));
  if (k >= images->size()) return std::printf("FAIL: no texture %zu\n", k), 1;
  const std::string painted = character->textures()[k].path;
  if (std::filesystem::equivalent(painted, argv[2])) fail("the saved scene still names the original " + painted);
  app::RgbaImage original;
  std::string error;
  if (!app::readImage(argv[2], original, &error)) return std::printf("FAIL: %s: %s\n", argv[2], error.c_str()), 1;
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
  return failures == 0 ? 0 : 1;
}
