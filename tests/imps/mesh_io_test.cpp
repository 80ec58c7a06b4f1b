// SPDX-License-Identifier: MIT
// Tests for imps/mesh_io.h: round trips through independent readers, determinism, atomic saves, GLB validity.
#include "imps/mesh_io.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <glm/geometric.hpp>

#include "mesh_readers.h"

namespace imps {
namespace {

// Why a writer or encoder failed (its one error, which names the file for a writer), "" when it succeeded.
template <class T>
std::string failure(const std::expected<T, Diagnostics>& result) {
  return result ? std::string() : result.error().all().front().message;
}

namespace fs = std::filesystem;

// A curved open sheet (so the normals vary) with awkward float values: tiny, huge, negative, non-dyadic.
Mesh testMesh(uint32_t n = 9) {
  Mesh mesh;
  for (uint32_t y = 0; y <= n; ++y) {
    for (uint32_t x = 0; x <= n; ++x) {
      const float u = static_cast<float>(x) / static_cast<float>(n), v = static_cast<float>(y) / static_cast<float>(n);
      const float z = 0.1f * std::sin(3.0f * u) * std::cos(2.0f * v) + 1e-7f * static_cast<float>(x);
      mesh.positions.insert(mesh.positions.end(), {u * 3.3f - 1.1f, v * -2.7f + 0.3f, z});
      const glm::vec3 normal = glm::normalize(glm::vec3(-0.3f * std::cos(3.0f * u), 0.2f * std::sin(2.0f * v), 1.0f));
      mesh.normals.insert(mesh.normals.end(), {normal.x, normal.y, normal.z});
      mesh.colors.insert(mesh.colors.end(), {u, v, 0.5f * (u + v) * 0.77f});
    }
  }
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
    }
  }
  mesh.positions[0] = -3.5e6f;  // large and exactly representable
  mesh.positions[4] = 1.0e-30f; // tiny
  return mesh;
}

std::vector<uint8_t> fileBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeText(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

class MeshIoTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_mesh_io_" + std::to_string(::getpid()) + "_" +
                                        testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // Names in the test directory, to prove no temporary file was left behind.
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_;
};

void expectSameGeometry(const Mesh& expected, const Mesh& actual, float colorTolerance) {
  EXPECT_EQ(actual.positions, expected.positions);  // bit-exact: binary copies or shortest round-trip text
  EXPECT_EQ(actual.normals, expected.normals);
  EXPECT_EQ(actual.indices, expected.indices);
  ASSERT_EQ(actual.colors.size(), expected.colors.size());
  for (size_t i = 0; i < expected.colors.size(); ++i) {
    ASSERT_NEAR(actual.colors[i], expected.colors[i], colorTolerance) << "color component " << i;
  }
}

TEST_F(MeshIoTest, ObjRoundTripsExactly) {
  const Mesh mesh = testMesh();
  std::string error;
  ASSERT_EQ(failure(writeMesh(mesh, path("m.obj"))), "");
  Mesh back;
  ASSERT_TRUE(test::readObj(path("m.obj"), &back, &error)) << error;
  expectSameGeometry(mesh, back, 0.0f);
}

