// SPDX-License-Identifier: MIT
// Tests for several named meshes in one file: glTF nodes (one per object, named, each its own mesh), OBJ objects
// with indices running on, PLY merged.
#include "imps/mesh_objects.h"

#include <gtest/gtest.h>

#include <cstring>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "imps/vrml_props.h"

namespace imps {
namespace {

// Why a writer or encoder failed (its one error, which names the file for a writer), "" when it succeeded.
template <class T>
std::string failure(const std::expected<T, Diagnostics>& result) {
  return result ? std::string() : result.error().all().front().message;
}

nlohmann::json glbJson(const std::vector<uint8_t>& glb) {
  uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  return nlohmann::json::parse(std::string(reinterpret_cast<const char*>(glb.data()) + 20, length));
}

TEST(MeshObjects, EachObjectIsItsOwnGltfNode) {
  const Mesh box = boxMesh({1, 1, 1}), ball = sphereMesh(0.5f);
  const Mesh empty;
  const std::vector<NamedMesh> objects{{"hero", &ball}, {"hat", &box}, {"nothing", &empty}};
  auto glb = encodeGlbObjects(objects);
  ASSERT_TRUE(glb.has_value()) << failure(glb);
  ASSERT_EQ(glb->size() % 4, 0u);
  const auto json = glbJson(*glb);
  ASSERT_EQ(json["scenes"][0]["nodes"].size(), 3u);
  ASSERT_EQ(json["nodes"].size(), 3u);
  ASSERT_EQ(json["meshes"].size(), 2u);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(json["nodes"][k]["name"], objects[k].name);
  EXPECT_FALSE(json["nodes"][2].contains("mesh")) << "an empty object is a node without a mesh";
  // Each node's mesh holds exactly its object's vertices and indices.
  for (size_t k = 0; k < 2; ++k) {
    const auto& primitive = json["meshes"][size_t(json["nodes"][k]["mesh"])]["primitives"][0];
    EXPECT_EQ(json["accessors"][size_t(primitive["attributes"]["POSITION"])]["count"], objects[k].mesh->vertexCount());
    EXPECT_EQ(json["accessors"][size_t(primitive["indices"])]["count"], objects[k].mesh->indices.size());
  }
  // The buffer holds every byte the views name.
  size_t end = 0;
  for (const auto& v : json["bufferViews"]) end = std::max(end, size_t(v["byteOffset"]) + size_t(v["byteLength"]));
  EXPECT_LE(end, size_t(json["buffers"][0]["byteLength"]));
}

TEST(MeshObjects, ObjObjectsRunTheirIndicesOn) {
  const Mesh box = boxMesh({1, 1, 1}), cone = coneMesh(1, 1);
  const std::vector<NamedMesh> objects{{"a box", &box}, {"cone", &cone}};
  auto obj = encodeObjObjects(objects);
  ASSERT_TRUE(obj.has_value());
  std::istringstream in(std::string(obj->begin(), obj->end()));
  std::string line;
  std::vector<std::string> names;
  size_t vertices = 0, maxIndex = 0, minSecond = SIZE_MAX;
  while (std::getline(in, line)) {
    if (line.starts_with("o ")) names.push_back(line.substr(2));
    if (line.starts_with("v ")) ++vertices;
    if (line.starts_with("f ")) {
      std::istringstream f(line.substr(2));
      std::string corner;
      while (f >> corner) {
        const size_t i = std::stoul(corner.substr(0, corner.find('/')));
        maxIndex = std::max(maxIndex, i);
        if (names.size() == 2) minSecond = std::min(minSecond, i);
      }
    }
  }
  EXPECT_EQ(names, (std::vector<std::string>{"a_box", "cone"}));
  EXPECT_EQ(vertices, box.vertexCount() + cone.vertexCount());
  EXPECT_EQ(maxIndex, vertices);
  EXPECT_EQ(minSecond, box.vertexCount() + 1) << "the second object's faces start after the first's vertices";
}

TEST(MeshObjects, BadMeshesAreRefusedByName) {
  Mesh bad = boxMesh({1, 1, 1});
  bad.indices.push_back(99999);
  bad.indices.push_back(0);
  bad.indices.push_back(1);
  const std::vector<NamedMesh> objects{{"broken", &bad}};
  const std::string error = failure(encodeGlbObjects(objects));
  EXPECT_NE(error, "");
  EXPECT_NE(error.find("broken"), std::string::npos) << error;
}

}  // namespace
}  // namespace imps
