// SPDX-License-Identifier: MIT
// Texture images (puppeteer/src/textures.h) and textured software rendering (snapshot.h): loading beside the scene,
// the error for a missing image, bilinear repeating sampling, and layers modulating the rendered colour.
#include "textures.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "failure_text.h"
#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/texturing.h"
#include "snapshot.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

// A w x h image whose left half is `left` and right half `right` (bytes).
RgbaImage halves(int w, int h, glm::u8vec3 left, glm::u8vec3 right) {
  RgbaImage image{w, h, std::vector<uint8_t>(size_t(w) * size_t(h) * 4)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::u8vec3 c = x < w / 2 ? left : right;
      uint8_t* p = &image.rgba[(size_t(y) * size_t(w) + size_t(x)) * 4];
      p[0] = c.r, p[1] = c.g, p[2] = c.b, p[3] = 255;
    }
  return image;
}

class TexturesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_textures_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_ / "maps");
  }
  void TearDown() override { fs::remove_all(dir_); }
  Character character(const std::string& url) {
    const std::string text =
        "#VRML V2.0 utf8\nExponentialBlend { children [\n  Metaball { texture ImageTexture { url \"" + url +
        "\" } }\n] }\n";
    auto scene = readScene(text, (dir_ / "s.wrl").string());
    EXPECT_TRUE(scene.has_value());
    auto c = Character::fromScene(*scene);
    EXPECT_TRUE(c.has_value());
    return std::move(*c);
  }
  fs::path dir_;
};

TEST_F(TexturesTest, ImagesAreReadRelativeToTheSceneFile) {
  const RgbaImage image = halves(8, 4, {255, 0, 0}, {0, 0, 255});
  ASSERT_EQ(test::failureText(savePng(image.rgba, image.width, image.height, (dir_ / "maps/skin.png").string())), "");
  const auto loaded = loadTextures(character("maps/skin.png"));
  ASSERT_TRUE(loaded.has_value()) << loaded.error().str();
  ASSERT_EQ(loaded->size(), 1u);
  EXPECT_EQ((*loaded)[0], image);
}

TEST_F(TexturesTest, AMissingOrUnreadableImageIsAnErrorNamingTheFileAndItsPlaceInTheScene) {
  const std::string scene = (dir_ / "s.wrl").string();
  auto missing = loadTextures(character("maps/none.png"));
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().str(), scene + ":3:41: error: cannot read texture 'maps/none.png' (" +
                                       (dir_ / "maps/none.png").string() + "): No such file or directory\n");
  std::ofstream(dir_ / "maps/junk.png") << "not an image";
  auto junk = loadTextures(character("maps/junk.png"));
  ASSERT_FALSE(junk.has_value());
  EXPECT_NE(junk.error().str().find(scene + ":3:41: error: cannot read texture 'maps/junk.png' ("), std::string::npos)
      << junk.error().str();
  EXPECT_TRUE(loadTextures(character("maps")).error().str().ends_with("): Is a directory\n"));
}

// Writes `values` (w x h x channels, rows from the top) to `path` through OpenImageIO as `type`.
template <typename T>
void writeImage(const fs::path& path, int w, int h, int channels, OIIO::TypeDesc type, const std::vector<T>& values,
                OIIO::TypeDesc source) {
  auto out = OIIO::ImageOutput::create(path.string());
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, channels, type);
  spec.attribute("Compression", "none");
  spec.attribute("CompressionQuality", 100);
  ASSERT_TRUE(out->open(path.string(), spec)) << out->geterror();
  ASSERT_TRUE(out->write_image(source, values.data())) << out->geterror();
  ASSERT_TRUE(out->close());
}

// EXR holds linear light: the loader encodes it to sRGB bytes, so that the renderers' sRGB decoding
// (sampleTexture, GL_SRGB8_ALPHA8) gives the file's values back (clamped to [0, 1]) instead of darkening them.
TEST_F(TexturesTest, ExrLinearValuesComeBackLinearThroughTheSrgbDecoding) {
  const std::vector<float> linear = {0.0f, 0.002f, 0.05f, 0.18f, 0.5f, 0.8f, 1.0f, 3.0f};  // 8 x 1, grey
  for (const OIIO::TypeDesc& type : {OIIO::TypeDesc(OIIO::TypeDesc::FLOAT), OIIO::TypeDesc(OIIO::TypeDesc::HALF)}) {
    SCOPED_TRACE(type.c_str());
    std::vector<float> rgba;
    for (float x : linear) rgba.insert(rgba.end(), {x, x * 0.5f, 0.25f, 0.6f});
    writeImage(dir_ / "maps/light.exr", 8, 1, 4, type, rgba, OIIO::TypeDesc::FLOAT);
    const auto read = readImage((dir_ / "maps/light.exr").string());
    ASSERT_TRUE(read) << read.error().str();
    const RgbaImage& image = *read;
    ASSERT_EQ(image.width, 8);
    ASSERT_EQ(image.height, 1);
    for (int x = 0; x < 8; ++x) {
      const glm::vec3 c = sampleTexture(image, (float(x) + 0.5f) / 8.0f, 0.5f);
      // One 8-bit sRGB step is at most ~1.3 % of the value above 0.05 (and 0.0004 below).
      const auto near = [](float want) { return 0.0005f + 0.015f * std::min(want, 1.0f); };
      EXPECT_NEAR(c.r, std::min(linear[size_t(x)], 1.0f), near(linear[size_t(x)])) << "texel " << x;
      EXPECT_NEAR(c.g, std::min(0.5f * linear[size_t(x)], 1.0f), near(0.5f * linear[size_t(x)])) << "texel " << x;
      EXPECT_NEAR(c.b, 0.25f, near(0.25f));
      EXPECT_EQ(image.rgba[size_t(x) * 4 + 3], 153) << "alpha stays linear: 0.6 x 255";
    }
    EXPECT_EQ(image.rgba[4 * 4], 188) << "linear 0.5 is sRGB byte 188";
  }
}