TEST_F(MeshIoTest, PlyRoundTripsWithEightBitColors) {
  const Mesh mesh = testMesh();
  std::string error;
  ASSERT_EQ(failure(writeMesh(mesh, path("m.ply"))), "");
  Mesh back;
  ASSERT_TRUE(test::readPly(path("m.ply"), &back, &error)) << error;
  expectSameGeometry(mesh, back, 0.5f / 255.0f + 1e-6f);
  // The header is the one documented, byte for byte.
  const std::vector<uint8_t> bytes = fileBytes(path("m.ply"));
  const std::string start(bytes.begin(), bytes.begin() + 400);
  EXPECT_EQ(start.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(start.find("element vertex 100\nproperty float x\nproperty float y\nproperty float z\n"
                       "property float nx\nproperty float ny\nproperty float nz\n"
                       "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                       "element face 162\nproperty list uchar uint vertex_indices\nend_header\n"),
            std::string::npos);
}

TEST_F(MeshIoTest, GlbRoundTripsThroughTinygltf) {
  const Mesh mesh = testMesh();
  std::string error, warning;
  ASSERT_EQ(failure(writeMesh(mesh, path("m.glb"))), "");
  Mesh back;
  ASSERT_TRUE(test::readGlb(path("m.glb"), &back, &error, &warning)) << error;
  EXPECT_EQ(warning, "");
  expectSameGeometry(mesh, back, 0.0f);
}

TEST_F(MeshIoTest, MissingAttributesAreLeftOut) {
  Mesh mesh = testMesh(3);
  mesh.normals.clear();
  mesh.colors.clear();
  std::string error;
  for (const char* name : {"bare.obj", "bare.ply", "bare.glb"}) {
    ASSERT_EQ(failure(writeMesh(mesh, path(name))), "") << name;
    Mesh back;
    const std::string file = path(name);
    const bool ok = file.ends_with(".obj")   ? test::readObj(file, &back, &error)
                    : file.ends_with(".ply") ? test::readPly(file, &back, &error)
                                             : test::readGlb(file, &back, &error);
    ASSERT_TRUE(ok) << name << ": " << error;
    EXPECT_EQ(back, mesh) << name;
  }
  const std::vector<uint8_t> obj = fileBytes(path("bare.obj"));
  EXPECT_EQ(std::string(obj.begin(), obj.end()).find("//"), std::string::npos);
}

TEST_F(MeshIoTest, ColorsAreClampedAndQuantizedToNearest) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  mesh.colors = {1.5f, -0.25f, 0.5f, 1.0f / 255.0f, 0.499f / 255.0f, 254.6f / 255.0f, 0, 0, 0};
  mesh.indices = {0, 1, 2};
  const auto ply = encodePly(mesh);
  ASSERT_TRUE(ply);
  // The first vertex record (12 position bytes, then 3 colour bytes) follows the header directly.
  const std::string text(ply->begin(), ply->end());
  const size_t body = text.find("end_header\n") + std::strlen("end_header\n");
  EXPECT_EQ((*ply)[body + 12], 255);
  EXPECT_EQ((*ply)[body + 13], 0);
  EXPECT_EQ((*ply)[body + 14], 128);
  EXPECT_EQ((*ply)[body + 15 + 12], 1);
  EXPECT_EQ((*ply)[body + 15 + 13], 0);
  EXPECT_EQ((*ply)[body + 15 + 14], 255);

  std::string error;
  ASSERT_EQ(failure(writeGlb(mesh, path("c.glb"))), "");
  Mesh back;
  ASSERT_TRUE(test::readGlb(path("c.glb"), &back, &error)) << error;
  EXPECT_EQ(back.colors[0], 1.0f);
  EXPECT_EQ(back.colors[1], 0.0f);
  EXPECT_EQ(back.colors[2], 0.5f);
}

TEST_F(MeshIoTest, OutputIsByteExactDeterministic) {
  const Mesh mesh = testMesh();
  for (const char* extension : {".obj", ".ply", ".glb"}) {
    const std::string a = path(std::string("a") + extension), b = path(std::string("b") + extension);
    ASSERT_EQ(failure(writeMesh(mesh, a)), "");
    ASSERT_EQ(failure(writeMesh(mesh, b)), "");
    const std::vector<uint8_t> bytesA = fileBytes(a);
    EXPECT_FALSE(bytesA.empty());
    EXPECT_EQ(bytesA, fileBytes(b)) << extension;
  }
  EXPECT_EQ(*encodePly(mesh), fileBytes(path("a.ply")));
  EXPECT_EQ(*encodeGlb(mesh), fileBytes(path("a.glb")));
  EXPECT_EQ(*encodeObj(mesh), fileBytes(path("a.obj")));
  // A different mesh gives different bytes (the comparison above can fail).
  Mesh other = mesh;
  other.positions[7] += 1.0f;
  EXPECT_NE(*encodeGlb(other), fileBytes(path("a.glb")));
}

TEST_F(MeshIoTest, ObjTextIsTheDocumentedForm) {
  Mesh mesh;
  mesh.positions = {0, 0, 0, 1, 0, 0, 0, 0.1f, 0};
  mesh.normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  mesh.colors = {1, 0, 0, 0, 1, 0, 0, 0, 0.25f};
  mesh.indices = {0, 1, 2};
  const auto obj = encodeObj(mesh);
  ASSERT_TRUE(obj);
  const std::string text(obj->begin(), obj->end());
  EXPECT_EQ(text.substr(text.find('\n') + 1),
            "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 0.1 0 0 0 0.25\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n");
}

TEST_F(MeshIoTest, FormatIsChosenByExtension) {
  EXPECT_EQ(meshFormatForPath("a/b.OBJ"), MeshFormat::Obj);
  EXPECT_EQ(meshFormatForPath("b.Ply"), MeshFormat::Ply);
  EXPECT_EQ(meshFormatForPath("/x/y.glb"), MeshFormat::Glb);
  EXPECT_EQ(meshFormatForPath("dir.ply/file"), std::nullopt);
  EXPECT_EQ(meshFormatForPath("mesh.gltf"), std::nullopt);
  EXPECT_EQ(meshFormatForPath("ply"), std::nullopt);
}

TEST_F(MeshIoTest, UnknownExtensionIsAnErrorAndLeavesTargetUntouched) {
  writeText(path("mesh.stl"), "keep me");
  std::string error = failure(writeMesh(testMesh(), path("mesh.stl")));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find(".obj"), std::string::npos) << error;
  EXPECT_NE(error.find(".ply"), std::string::npos) << error;
  EXPECT_NE(error.find(".glb"), std::string::npos) << error;
  EXPECT_NE(error.find("mesh.stl"), std::string::npos) << error;
  const std::vector<uint8_t> bytes = fileBytes(path("mesh.stl"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "keep me");
  EXPECT_EQ(entries(), std::vector<std::string>{"mesh.stl"});
}

TEST_F(MeshIoTest, MissingDirectoryIsAnError) {
  std::string error = failure(writeMesh(testMesh(), path("no/such/dir/m.ply")));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("no/such/dir/m.ply"), std::string::npos) << error;
  EXPECT_TRUE(entries().empty());
}

