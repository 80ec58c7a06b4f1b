// SPDX-License-Identifier: MIT
// Several named meshes in one glTF, OBJ or PLY file (see imps/mesh_objects.h).
#include "imps/mesh_objects.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "imps/atomic_file.h"
#include "imps/mesh_io.h"

namespace imps {

namespace {

std::unexpected<Diagnostics> invalid(std::string problem) {
  return std::unexpected(singleError({}, std::move(problem)));
}

bool finite(const std::vector<float>& v) {
  return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

// Mesh's invariants (as the single-mesh writers check them); "" when the object can be written.
std::string objectProblem(const NamedMesh& o) {
  if (o.mesh == nullptr) return "object '" + o.name + "' has no mesh";
  const Mesh& m = *o.mesh;
  const std::string at = "object '" + o.name + "': invalid mesh: ";
  if (m.positions.size() % 3 != 0 || m.indices.size() % 3 != 0) return at + "not whole triples";
  if ((!m.normals.empty() && m.normals.size() != m.positions.size()) ||
      (!m.colors.empty() && m.colors.size() != m.positions.size()))
    return at + "normals or colors neither empty nor as long as positions";
  if (m.vertexCount() > UINT32_MAX) return at + "more than 2^32 - 1 vertices";
  for (uint32_t i : m.indices)
    if (i >= m.vertexCount()) return at + "an index is not below the vertex count";
  if (!finite(m.positions) || !finite(m.normals) || !finite(m.colors)) return at + "a number is not finite";
  return {};
}

void appendNumber(std::string& out, float x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

void appendNumber(std::string& out, uint64_t x) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

void appendBytes(std::vector<uint8_t>& bin, const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  bin.insert(bin.end(), p, p + size);
}

}  // namespace

std::expected<std::vector<uint8_t>, Diagnostics> encodeGlbObjects(std::span<const NamedMesh> objects) {
  for (const NamedMesh& o : objects)
    if (std::string problem = objectProblem(o); !problem.empty()) return invalid(std::move(problem));
  using nlohmann::json;
  constexpr int kFloat = 5126, kUnsignedInt = 5125, kTriangles = 4;
  constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
  std::vector<uint8_t> bin;
  json bufferViews = json::array(), accessors = json::array(), meshes = json::array(), nodes = json::array();
  json sceneNodes = json::array();
  auto addView = [&](const void* data, size_t size, int target) {
    bufferViews.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", size}, {"target", target}});
    appendBytes(bin, data, size);
    return bufferViews.size() - 1;
  };
  for (const NamedMesh& o : objects) {
    const Mesh& m = *o.mesh;
    json node = {{"name", o.name}};
    if (m.triangleCount() > 0) {
      const size_t bytes = m.positions.size() * sizeof(float);
      json attributes;
      auto vec3 = [&](const std::vector<float>& values) {
        accessors.push_back({{"bufferView", addView(values.data(), bytes, kArrayBuffer)}, {"componentType", kFloat},
                             {"count", m.vertexCount()}, {"type", "VEC3"}});
        return accessors.size() - 1;
      };
      const size_t position = vec3(m.positions);
      const MeshBounds box = bounds(m);
      accessors[position]["min"] = {double{box.min.x}, double{box.min.y}, double{box.min.z}};
      accessors[position]["max"] = {double{box.max.x}, double{box.max.y}, double{box.max.z}};
      attributes["POSITION"] = position;
      if (!m.normals.empty()) attributes["NORMAL"] = vec3(m.normals);
      if (!m.colors.empty()) {
        std::vector<float> clamped(m.colors);
        for (float& c : clamped) c = std::clamp(c, 0.0f, 1.0f);
        attributes["COLOR_0"] = vec3(clamped);
      }
      accessors.push_back({{"bufferView", addView(m.indices.data(), m.indices.size() * sizeof(uint32_t),
                                                  kElementArrayBuffer)},
                           {"componentType", kUnsignedInt}, {"count", m.indices.size()}, {"type", "SCALAR"}});
      json primitive = {{"attributes", attributes}, {"indices", accessors.size() - 1}, {"mode", kTriangles}};
      meshes.push_back({{"name", o.name}, {"primitives", json::array({primitive})}});
      node["mesh"] = meshes.size() - 1;
    }
    sceneNodes.push_back(nodes.size());
    nodes.push_back(std::move(node));
  }
  json gltf;
  gltf["asset"] = {{"version", "2.0"}, {"generator", "IMPS Puppeteer"}};
  gltf["scene"] = 0;
  gltf["scenes"] = json::array({json{{"nodes", sceneNodes}}});
  gltf["nodes"] = std::move(nodes);
  if (!meshes.empty()) {
    gltf["meshes"] = std::move(meshes);
    gltf["accessors"] = std::move(accessors);
    gltf["bufferViews"] = std::move(bufferViews);
    gltf["buffers"] = json::array({json{{"byteLength", bin.size()}}});
  }
  std::string text = gltf.dump();
  auto padded = [](size_t size) { return (size + 3) & ~size_t{3}; };
  text.resize(padded(text.size()), ' ');
  bin.resize(padded(bin.size()), 0);
  const bool hasBin = !gltf["bufferViews"].is_null() && !bin.empty();
  const size_t total = 12 + 8 + text.size() + (hasBin ? 8 + bin.size() : 0);
  if (total > UINT32_MAX) {
    return invalid("objects too large for GLB (more than 4 GiB)");
  }
  std::vector<uint8_t> out;
  out.reserve(total);
  auto put = [&out](uint32_t v) { appendBytes(out, &v, 4); };
  put(0x46546C67);  // "glTF"
  put(2);
  put(uint32_t(total));
  put(uint32_t(text.size()));
  put(0x4E4F534A);  // "JSON"
  appendBytes(out, text.data(), text.size());
  if (hasBin) {
    put(uint32_t(bin.size()));
    put(0x004E4942);  // "BIN\0"
    appendBytes(out, bin.data(), bin.size());
  }
  return out;
}

std::expected<std::vector<uint8_t>, Diagnostics> encodeObjObjects(std::span<const NamedMesh> objects) {
  for (const NamedMesh& o : objects)
    if (std::string problem = objectProblem(o); !problem.empty()) return invalid(std::move(problem));
  std::string out = "# IMPS Puppeteer: " + std::to_string(objects.size()) + " objects\n";
  uint64_t base = 0;
  for (const NamedMesh& o : objects) {
    const Mesh& m = *o.mesh;
    std::string name = o.name.empty() ? "object" : o.name;
    for (char& c : name)
      if (c == ' ' || c == '\t' || c == '\n' || c == '\r') c = '_';
    out += "o " + name + "\n";
    for (size_t v = 0; v < m.vertexCount(); ++v) {
      out += "v";
      for (int k = 0; k < 3; ++k) out += ' ', appendNumber(out, m.positions[3 * v + k]);
      if (!m.colors.empty())
        for (int k = 0; k < 3; ++k) out += ' ', appendNumber(out, std::clamp(m.colors[3 * v + k], 0.0f, 1.0f));
      out += '\n';
    }
    for (size_t v = 0; v < m.vertexCount() && !m.normals.empty(); ++v) {
      out += "vn";
      for (int k = 0; k < 3; ++k) out += ' ', appendNumber(out, m.normals[3 * v + k]);
      out += '\n';
    }
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      out += 'f';
      for (int k = 0; k < 3; ++k) {
        const uint64_t i = base + m.indices[3 * t + k] + 1;
        out += ' ';
        appendNumber(out, i);
        if (!m.normals.empty()) out += "//", appendNumber(out, i);
      }
      out += '\n';
    }
    base += m.vertexCount();
  }
  return std::vector<uint8_t>(out.begin(), out.end());
}

std::expected<void, Diagnostics> writeMeshObjects(std::span<const NamedMesh> objects, const std::string& path) {
  const std::optional<MeshFormat> format = meshFormatForPath(path);
  if (!format) return invalid(path + ": unsupported mesh file extension (supported: .obj, .ply, .glb)");
  if (*format == MeshFormat::Ply) {
    Mesh merged;
    for (const NamedMesh& o : objects) {
      if (std::string problem = objectProblem(o); !problem.empty()) return invalid(path + ": " + problem);
      appendMesh(merged, *o.mesh);
    }
    return writePly(merged, path);
  }
  return saveEncodedMesh(*format == MeshFormat::Glb ? encodeGlbObjects(objects) : encodeObjObjects(objects), path);
}

}  // namespace imps
