// SPDX-License-Identifier: MIT
// Textured export (puppeteer/src/textured_export.h, imps::encodeTexturedGlb / encodeTexturedObj): the textured
// blobs as glTF binary with embedded images and TEXCOORD_0 from the generators, valid for the Khronos validator
// (when node and gltf-validator are installed), and as OBJ with an .mtl and the images beside it.
#include "textured_export.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

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

struct Blobs {
  Character character;
  std::vector<RgbaImage> images;
  Mesh mesh;
};

Blobs texturedBlobs() {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/textured_blobs.wrl");
  EXPECT_TRUE(scene.has_value());
  auto c = Character::fromScene(*scene);
  EXPECT_TRUE(c.has_value());
  Blobs b{std::move(*c), {}, {}};
  auto images = loadTextures(b.character);
  EXPECT_TRUE(images.has_value()) << images.error().str();
  b.images = std::move(*images);
  SkeletonCache cache(b.character);
  MarchingCubesOptions o;
  o.cellSize = 0.1f;
  b.mesh = polygonize(cache.field(), o);
  textureMesh(b.mesh, cache);
  return b;
}

class TexturedExport : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_textured_export_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(TexturedExport, GlbEmbedsTheImagesAndTheGeneratorsCoordinates) {
  const Blobs b = texturedBlobs();
  ASSERT_TRUE(b.mesh.textured());
  const std::string path = (dir_ / "blobs.glb").string();
  ASSERT_EQ(test::failureText(writeTexturedMesh(b.mesh, b.character, b.images, path)), "");
  const std::string bytes = slurp(path);
  uint32_t jsonLength = 0;
  std::memcpy(&jsonLength, bytes.data() + 12, 4);
  const auto gltf = nlohmann::json::parse(bytes.substr(20, jsonLength));
  const size_t binStart = 20 + jsonLength + 8;
  ASSERT_EQ(gltf["images"].size(), 2u);
  ASSERT_EQ(gltf["textures"].size(), 2u);
  // The images are the PNG files themselves.
  for (size_t k = 0; k < 2; ++k) {
    const auto& image = gltf["images"][k];
    EXPECT_EQ(image["mimeType"], "image/png");
    const auto& view = gltf["bufferViews"][image["bufferView"].get<size_t>()];
    const std::string embedded =
        bytes.substr(binStart + view["byteOffset"].get<size_t>(), view["byteLength"].get<size_t>());
    EXPECT_EQ(embedded, slurp(b.character.textures()[k].path)) << k;
  }
  // Every textured primitive: TEXCOORD_0 is (u, 1 - v) of its texture's generator at the vertex (u up to the
  // whole turns a seam-crossing triangle unwraps by).
  size_t textured = 0;
  for (const auto& primitive : gltf["meshes"][0]["primitives"]) {
    const auto& material = gltf["materials"][primitive["material"].get<size_t>()];
    if (!material["pbrMetallicRoughness"].contains("baseColorTexture")) continue;
    ++textured;
    const size_t texture = material["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    const size_t image = gltf["textures"][texture]["source"];
    const int32_t layer = image == 0 ? 0 : 1;  // each blob has its own image, in primitive order
    auto floats = [&](size_t accessor) {
      const auto& view = gltf["bufferViews"][gltf["accessors"][accessor]["bufferView"].get<size_t>()];
      std::vector<float> out(view["byteLength"].get<size_t>() / 4);
      std::memcpy(out.data(), bytes.data() + binStart + view["byteOffset"].get<size_t>(), out.size() * 4);
      return out;
    };
    const auto positions = floats(primitive["attributes"]["POSITION"]);
    const auto st = floats(primitive["attributes"]["TEXCOORD_0"]);
    ASSERT_EQ(st.size() / 2, positions.size() / 3);
    for (size_t v = 0; v < st.size() / 2; ++v) {
      const glm::vec3 p(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]);
      const glm::vec2 uv = b.mesh.layerGens[size_t(layer)].map(p);
      EXPECT_NEAR(st[2 * v] - std::round(st[2 * v] - uv.x), uv.x, 1e-5f);
      EXPECT_NEAR(st[2 * v + 1], 1.0f - uv.y, 1e-5f);
    }
  }
  EXPECT_EQ(textured, 2u);

  // The Khronos validator, when it is installed (npm install -g gltf-validator).
  const std::string script = std::string(IMPS_SOURCE_DIR) + "/tests/puppeteer/validate_gltf.js";
  const std::string command = "command -v node >/dev/null 2>&1 && NODE_PATH=\"$(npm root -g 2>/dev/null)\" node '" +
                              script + "' '" + path + "' > '" + (dir_ / "report.txt").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const std::string text = slurp(dir_ / "report.txt");
  if (code != 0 && code != 1) GTEST_SKIP() << "node or gltf-validator not available: " << text;
  std::printf("gltf-validator: %s", text.c_str());
  EXPECT_EQ(code, 0) << text;
}

TEST_F(TexturedExport, ObjWritesTheMaterialLibraryAndTheImagesBesideIt) {
  const Blobs b = texturedBlobs();
  const std::string path = (dir_ / "blobs.obj").string();
  ASSERT_EQ(test::failureText(writeTexturedMesh(b.mesh, b.character, b.images, path)), "");
  const std::string obj = slurp(path), mtl = slurp(dir_ / "blobs.mtl");
  EXPECT_NE(obj.find("mtllib blobs.mtl\n"), std::string::npos);
  EXPECT_NE(obj.find("usemtl texture0\n"), std::string::npos);
  EXPECT_NE(obj.find("usemtl texture1\n"), std::string::npos);
  EXPECT_NE(mtl.find("newmtl texture0\nKd 1 1 1\nmap_Kd blobs_0.png\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("map_Kd blobs_1.png\n"), std::string::npos) << mtl;
  EXPECT_EQ(slurp(dir_ / "blobs_0.png"), slurp(b.character.textures()[0].path));
  EXPECT_EQ(slurp(dir_ / "blobs_1.png"), slurp(b.character.textures()[1].path));
  size_t vs = 0, vts = 0;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    vs += line.starts_with("v ");
    vts += line.starts_with("vt ");
  }
  EXPECT_EQ(vs, vts);
  EXPECT_GE(vs, b.mesh.vertexCount());
  // An untextured mesh is written as before, without a material library.
  Mesh plain = b.mesh;
  plain.clearTextures();
  ASSERT_EQ(test::failureText(writeTexturedMesh(plain, b.character, b.images, (dir_ / "plain.obj").string())), "");
  EXPECT_EQ(slurp(dir_ / "plain.obj").find("mtllib"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir_ / "plain.mtl"));
}

}  // namespace
}  // namespace imps::app
