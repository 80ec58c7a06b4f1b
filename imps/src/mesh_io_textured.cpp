// SPDX-License-Identifier: MIT
// Textured export: glTF 2.0 binary with embedded images and OBJ + MTL, from splitByTexture's parts.
// Based on: Khronos Group, "glTF 2.0 Specification" (2021), sections 3.8-3.9 (materials, textures, images) and 4
// (GLB); Wavefront, "Object Files (.obj)" and "Material Library Files (.mtl)".
#include <algorithm>
#include <charconv>
#include <cstring>
#include <nlohmann/json.hpp>

#include "imps/atomic_file.h"
#include "imps/mesh_io.h"
#include "imps/texturing.h"

namespace imps {
namespace {

std::unexpected<Diagnostics> invalid(std::string problem) {
  return std::unexpected(singleError({}, std::move(problem)));
}

// "" when every image the mesh's layers name is in `images`, else which one is not.
std::string missingImage(const Mesh& mesh, const std::vector<MeshImage>& images) {
  for (const int32_t image : mesh.layerImages)
    if (image >= 0 && size_t(image) >= images.size())
      return "the mesh names texture image " + std::to_string(image) + " of " + std::to_string(images.size());
  return {};
}

// The BIN chunk under construction: 4-byte aligned views.
struct Bin {
  std::vector<uint8_t> bytes;
  nlohmann::json views = nlohmann::json::array();
  size_t view(const void* data, size_t size, int target) {
    const size_t offset = bytes.size();
    bytes.resize(offset + ((size + 3) & ~size_t{3}), 0);
    if (size > 0) std::memcpy(bytes.data() + offset, data, size);
    nlohmann::json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
    if (target) v["target"] = target;
    views.push_back(std::move(v));
    return views.size() - 1;
  }
};

}  // namespace

std::expected<std::vector<uint8_t>, Diagnostics> encodeTexturedGlb(const Mesh& mesh,
                                                                   const std::vector<MeshImage>& images) {
  if (!mesh.textured() || images.empty() || mesh.triangleCount() == 0) return encodeGlb(mesh);
  if (std::string missing = missingImage(mesh, images); !missing.empty()) return invalid(std::move(missing));
  if (auto plain = encodeGlb(mesh); !plain) return std::unexpected(plain.error());  // the same checks of the mesh
  using nlohmann::json;
  constexpr int kFloat = 5126, kUnsignedInt = 5125, kTriangles = 4, kArrayBuffer = 34962, kElements = 34963;
  constexpr int kRepeat = 10497, kLinear = 9729, kLinearMipmapLinear = 9987;
  Bin bin;
  json accessors = json::array(), primitives = json::array(), materials = json::array(), textures = json::array(),
       gltfImages = json::array();
  std::vector<int> textureOfImage(images.size(), -1);
  auto accessor = [&](size_t view, size_t count, const char* type) {
    accessors.push_back({{"bufferView", view}, {"componentType", kFloat}, {"count", count}, {"type", type}});
    return accessors.size() - 1;
  };
  for (const TexturedPart& part : splitByTexture(mesh)) {
    const Mesh& m = part.mesh;
    json attributes;
    const size_t position = accessor(bin.view(m.positions.data(), m.positions.size() * 4, kArrayBuffer),
                                     m.vertexCount(), "VEC3");
    const MeshBounds box = bounds(m);
    accessors[position]["min"] = {double{box.min.x}, double{box.min.y}, double{box.min.z}};
    accessors[position]["max"] = {double{box.max.x}, double{box.max.y}, double{box.max.z}};
    attributes["POSITION"] = position;
    if (!m.normals.empty())
      attributes["NORMAL"] =
          accessor(bin.view(m.normals.data(), m.normals.size() * 4, kArrayBuffer), m.vertexCount(), "VEC3");
    if (!m.colors.empty()) {
      std::vector<float> clamped(m.colors);
      for (float& c : clamped) c = std::clamp(c, 0.0f, 1.0f);
      attributes["COLOR_0"] =
          accessor(bin.view(clamped.data(), clamped.size() * 4, kArrayBuffer), m.vertexCount(), "VEC3");
    }
    json material = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}},
                     {"doubleSided", true}};
    if (part.image >= 0) {
      std::vector<float> st(part.uvs);
      for (size_t k = 1; k < st.size(); k += 2) st[k] = 1.0f - st[k];  // glTF's t runs down the image
      attributes["TEXCOORD_0"] = accessor(bin.view(st.data(), st.size() * 4, kArrayBuffer), m.vertexCount(), "VEC2");
      int& texture = textureOfImage[size_t(part.image)];
      if (texture < 0) {
        const MeshImage& image = images[size_t(part.image)];
        gltfImages.push_back({{"bufferView", bin.view(image.bytes.data(), image.bytes.size(), 0)},
                              {"mimeType", image.mimeType}, {"name", image.name}});
        textures.push_back({{"sampler", 0}, {"source", gltfImages.size() - 1}});
        texture = int(textures.size() - 1);
      }
      material["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", texture}};
      material["name"] = images[size_t(part.image)].name;
    } else {
      material["name"] = "untextured";
    }
    materials.push_back(std::move(material));
    const size_t indices = bin.view(m.indices.data(), m.indices.size() * 4, kElements);
    accessors.push_back({{"bufferView", indices}, {"componentType", kUnsignedInt}, {"count", m.indices.size()},
                         {"type", "SCALAR"}});
    primitives.push_back({{"attributes", attributes}, {"indices", accessors.size() - 1}, {"mode", kTriangles},
                          {"material", materials.size() - 1}});
  }
  json gltf;
  gltf["asset"] = {{"version", "2.0"}, {"generator", "IMPS Puppeteer"}};
  gltf["scene"] = 0;
  gltf["scenes"] = json::array({json{{"nodes", json::array({0})}}});
  gltf["nodes"] = json::array({json{{"mesh", 0}}});
  gltf["meshes"] = json::array({json{{"primitives", std::move(primitives)}}});
  gltf["materials"] = std::move(materials);
  gltf["accessors"] = std::move(accessors);
  gltf["bufferViews"] = std::move(bin.views);
  gltf["buffers"] = json::array({json{{"byteLength", bin.bytes.size()}}});
  if (!textures.empty()) {
    gltf["textures"] = std::move(textures);
    gltf["images"] = std::move(gltfImages);
    gltf["samplers"] = json::array({json{{"magFilter", kLinear}, {"minFilter", kLinearMipmapLinear},
                                         {"wrapS", kRepeat}, {"wrapT", kRepeat}}});
  }
  std::string jsonText = gltf.dump();
  jsonText.resize((jsonText.size() + 3) & ~size_t{3}, ' ');
  const size_t total = 12 + 8 + jsonText.size() + 8 + bin.bytes.size();
  if (total > UINT32_MAX) {
    return invalid("mesh too large for GLB (more than 4 GiB)");
  }
  std::vector<uint8_t> bytes;
  bytes.reserve(total);
  auto put32 = [&](uint32_t x) {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(&x);
    bytes.insert(bytes.end(), p, p + 4);
  };
  put32(0x46546C67);  // "glTF"
  put32(2);
  put32(uint32_t(total));
  put32(uint32_t(jsonText.size()));
  put32(0x4E4F534A);  // "JSON"
  bytes.insert(bytes.end(), jsonText.begin(), jsonText.end());
  put32(uint32_t(bin.bytes.size()));
  put32(0x004E4942);  // "BIN\0"
  bytes.insert(bytes.end(), bin.bytes.begin(), bin.bytes.end());
  return bytes;
}