// JPEG (like PNG) stores sRGB bytes: they are kept as they are.
TEST_F(TexturesTest, JpegBytesAreKeptAsTheyAre) {
  std::vector<uint8_t> rgb;
  const glm::u8vec3 colours[4] = {{200, 100, 50}, {20, 220, 120}, {128, 128, 128}, {250, 10, 240}};
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) {
      const glm::u8vec3 c = colours[(y / 16) * 2 + x / 16];
      rgb.insert(rgb.end(), {c.r, c.g, c.b});
    }
  writeImage(dir_ / "maps/skin.jpg", 32, 32, 3, OIIO::TypeDesc::UINT8, rgb, OIIO::TypeDesc::UINT8);
  const auto loaded = loadTextures(character("maps/skin.jpg"));
  ASSERT_TRUE(loaded.has_value()) << loaded.error().str();
  const RgbaImage& image = (*loaded)[0];
  ASSERT_EQ(image.width, 32);
  ASSERT_EQ(image.height, 32);
  for (int q = 0; q < 4; ++q) {
    const int x = (q % 2) * 16 + 8, y = (q / 2) * 16 + 8;  // inside each block, away from its edges
    const uint8_t* p = &image.rgba[(size_t(y) * 32 + size_t(x)) * 4];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(int(p[k]), int(colours[q][k]), 3) << "block " << q << " channel " << k;
    EXPECT_EQ(p[3], 255) << "no alpha: opaque";
  }
}

TEST(SampleTexture, BilinearRepeatingAndVUp) {
  // Top row white, bottom row black (rows from the top): v = 1 is the top.
  RgbaImage image{1, 2, {255, 255, 255, 255, 0, 0, 0, 255}};
  EXPECT_NEAR(sampleTexture(image, 0.5f, 0.75f).g, 1.0f, 1e-6f);  // the top texel's centre
  EXPECT_NEAR(sampleTexture(image, 0.5f, 0.25f).g, 0.0f, 1e-6f);  // the bottom one's
  EXPECT_NEAR(sampleTexture(image, 0.5f, 0.5f).g, 0.5f, 1e-6f);   // half way (linear bytes: 0 and 1)
  EXPECT_NEAR(sampleTexture(image, 7.5f, -2.25f).g, 1.0f, 1e-6f);  // repeats: v = -2.25 is v = 0.75
  EXPECT_EQ(sampleTexture(RgbaImage{}, 0.3f, 0.3f), glm::vec3(1.0f));  // no image: white
}

// A metaball with a slide projected on its front, left half red and right half blue, rendered from the front: the
// texture modulates the surface colour where the layer weighs in, and without the images the surface is plain.
TEST(TexturedSnapshot, LayersModulateTheColourWithTheirImages) {
  auto scene = readScene(R"(#VRML V2.0 utf8
ExponentialBlend { children [
  Metaball { radius 1 material Material { diffuseColor 1 1 1 }
             texGen TexGenPlane { width 2 height 2 } texture ImageTexture { url "x.png" } }
] }
)", "s.wrl");
  ASSERT_TRUE(scene.has_value());
  auto c = Character::fromScene(*scene);
  ASSERT_TRUE(c.has_value());
  SkeletonCache cache(*c);
  MarchingCubesOptions o;
  o.cellSize = 0.05f;
  Mesh mesh = polygonize(cache.field(), o);
  textureMesh(mesh, cache);
  const std::vector<RgbaImage> images = {halves(16, 16, {255, 0, 0}, {0, 0, 255})};
  SnapshotOptions options;
  options.width = options.height = 64;
  options.camera = Camera{.eye = {0, 0, 5}, .target = {0, 0, 0}, .up = {0, 1, 0}, .verticalFov = 0.6f};
  options.rim = 0.0f;
  options.textures = &images;
  const std::vector<uint8_t> textured = renderMesh(mesh, options);
  auto pixel = [](const std::vector<uint8_t>& p, int x, int y) { return &p[(size_t(y) * 64 + size_t(x)) * 4]; };
  const uint8_t* left = pixel(textured, 24, 32);
  const uint8_t* right = pixel(textured, 40, 32);
  EXPECT_GT(left[0], 100);
  EXPECT_LT(left[2], 10);
  EXPECT_GT(right[2], 100);
  EXPECT_LT(right[0], 10);
  options.textures = nullptr;  // layers without images are white: the plain white surface
  const std::vector<uint8_t> plain = renderMesh(mesh, options);
  EXPECT_GT(pixel(plain, 24, 32)[2], 100);
  EXPECT_EQ(pixel(plain, 24, 32)[0], pixel(plain, 24, 32)[2]);
  mesh.clearTextures();  // and an untextured mesh renders as before
  EXPECT_EQ(renderMesh(mesh, options), plain);
}

}  // namespace
}  // namespace imps::app