TEST_F(MeshIoTest, FailedRenameLeavesTargetAndNoTemporaryFile) {
  // The target is a non-empty directory: the temporary file is written, then rename() fails.
  fs::create_directories(dir_ / "m.glb");
  writeText(dir_ / "m.glb" / "inside", "keep me");
  std::string error = failure(writeMesh(testMesh(), path("m.glb")));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("renaming the temporary file over it"), std::string::npos) << error;
  EXPECT_TRUE(fs::is_directory(dir_ / "m.glb"));
  const std::vector<uint8_t> bytes = fileBytes(dir_ / "m.glb" / "inside");
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "keep me");
  EXPECT_EQ(entries(), std::vector<std::string>{"m.glb"});
}

TEST_F(MeshIoTest, InvalidMeshIsAnErrorAndLeavesTargetUntouched) {
  writeText(path("m.ply"), "old");
  Mesh mesh = testMesh(2);
  mesh.indices[4] = 1000;
  std::string error = failure(writeMesh(mesh, path("m.ply")));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("index 1000"), std::string::npos) << error;
  mesh = testMesh(2);
  mesh.normals.pop_back();
  error = failure(writeMesh(mesh, path("m.ply")));
  EXPECT_NE(error, "");
  mesh = testMesh(2);
  mesh.positions[5] = std::nanf("");
  error = failure(writeMesh(mesh, path("m.ply")));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("finite"), std::string::npos) << error;
  const std::vector<uint8_t> bytes = fileBytes(path("m.ply"));
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "old");
  EXPECT_EQ(entries(), std::vector<std::string>{"m.ply"});
}

TEST_F(MeshIoTest, OverwritesAnExistingFile) {
  writeText(path("m.obj"), std::string(100000, 'x'));  // longer than the new file: no stale tail may remain
  ASSERT_EQ(failure(writeMesh(testMesh(2), path("m.obj"))), "");
  EXPECT_EQ(fileBytes(path("m.obj")), *encodeObj(testMesh(2)));
  EXPECT_EQ(entries(), std::vector<std::string>{"m.obj"});
}

uint32_t readU32(const std::vector<uint8_t>& bytes, size_t at) {
  uint32_t value;
  std::memcpy(&value, bytes.data() + at, 4);
  return value;
}

