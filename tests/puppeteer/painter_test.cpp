// SPDX-License-Identifier: MIT
// 3D painting (puppeteer/src/painter.h): the ray cast, an antialiased dab into the owning primitive's texture and
// nowhere else, and saving painted textures under new names so that the saved scene reloads with the stroke.
#include "painter.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "failure_text.h"
#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/texturing.h"
#include "textures.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

RgbaImage white(int w, int h) { return RgbaImage{w, h, std::vector<uint8_t>(size_t(w) * size_t(h) * 4, 255)}; }

class PainterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_painter_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    const RgbaImage blank = white(64, 64);
    ASSERT_EQ(test::failureText(savePng(blank.rgba, 64, 64, (dir_ / "face.png").string())), "");
    ASSERT_EQ(test::failureText(savePng(blank.rgba, 64, 64, (dir_ / "back.png").string())), "");
    // Two balls side by side; the left one's face is a slide projected from the front.
    std::ofstream(dir_ / "s.wrl") << R"(#VRML V2.0 utf8
ExponentialBlend { children [
  Metaball { center -1 0 0 radius 1 texGen TexGenPlane { width 2 height 2 } texture ImageTexture { url "face.png" } }
  Metaball { center 1.2 0 0 radius 0.8 texture ImageTexture { url "back.png" } }
] }
)";
    auto scene = readSceneFile((dir_ / "s.wrl").string());
    ASSERT_TRUE(scene.has_value()) << scene.error().str();
    scene_ = *scene;
    auto c = Character::fromScene(scene_);
    ASSERT_TRUE(c.has_value());
    character_ = std::make_unique<Character>(std::move(*c));
    auto images = loadTextures(*character_);
    ASSERT_TRUE(images.has_value()) << images.error().str();
    images_ = std::move(*images);
    SkeletonCache cache(*character_);
    MarchingCubesOptions o;
    o.cellSize = 0.05f;
    mesh_ = polygonize(cache.field(), o);
    textureMesh(mesh_, cache);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path dir_;
  Scene scene_;
  std::unique_ptr<Character> character_;
  std::vector<RgbaImage> images_;
  Mesh mesh_;
};

TEST_F(PainterTest, TheRayHitsTheNearestSurface) {
  const auto hit = intersectMesh(mesh_, PickRay{{-1.2f, 0.3f, 5}, {0, 0, -1}});
  ASSERT_TRUE(hit.has_value());
  // The left ball's front: z = sqrt(1 - 0.2^2 - 0.3^2) (a little more: the blend swells it).
  EXPECT_NEAR(hit->point.x, -1.2f, 1e-4f);
  EXPECT_NEAR(hit->point.y, 0.3f, 1e-4f);
  EXPECT_GT(hit->point.z, 0.9f);
  EXPECT_LT(hit->point.z, 1.05f);
  EXPECT_NEAR(hit->barycentric.x + hit->barycentric.y + hit->barycentric.z, 1.0f, 1e-5f);
  EXPECT_FALSE(intersectMesh(mesh_, PickRay{{-1.2f, 0.3f, 5}, {0, 0, 1}}).has_value()) << "nothing behind the eye";
  EXPECT_FALSE(intersectMesh(mesh_, PickRay{{0, 5, 5}, {0, 0, -1}}).has_value()) << "a miss";
}

TEST_F(PainterTest, ADabChangesOnlyTheTexelsUnderTheBrushOfTheOwningTexture) {
  const auto hit = intersectMesh(mesh_, PickRay{{-1.0f, 0.0f, 5}, {0, 0, -1}});  // the face's centre
  ASSERT_TRUE(hit.has_value());
  Brush brush;
  brush.size = 4;  // radius 5 texels
  brush.color[0] = 10, brush.color[1] = 20, brush.color[2] = 200;
  const std::vector<RgbaImage> before = images_;
  ASSERT_EQ(paintDab(mesh_, *hit, brush, images_), 0) << "into the left ball's image";
  EXPECT_EQ(images_[1], before[1]) << "the other texture is untouched";
  // The slide's centre (u, v) = (1/2, 1/2) is texel (32, 32) of the 64 x 64 image.
  const glm::vec2 uv = mesh_.layerGens[0].map(hit->point);
  const float cx = uv.x * 64.0f, cy = (1.0f - uv.y) * 64.0f;
  size_t full = 0, partial = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const uint8_t* p = &images_[0].rgba[(size_t(y) * 64 + size_t(x)) * 4];
      const float d = std::hypot(float(x) + 0.5f - cx, float(y) + 0.5f - cy);
      if (d > 5.5f) {
        EXPECT_EQ(p[0], 255) << x << "," << y << " is outside the brush";
        EXPECT_EQ(p[2], 255);
      } else if (d < 4.5f) {
        EXPECT_EQ(p[0], 10) << x << "," << y;
        EXPECT_EQ(p[1], 20);
        EXPECT_EQ(p[2], 200);
        ++full;
      } else if (p[0] != 255 && p[0] != 10) {
        ++partial;  // the antialiased rim: a mix of the brush and the texel
      }
      EXPECT_EQ(p[3], 255);
    }
  EXPECT_GT(full, 50u);
  EXPECT_GT(partial, 8u);
}

