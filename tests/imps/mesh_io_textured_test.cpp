// SPDX-License-Identifier: MIT
// Textured export (imps/src/mesh_io_textured.cpp) on a hand-made textured octahedron whose two layers are plane
// projectors: the GLB's chunks and lengths, one primitive per image with TEXCOORD_0 = (u, 1 - v) of its generator,
// the images embedded byte for byte with their names and MIME types, one texture per image with a repeating,
// trilinear sampler, the untextured part's plain material, the fallbacks to encodeGlb, and a layer naming a missing
// image refused; the OBJ's groups, materials and v/vt/vn counts, and the .mtl's map_Kd lines.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "imps/mesh_io.h"
#include "imps/texgen.h"
#include "octahedron.h"
#include "scratch_dir.h"

namespace imps {
namespace {

// Why a writer or encoder failed (its one error, which names the file for a writer), "" when it succeeded.
template <class T>
std::string failure(const std::expected<T, Diagnostics>& result) {
  return result ? std::string() : result.error().all().front().message;
}

using nlohmann::json;

// The octahedron of radius 1 (vertices +x -x +y -y +z -z), faces outward. Layer 0 (image 0) weighs most on the
// upper faces, layer 1 (image 1) on the lower ones; both are plane projectors down -z with a 4 x 4 slide, so
// (u, v) = (1/2 + x/4, 1/2 + y/4), inside the slide.
Mesh texturedOctahedron() {
  Mesh m = test::octahedronMesh();
  m.normals = m.positions;
  for (size_t v = 0; v < m.vertexCount(); ++v) m.colors.insert(m.colors.end(), {0.5f, 0.25f, 1.5f});  // 1.5: clamped
  TexGen plane;
  plane.type = TexGenType::Plane;
  plane.width = plane.height = 4.0f;
  m.layerGens = {plane, plane};
  m.layerImages = {0, 1};
  for (size_t v = 0; v < 6; ++v) {
    const bool top = v == 4, bottom = v == 5;
    m.layers.insert(m.layers.end(), {0, 1});
    m.layerWeights.insert(m.layerWeights.end(), {top ? 1.0f : bottom ? 0.0f : 0.5f, bottom ? 1.0f : top ? 0.0f : 0.3f});
    const glm::vec2 uv = plane.map(m.position(v));
    m.texcoords.insert(m.texcoords.end(), {uv.x, uv.y});
  }
  return m;
}

const std::vector<MeshImage> kImages = {{"top.png", "image/png", {0x89, 'P', 'N', 'G', 1, 2, 3}},
                                        {"bottom.jpg", "image/jpeg", {0xFF, 0xD8, 0xFF, 9, 8}}};

uint32_t read32(const std::vector<uint8_t>& b, size_t at) {
  uint32_t x = 0;
  std::memcpy(&x, b.data() + at, 4);
  return x;
}

// A GLB split into its JSON and BIN chunks, its layout checked on the way (glTF 2.0 section 4).
struct Glb {
  json gltf;
  std::vector<uint8_t> bin;
  explicit Glb(const std::vector<uint8_t>& bytes) {
    EXPECT_EQ(read32(bytes, 0), 0x46546C67u) << "magic glTF";
    EXPECT_EQ(read32(bytes, 4), 2u);
    EXPECT_EQ(read32(bytes, 8), bytes.size()) << "the header's length is the file's";
    const uint32_t jsonLength = read32(bytes, 12);
    EXPECT_EQ(read32(bytes, 16), 0x4E4F534Au) << "JSON chunk first";
    EXPECT_EQ(jsonLength % 4, 0u);
    gltf = json::parse(bytes.begin() + 20, bytes.begin() + 20 + jsonLength);
    const size_t binAt = 20 + jsonLength;
    const uint32_t binLength = read32(bytes, binAt);
    EXPECT_EQ(read32(bytes, binAt + 4), 0x004E4942u) << "then BIN";
    EXPECT_EQ(binAt + 8 + binLength, bytes.size());
    EXPECT_EQ(gltf["buffers"][0]["byteLength"], binLength);
    bin.assign(bytes.begin() + long(binAt) + 8, bytes.end());
  }
  std::vector<uint8_t> view(size_t index) const {
    const json& v = gltf["bufferViews"][index];
    const size_t offset = v["byteOffset"], length = v["byteLength"];
    EXPECT_EQ(offset % 4, 0u) << "views are 4-byte aligned";
    return {bin.begin() + long(offset), bin.begin() + long(offset + length)};
  }
  std::vector<float> floats(size_t accessor) const {
    const std::vector<uint8_t> bytes = view(gltf["accessors"][accessor]["bufferView"]);
    std::vector<float> out(bytes.size() / 4);
    std::memcpy(out.data(), bytes.data(), out.size() * 4);
    return out;
  }
};

TEST(MeshIoTextured, GlbHasOnePrimitivePerImageWithItsGeneratorsCoordinates) {
  const Mesh mesh = texturedOctahedron();
  const auto bytes = encodeTexturedGlb(mesh, kImages);
  ASSERT_TRUE(bytes.has_value()) << failure(bytes);
  const Glb glb(*bytes);
  const json& primitives = glb.gltf["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 2u) << "every face leans to one layer: no untextured part";
  size_t triangles = 0;
  std::vector<size_t> imagesSeen;
  for (const json& primitive : primitives) {
    EXPECT_EQ(primitive["mode"], 4);
    const json& material = glb.gltf["materials"][primitive["material"].get<size_t>()];
    ASSERT_TRUE(material["pbrMetallicRoughness"].contains("baseColorTexture"));
    const size_t texture = material["pbrMetallicRoughness"]["baseColorTexture"]["index"];
    const size_t image = glb.gltf["textures"][texture]["source"];
    imagesSeen.push_back(image);
    EXPECT_EQ(material["name"], kImages[image].name);
    const std::vector<float> positions = glb.floats(primitive["attributes"]["POSITION"]);
    const std::vector<float> st = glb.floats(primitive["attributes"]["TEXCOORD_0"]);
    const std::vector<float> colors = glb.floats(primitive["attributes"]["COLOR_0"]);
    ASSERT_EQ(st.size() / 2, positions.size() / 3);
    for (size_t v = 0; v < st.size() / 2; ++v) {
      const float x = positions[3 * v], y = positions[3 * v + 1], z = positions[3 * v + 2];
      EXPECT_NEAR(st[2 * v], 0.5f + x / 4, 1e-6f);
      EXPECT_NEAR(st[2 * v + 1], 1.0f - (0.5f + y / 4), 1e-6f) << "glTF's t runs down the image";
      EXPECT_LE(colors[3 * v + 2], 1.0f) << "colours clamped";
      // The upper faces are image 0's, the lower image 1's.
      EXPECT_GE(image == 0 ? z : -z, 0.0f) << "vertex " << v << " of image " << image;
    }
    const json& indices = glb.gltf["accessors"][primitive["indices"].get<size_t>()];
    EXPECT_EQ(indices["componentType"], 5125);
    triangles += indices["count"].get<size_t>() / 3;
  }
  EXPECT_EQ(triangles, mesh.triangleCount());
  std::sort(imagesSeen.begin(), imagesSeen.end());
  EXPECT_EQ(imagesSeen, (std::vector<size_t>{0, 1}));
}

TEST(MeshIoTextured, GlbEmbedsEachImageOnceWithARepeatingTrilinearSampler) {
  const auto bytes = encodeTexturedGlb(texturedOctahedron(), kImages);
  ASSERT_TRUE(bytes.has_value());
  const Glb glb(*bytes);
  ASSERT_EQ(glb.gltf["images"].size(), 2u);
  ASSERT_EQ(glb.gltf["textures"].size(), 2u);
  for (const json& image : glb.gltf["images"]) {
    const auto k = size_t(std::find_if(kImages.begin(), kImages.end(),
                                       [&](const MeshImage& m) { return m.name == image["name"].get<std::string>(); }) -
                          kImages.begin());
    ASSERT_LT(k, kImages.size());
    EXPECT_EQ(image["mimeType"], kImages[k].mimeType);
    EXPECT_EQ(glb.view(image["bufferView"]), kImages[k].bytes) << "the image's own bytes";
  }
  ASSERT_EQ(glb.gltf["samplers"].size(), 1u);
  const json& sampler = glb.gltf["samplers"][0];
  EXPECT_EQ(sampler["wrapS"], 10497);
  EXPECT_EQ(sampler["wrapT"], 10497);
  EXPECT_EQ(sampler["magFilter"], 9729);
  EXPECT_EQ(sampler["minFilter"], 9987);
}

TEST(MeshIoTextured, TrianglesWithoutAnImageGoToAPlainMaterial) {
  Mesh mesh = texturedOctahedron();
  mesh.layerImages[1] = -1;  // a generator without an image: the lower faces are untextured
  const auto bytes = encodeTexturedGlb(mesh, kImages);
  ASSERT_TRUE(bytes.has_value());
  const Glb glb(*bytes);
  const json& primitives = glb.gltf["meshes"][0]["primitives"];
  ASSERT_EQ(primitives.size(), 2u);
  const json& plain = primitives[0];  // the untextured part comes first
  const json& material = glb.gltf["materials"][plain["material"].get<size_t>()];
  EXPECT_EQ(material["name"], "untextured");
  EXPECT_FALSE(material["pbrMetallicRoughness"].contains("baseColorTexture"));
  EXPECT_FALSE(plain["attributes"].contains("TEXCOORD_0"));
  EXPECT_EQ(glb.gltf["images"].size(), 1u) << "only images in use are embedded";
}

TEST(MeshIoTextured, UntexturedMeshesAndNoImagesFallBackToThePlainGlb) {
  Mesh plain = texturedOctahedron();
  plain.clearTextures();
  EXPECT_EQ(encodeTexturedGlb(plain, kImages).value(), encodeGlb(plain).value());
  const Mesh textured = texturedOctahedron();
  EXPECT_EQ(encodeTexturedGlb(textured, {}).value(), encodeGlb(textured).value());
}

TEST(MeshIoTextured, ALayerNamingAMissingImageIsRefused) {
  Mesh mesh = texturedOctahedron();
  mesh.layerImages[1] = 2;
  EXPECT_EQ(failure(encodeTexturedGlb(mesh, kImages)), "the mesh names texture image 2 of 2");
  EXPECT_EQ(failure(encodeTexturedObj(mesh, kImages, "m.mtl")), "the mesh names texture image 2 of 2");
  // The mesh's own checks come too: an index past the vertices.
  Mesh broken = texturedOctahedron();
  broken.indices[0] = 99;
  EXPECT_EQ(failure(encodeTexturedGlb(broken, kImages)).rfind("invalid mesh: index 99", 0), 0u);
}

TEST(MeshIoTextured, WriteTexturedGlbWritesTheEncodedBytesOrSaysWhichFile) {
  ScratchDir dir("mesh_io_textured");
  const Mesh mesh = texturedOctahedron();
  const std::string path = (dir / "m.glb").string();
  ASSERT_EQ(failure(writeTexturedGlb(mesh, kImages, path)), "");
  const std::string written = fileBytes(path);
  const auto encoded = encodeTexturedGlb(mesh, kImages);
  ASSERT_TRUE(encoded.has_value());
  EXPECT_EQ(written, std::string(encoded->begin(), encoded->end()));
  Mesh bad = mesh;
  bad.layerImages[0] = 5;
  EXPECT_EQ(failure(writeTexturedGlb(bad, kImages, (dir / "bad.glb").string())),
            (dir / "bad.glb").string() + ": the mesh names texture image 5 of 2");
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.glb"));
}

TEST(MeshIoTextured, ObjHasAGroupAndMaterialPerPartAndAVtPerV) {
  const auto out = encodeTexturedObj(texturedOctahedron(), kImages, "oct.mtl");
  ASSERT_TRUE(out.has_value());
  const std::string obj(out->obj.begin(), out->obj.end()), mtl(out->mtl.begin(), out->mtl.end());
  EXPECT_NE(obj.find("\nmtllib oct.mtl\n"), std::string::npos);
  EXPECT_NE(obj.find("\ng texture0\nusemtl texture0\n"), std::string::npos);
  EXPECT_NE(obj.find("\ng texture1\nusemtl texture1\n"), std::string::npos);
  EXPECT_NE(mtl.find("newmtl texture0\nKd 1 1 1\nmap_Kd top.png\n"), std::string::npos) << mtl;
  EXPECT_NE(mtl.find("newmtl texture1\nKd 1 1 1\nmap_Kd bottom.jpg\n"), std::string::npos) << mtl;
  size_t vs = 0, vts = 0, vns = 0, fs = 0, maxIndex = 0;
  std::istringstream lines(obj);
  for (std::string line; std::getline(lines, line);) {
    vs += line.starts_with("v ");
    vts += line.starts_with("vt ");
    vns += line.starts_with("vn ");
    if (!line.starts_with("f ")) continue;
    ++fs;
    std::istringstream corners(line.substr(2));
    for (std::string c; corners >> c;) {
      const size_t a = std::stoul(c);
      EXPECT_EQ(c, std::to_string(a) + "/" + std::to_string(a) + "/" + std::to_string(a)) << "one index for all";
      maxIndex = std::max(maxIndex, a);
    }
  }
  EXPECT_EQ(fs, 8u);
  EXPECT_EQ(vs, vts);
  EXPECT_EQ(vs, vns);
  EXPECT_EQ(maxIndex, vs) << "indices run over all parts' vertices, from 1";
  // An untextured mesh has one plain part, without map_Kd.
  Mesh plain = texturedOctahedron();
  plain.clearTextures();
  const auto p = encodeTexturedObj(plain, kImages, "p.mtl");
  ASSERT_TRUE(p.has_value());
  const std::string plainMtl(p->mtl.begin(), p->mtl.end());
  EXPECT_NE(plainMtl.find("newmtl untextured\n"), std::string::npos);
  EXPECT_EQ(plainMtl.find("map_Kd"), std::string::npos);
}

}  // namespace
}  // namespace imps