std::expected<void, Diagnostics> writeTexturedGlb(const Mesh& mesh, const std::vector<MeshImage>& images,
                                                  const std::string& path) {
  return saveEncodedMesh(encodeTexturedGlb(mesh, images), path);
}

std::expected<TexturedObj, Diagnostics> encodeTexturedObj(const Mesh& mesh, const std::vector<MeshImage>& images,
                                                          const std::string& mtlName) {
  if (auto plain = encodeObj(mesh); !plain) return std::unexpected(plain.error());
  if (std::string missing = missingImage(mesh, images); !missing.empty()) return invalid(std::move(missing));
  std::string obj = "# IMPS Puppeteer textured mesh\nmtllib " + mtlName + "\n", mtl = "# IMPS Puppeteer materials\n";
  auto number = [](float x) {
    char buffer[32];
    return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, x).ptr);
  };
  size_t base = 1;
  for (const TexturedPart& part : splitByTexture(mesh)) {
    const Mesh& m = part.mesh;
    const std::string name = part.image >= 0 ? "texture" + std::to_string(part.image) : "untextured";
    mtl += "newmtl " + name + "\nKd 1 1 1\n";
    if (part.image >= 0) mtl += "map_Kd " + images[size_t(part.image)].name + "\n";
    obj += "g " + name + "\nusemtl " + name + "\n";
    for (size_t v = 0; v < m.vertexCount(); ++v) {
      obj += "v " + number(m.positions[3 * v]) + " " + number(m.positions[3 * v + 1]) + " " +
             number(m.positions[3 * v + 2]);
      if (!m.colors.empty())
        for (int k = 0; k < 3; ++k) obj += " " + number(std::clamp(m.colors[3 * v + size_t(k)], 0.0f, 1.0f));
      obj += "\nvt " + number(part.uvs[2 * v]) + " " + number(part.uvs[2 * v + 1]) + "\n";
      if (!m.normals.empty())
        obj += "vn " + number(m.normals[3 * v]) + " " + number(m.normals[3 * v + 1]) + " " +
               number(m.normals[3 * v + 2]) + "\n";
    }
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      obj += "f";
      for (int k = 0; k < 3; ++k) {
        const std::string i = std::to_string(base + m.indices[3 * t + size_t(k)]);
        obj += " " + i + "/" + i + (m.normals.empty() ? "" : "/" + i);
      }
      obj += "\n";
    }
    base += m.vertexCount();
  }
  return TexturedObj{std::vector<uint8_t>(obj.begin(), obj.end()), std::vector<uint8_t>(mtl.begin(), mtl.end())};
}

}  // namespace imps