TEST_F(MeshIoTest, GlbIsValidGltf) {
  const Mesh mesh = testMesh();
  std::string error, warning;
  ASSERT_EQ(failure(writeGlb(mesh, path("m.glb"))), "");

  // Container: header, space-padded JSON chunk, zero-padded BIN chunk, everything 4-byte aligned.
  const std::vector<uint8_t> bytes = fileBytes(path("m.glb"));
  ASSERT_GE(bytes.size(), 28u);
  EXPECT_EQ(readU32(bytes, 0), 0x46546C67u);
  EXPECT_EQ(readU32(bytes, 4), 2u);
  EXPECT_EQ(readU32(bytes, 8), bytes.size());
  const uint32_t jsonLength = readU32(bytes, 12);
  EXPECT_EQ(jsonLength % 4, 0u);
  EXPECT_EQ(readU32(bytes, 16), 0x4E4F534Au);
  EXPECT_EQ(bytes[20], '{');
  const size_t jsonEnd = 20 + jsonLength;
  size_t last = jsonEnd - 1;
  while (bytes[last] == ' ') --last;
  EXPECT_EQ(bytes[last], '}');
  const uint32_t binLength = readU32(bytes, jsonEnd);
  EXPECT_EQ(binLength % 4, 0u);
  EXPECT_EQ(readU32(bytes, jsonEnd + 4), 0x004E4942u);
  EXPECT_EQ(jsonEnd + 8 + binLength, bytes.size());

  // The document, as an independent parser sees it.
  tinygltf::Model model;
  ASSERT_TRUE(test::loadGlbModel(path("m.glb"), &model, &error, &warning)) << error;
  EXPECT_EQ(error, "");
  EXPECT_EQ(warning, "");
  EXPECT_EQ(model.asset.version, "2.0");
  EXPECT_EQ(model.asset.generator, "IMPS Puppeteer");
  ASSERT_EQ(model.scenes.size(), 1u);
  EXPECT_EQ(model.defaultScene, 0);
  ASSERT_EQ(model.nodes.size(), 1u);
  EXPECT_EQ(model.scenes[0].nodes, std::vector<int>{0});
  EXPECT_EQ(model.nodes[0].mesh, 0);
  ASSERT_EQ(model.meshes.size(), 1u);
  ASSERT_EQ(model.meshes[0].primitives.size(), 1u);
  ASSERT_EQ(model.buffers.size(), 1u);
  EXPECT_EQ(model.buffers[0].data.size(), binLength);
  const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
  EXPECT_EQ(primitive.mode, TINYGLTF_MODE_TRIANGLES);
  ASSERT_EQ(primitive.attributes.size(), 3u);

  const tinygltf::Accessor& position = model.accessors.at(static_cast<size_t>(primitive.attributes.at("POSITION")));
  EXPECT_EQ(position.count, mesh.vertexCount());
  EXPECT_EQ(position.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  EXPECT_EQ(position.type, TINYGLTF_TYPE_VEC3);
  const MeshBounds box = bounds(mesh);
  ASSERT_EQ(position.minValues.size(), 3u);
  ASSERT_EQ(position.maxValues.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(static_cast<float>(position.minValues[static_cast<size_t>(k)]), box.min[k]);
    EXPECT_EQ(static_cast<float>(position.maxValues[static_cast<size_t>(k)]), box.max[k]);
  }
  EXPECT_EQ(box.min.x, -3.5e6f);  // the test mesh's extreme really is the min
  for (const char* name : {"NORMAL", "COLOR_0"}) {
    const tinygltf::Accessor& a = model.accessors.at(static_cast<size_t>(primitive.attributes.at(name)));
    EXPECT_EQ(a.count, mesh.vertexCount()) << name;
    EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT) << name;
    EXPECT_EQ(a.type, TINYGLTF_TYPE_VEC3) << name;
  }
  const tinygltf::Accessor& indices = model.accessors.at(static_cast<size_t>(primitive.indices));
  EXPECT_EQ(indices.count, mesh.indices.size());
  EXPECT_EQ(indices.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  EXPECT_EQ(indices.type, TINYGLTF_TYPE_SCALAR);
  EXPECT_EQ(model.bufferViews.at(static_cast<size_t>(indices.bufferView)).target, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  EXPECT_EQ(model.bufferViews.at(static_cast<size_t>(position.bufferView)).target, TINYGLTF_TARGET_ARRAY_BUFFER);
}

TEST_F(MeshIoTest, GlbOfMeshWithoutTrianglesIsAnEmptyScene) {
  std::string error, warning;
  ASSERT_EQ(failure(writeGlb(Mesh{}, path("empty.glb"))), "");
  tinygltf::Model model;
  ASSERT_TRUE(test::loadGlbModel(path("empty.glb"), &model, &error, &warning)) << error;
  EXPECT_EQ(warning, "");
  EXPECT_EQ(model.nodes.size(), 1u);
  EXPECT_TRUE(model.meshes.empty());
  EXPECT_TRUE(model.buffers.empty());
  // The other formats write an empty mesh that reads back empty.
  for (const char* name : {"empty.obj", "empty.ply"}) {
    ASSERT_EQ(failure(writeMesh(Mesh{}, path(name))), "");
  }
  Mesh back = testMesh(1);
  ASSERT_TRUE(test::readPly(path("empty.ply"), &back, &error)) << error;
  EXPECT_EQ(back, Mesh{});
  back = testMesh(1);
  ASSERT_TRUE(test::readObj(path("empty.obj"), &back, &error)) << error;
  EXPECT_EQ(back, Mesh{});
}

}  // namespace
}  // namespace imps