TEST_F(PainterTest, SavingWritesThePaintedTexturesUnderNewNamesAndTheSceneReloadsWithTheStroke) {
  const auto hit = intersectMesh(mesh_, PickRay{{-1.0f, 0.2f, 5}, {0, 0, -1}});
  ASSERT_TRUE(hit.has_value());
  Brush brush;
  brush.size = 0;
  ASSERT_EQ(paintDab(mesh_, *hit, brush, images_), 0);
  const std::string original = slurp(dir_ / "face.png");
  fs::create_directories(dir_ / "out");
  const std::string saved = (dir_ / "out/painted.wrl").string();
  ASSERT_EQ(test::failureText(savePaintedScene(scene_, *character_, images_, {true, false}, saved)), "");
  EXPECT_EQ(slurp(dir_ / "face.png"), original) << "the original is never overwritten";
  EXPECT_TRUE(fs::exists(dir_ / "out/painted_face.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out/painted_back.png")) << "only painted textures are written";
  auto reread = readSceneFile(saved);
  ASSERT_TRUE(reread.has_value()) << reread.error().str();
  auto c = Character::fromScene(*reread);
  ASSERT_TRUE(c.has_value());
  ASSERT_EQ(c->textures().size(), 2u);
  EXPECT_EQ(c->textures()[0].url, "painted_face.png");
  EXPECT_EQ(c->textures()[1].url, "../back.png");  // unpainted: the original file, from the new place
  auto reloaded = loadTextures(*c);
  ASSERT_TRUE(reloaded.has_value()) << reloaded.error().str();
  EXPECT_EQ((*reloaded)[0], images_[0]) << "the saved texture holds the stroke";
  EXPECT_EQ((*reloaded)[1], images_[1]);
  // Painting the saved scene and saving it again: a new file again, the first painted one kept.
  const std::string first = slurp(dir_ / "out/painted_face.png");
  ASSERT_EQ(test::failureText(savePaintedScene(*reread, *c, *reloaded, {true, false}, saved)), "");
  EXPECT_TRUE(fs::exists(dir_ / "out/painted_painted_face.png"));
  EXPECT_EQ(slurp(dir_ / "out/painted_face.png"), first);
}

// The app's plain `s` (nothing painted) into another directory: the saved scene still finds its images; in the
// scene's own directory the urls stay as written.
TEST_F(PainterTest, APlainSaveElsewhereKeepsTheImagesReachable) {
  fs::create_directories(dir_ / "elsewhere");
  ASSERT_EQ(
      test::failureText(savePaintedScene(scene_, *character_, images_, {}, (dir_ / "elsewhere/moved.wrl").string())),
      "");
  auto moved = readSceneFile((dir_ / "elsewhere/moved.wrl").string());
  ASSERT_TRUE(moved.has_value());
  auto c = Character::fromScene(*moved);
  ASSERT_TRUE(c.has_value());
  EXPECT_EQ(c->textures()[0].url, "../face.png");
  auto images = loadTextures(*c);
  ASSERT_TRUE(images.has_value()) << images.error().str();
  EXPECT_EQ(*images, images_);
  ASSERT_EQ(test::failureText(savePaintedScene(scene_, *character_, images_, {}, (dir_ / "same.wrl").string())), "");
  auto same = readSceneFile((dir_ / "same.wrl").string());
  ASSERT_TRUE(same.has_value());
  EXPECT_EQ(same->sceneGraph() != nullptr, true);
  auto cs = Character::fromScene(*same);
  ASSERT_TRUE(cs.has_value());
  EXPECT_EQ(cs->textures()[0].url, "face.png");
  EXPECT_EQ(fs::directory_iterator(dir_ / "elsewhere") != fs::directory_iterator(), true);
}

TEST(PaintedTextureNames, NeverTheNameOfOneOfTheScenesTextures) {
  auto scene = readScene(R"(#VRML V2.0 utf8
ExponentialBlend { children [
  Metaball { texture ImageTexture { url "face.png" } }
  Metaball { center 2 0 0 texture ImageTexture { url "x_face.png" } }
] }
)", "/d/s.wrl");
  ASSERT_TRUE(scene.has_value());
  auto c = Character::fromScene(*scene);
  ASSERT_TRUE(c.has_value());
  // Saved as /d/x.wrl, face.png would become /d/x_face.png: the other texture's file, so the next free name.
  EXPECT_EQ(paintedTextureNames(*c, {true, false}, "/d/x.wrl"), (std::vector<std::string>{"/d/x_face_2.png", ""}));
  EXPECT_EQ(paintedTextureNames(*c, {true, true}, "/e/y.wrl"),
            (std::vector<std::string>{"/e/y_face.png", "/e/y_x_face.png"}));
}

// A file already beside the saved scene — unrelated to it, or saved before — is never overwritten.
TEST_F(PainterTest, NeverTheNameOfAFileThatIsAlreadyThere) {
  const std::string scenePath = (dir_ / "x.wrl").string();
  const std::vector<std::string> first = paintedTextureNames(*character_, {true, false}, scenePath);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[0], (dir_ / "x_face.png").string());
  std::ofstream(first[0]) << "someone else's picture";
  const std::vector<std::string> second = paintedTextureNames(*character_, {true, false}, scenePath);
  EXPECT_EQ(second[0], (dir_ / "x_face_2.png").string());
  fs::create_symlink(dir_ / "nowhere.png", dir_ / "x_face_2.png");  // dangling: writing through it would create a file
  EXPECT_EQ(paintedTextureNames(*character_, {true, false}, scenePath)[0], (dir_ / "x_face_3.png").string());
  ASSERT_EQ(test::failureText(savePaintedScene(scene_, *character_, images_, {true, false}, scenePath)), "");
  std::ifstream kept(first[0]);
  std::string text((std::istreambuf_iterator<char>(kept)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "someone else's picture");
  EXPECT_TRUE(fs::exists(dir_ / "x_face_3.png"));
}

}  // namespace
}  // namespace imps::app
