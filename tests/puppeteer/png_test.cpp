// SPDX-License-Identifier: MIT
// PNG files (puppeteer/src/png.h): saved then read back pixel-exact, saved atomically, and refused with an error
// when truncated, not an image, missing, or named other than .png.
#include "png.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "scratch_dir.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

// width x height RGBA8 pixels of noise, alpha included (a few fully transparent and opaque ones among them).
std::vector<uint8_t> noise(int width, int height, uint32_t seed) {
  std::mt19937 random(seed);
  std::vector<uint8_t> rgba(size_t(width) * size_t(height) * 4);
  for (uint8_t& v : rgba) v = uint8_t(random() & 0xFF);
  rgba[3] = 0;
  if (rgba.size() >= 8) rgba[7] = 255;  // (a 1 x 1 image has one pixel)
  return rgba;
}

TEST(Png, SavedPixelsReadBackExactly) {
  const ScratchDir dir("imps_png");
  for (const auto& [width, height] : std::vector<std::pair<int, int>>{{1, 1}, {37, 5}, {64, 48}}) {
    const std::vector<uint8_t> rgba = noise(width, height, uint32_t(width * 131 + height));
    const std::string path = (dir / ("n" + std::to_string(width) + ".png")).string();
    const auto saved = savePng(rgba, width, height, path);
    ASSERT_TRUE(saved) << saved.error().str();
    const auto image = readImage(path);
    ASSERT_TRUE(image) << image.error().str();
    EXPECT_EQ(image->width, width);
    EXPECT_EQ(image->height, height);
    EXPECT_EQ(image->rgba, rgba) << width << "x" << height;
  }
}

// The encoded bytes are a PNG (its signature) and are what savePng writes; the extension may be upper case.
TEST(Png, EncodedBytesAreWhatIsSaved) {
  const ScratchDir dir("imps_png");
  const std::vector<uint8_t> rgba = noise(16, 9, 7);
  const auto bytes = encodePng(rgba, 16, 9);
  ASSERT_TRUE(bytes) << bytes.error().str();
  ASSERT_GT(bytes->size(), 8u);
  EXPECT_EQ(std::string(bytes->begin(), bytes->begin() + 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const std::string path = (dir / "UPPER.PNG").string();
  ASSERT_TRUE(savePng(rgba, 16, 9, path));
  EXPECT_EQ(fileBytes(path), std::string(bytes->begin(), bytes->end()));
}

// A PNG cut short is an error, not a picture with missing rows; so is a file that is no image, and a missing one.
TEST(Png, TruncatedGarbageAndMissingFilesAreErrors) {
  const ScratchDir dir("imps_png");
  const std::vector<uint8_t> rgba = noise(32, 32, 3);
  ASSERT_TRUE(savePng(rgba, 32, 32, (dir / "whole.png").string()));
  const std::string whole = fileBytes(dir / "whole.png");
  for (const size_t keep : {whole.size() / 2, size_t(40), size_t(8)}) {
    writeBytes(dir / "cut.png", whole.substr(0, keep));
    EXPECT_FALSE(readImage((dir / "cut.png").string())) << keep << " of " << whole.size() << " bytes";
  }
  writeBytes(dir / "garbage.png", "this is not a PNG file at all\n");
  EXPECT_FALSE(readImage((dir / "garbage.png").string()));
  EXPECT_FALSE(readImage((dir / "missing.png").string()));
}

// A name that is not .png, or a directory that does not exist, is refused; nothing is created, and a failed save
// leaves no temporary file behind.
TEST(Png, BadPathsAreRefusedAndLeaveNothing) {
  const ScratchDir dir("imps_png");
  const std::vector<uint8_t> rgba = noise(8, 8, 5);
  EXPECT_FALSE(savePng(rgba, 8, 8, (dir / "x.jpg").string()));
  EXPECT_FALSE(fs::exists(dir / "x.jpg"));
  const auto noDir = savePng(rgba, 8, 8, (dir / "nodir/x.png").string());
  ASSERT_FALSE(noDir);
  EXPECT_NE(noDir.error().str().find("nodir"), std::string::npos) << noDir.error().str();
  EXPECT_FALSE(fs::exists(dir / "nodir"));
  // Replacing an existing picture is atomic: afterwards it is the new one, and no temporary file is left.
  ASSERT_TRUE(savePng(noise(8, 8, 1), 8, 8, (dir / "p.png").string()));
  ASSERT_TRUE(savePng(rgba, 8, 8, (dir / "p.png").string()));
  const auto image = readImage((dir / "p.png").string());
  ASSERT_TRUE(image) << image.error().str();
  EXPECT_EQ(image->rgba, rgba);
  size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1u);
}

}  // namespace
}  // namespace imps::app
