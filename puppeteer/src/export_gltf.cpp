// SPDX-License-Identifier: MIT
// Skinned, animated glTF export of a take (see export_gltf.h).
#include "export_gltf.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include "imps/atomic_file.h"
#include "imps/marching_cubes.h"

namespace imps::app {
namespace {

using nlohmann::json;
constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

// The BIN chunk and the bufferViews / accessors describing it, every view 4-byte aligned.
struct BinaryBuilder {
  std::vector<uint8_t> bin;
  json views = json::array(), accessors = json::array();

  // Appends raw bytes as one bufferView (with `target` when >= 0) and an accessor over them; returns its index.
  int add(const void* data, size_t bytes, int componentType, const char* type, size_t count, int target,
          const json& extra = json::object()) {
    while (bin.size() % 4) bin.push_back(0);
    json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target >= 0) view["target"] = target;
    const auto* p = static_cast<const uint8_t*>(data);
    bin.insert(bin.end(), p, p + bytes);
    views.push_back(view);
    json accessor = {
        {"bufferView", views.size() - 1}, {"componentType", componentType}, {"count", count}, {"type", type}};
    accessor.update(extra);
    accessors.push_back(accessor);
    return static_cast<int>(accessors.size()) - 1;
  }
};

float contribution(const BlendFunction& blend, const CharacterPrimitive& p, const glm::vec3& x) {
  const float param = p.blendParam != 0.0f ? p.blendParam : blend.defaultParam;
  const float t = blend.term(p.local.distance(x), param);
  return blend.additive() ? t : t + 1.0f;  // elliptical: (1 - d) / range >= -1
}

std::vector<uint8_t> glbContainer(const std::string& jsonText, const std::vector<uint8_t>& bin) {
  std::string text = jsonText;
  while (text.size() % 4) text += ' ';
  std::vector<uint8_t> padded = bin;
  while (padded.size() % 4) padded.push_back(0);
  std::vector<uint8_t> out;
  auto put32 = [&](uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(static_cast<uint8_t>(v >> (8 * k)));
  };
  put32(0x46546C67);  // "glTF"
  put32(2);
  put32(static_cast<uint32_t>(12 + 8 + text.size() + 8 + padded.size()));
  put32(static_cast<uint32_t>(text.size()));
  put32(0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  put32(static_cast<uint32_t>(padded.size()));
  put32(0x004E4942);  // "BIN\0"
  out.insert(out.end(), padded.begin(), padded.end());
  return out;
}

}  // namespace

SkinWeights skinWeights(const Character& character, const Mesh& mesh) {
  // The rest pose: primitives in world space, per joint.
  SkeletonCache rest(character);
  const auto& prims = character.primitives();
  std::vector<CharacterPrimitive> world = prims;
  for (size_t i = 0; i < prims.size(); ++i) world[i].local = rest.field().primitive(i);
  const size_t joints = character.joints().size();
  SkinWeights out;
  std::vector<float> perJoint(joints);
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 x = mesh.position(v);
    std::fill(perJoint.begin(), perJoint.end(), 0.0f);
    float nearest = std::numeric_limits<float>::infinity();
    size_t nearestJoint = 0;
    for (const CharacterPrimitive& p : world) {
      const size_t j = p.joint >= 0 ? static_cast<size_t>(p.joint) : 0;
      perJoint[j] += std::max(contribution(character.blend(), p, x), 0.0f);
      const float d = p.local.distance(x);
      if (d < nearest) nearest = d, nearestJoint = j;
    }
    std::vector<size_t> order(joints);
    for (size_t j = 0; j < joints; ++j) order[j] = j;
    std::partial_sort(
        order.begin(), order.begin() + static_cast<std::ptrdiff_t>(std::min<size_t>(4, joints)), order.end(),
        [&](size_t a, size_t b) { return perJoint[a] > perJoint[b] || (perJoint[a] == perJoint[b] && a < b); });
    std::array<uint16_t, 4> js{0, 0, 0, 0};
    std::array<float, 4> ws{0, 0, 0, 0};
    float sum = 0;
    for (size_t k = 0; k < std::min<size_t>(4, joints); ++k) {
      if (!(perJoint[order[k]] > 0)) break;
      js[k] = static_cast<uint16_t>(order[k]);
      ws[k] = perJoint[order[k]];
      sum += ws[k];
    }
    if (sum > 0) {
      for (float& w : ws) w /= sum;
    } else {
      js = {static_cast<uint16_t>(nearestJoint), 0, 0, 0};
      ws = {1, 0, 0, 0};
    }
    out.joints.push_back(js);
    out.weights.push_back(ws);
  }
  return out;
}

std::expected<std::vector<uint8_t>, Diagnostics> encodeSkinnedGlb(const Character& character, const Take& take,
                                                                  const GltfExportOptions& options) {
  const auto& joints = character.joints();
  const size_t n = joints.size();
  if (n == 0 || n > 65535)
    return std::unexpected(singleError({}, "the character needs 1 to 65535 joints for a skin (a flat scene has none)"));
  // 1. The rest mesh and its weights.
  SkeletonCache rest(character);
  MarchingCubesOptions mc;
  mc.cellSize = options.cellSize;
  const Mesh mesh = polygonize(rest.field(), mc);
  if (mesh.triangleCount() == 0) return std::unexpected(singleError({}, "the rest mesh is empty"));
  const SkinWeights weights = skinWeights(character, mesh);

  BinaryBuilder b;
  glm::vec3 lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
  for (size_t v = 0; v < mesh.vertexCount(); ++v)
    lo = glm::min(lo, mesh.position(v)), hi = glm::max(hi, mesh.position(v));
  json attributes;
  attributes["POSITION"] = b.add(mesh.positions.data(), mesh.positions.size() * 4, kFloat, "VEC3", mesh.vertexCount(),
                                 kArrayBuffer, {{"min", {lo.x, lo.y, lo.z}}, {"max", {hi.x, hi.y, hi.z}}});
  if (!mesh.normals.empty())
    attributes["NORMAL"] =
        b.add(mesh.normals.data(), mesh.normals.size() * 4, kFloat, "VEC3", mesh.vertexCount(), kArrayBuffer);
  if (!mesh.colors.empty())
    attributes["COLOR_0"] =
        b.add(mesh.colors.data(), mesh.colors.size() * 4, kFloat, "VEC3", mesh.vertexCount(), kArrayBuffer);
  attributes["JOINTS_0"] = b.add(weights.joints.data(), weights.joints.size() * 8, kUnsignedShort, "VEC4",
                                 mesh.vertexCount(), kArrayBuffer);
  attributes["WEIGHTS_0"] = b.add(weights.weights.data(), weights.weights.size() * 16, kFloat, "VEC4",
                                  mesh.vertexCount(), kArrayBuffer);
  const int indices = b.add(mesh.indices.data(), mesh.indices.size() * 4, kUnsignedInt, "SCALAR", mesh.indices.size(),
                            kElementArrayBuffer);

  // 2. The skeleton: one node per joint with its rest transform; inverse bind matrices of the rest world transforms.
  json nodes = json::array();
  std::vector<float> ibm;
  for (size_t j = 0; j < n; ++j) {
    const Rigid& r = joints[j].rest;
    json node = {{"name", joints[j].name},
                 {"translation", {r.translation.x, r.translation.y, r.translation.z}},
                 {"rotation", {r.rotation.x, r.rotation.y, r.rotation.z, r.rotation.w}}};
    json children = json::array();
    for (size_t k = 0; k < n; ++k)
      if (joints[k].parent == static_cast<int>(j)) children.push_back(k);
    if (!children.empty()) node["children"] = children;
    nodes.push_back(node);
    const Rigid& w = rest.world(static_cast<int>(j));
    glm::mat4 m = glm::mat4_cast(w.rotation);
    m[3] = glm::vec4(w.translation, 1.0f);
    const glm::mat4 inv = glm::inverse(m);
    ibm.insert(ibm.end(), glm::value_ptr(inv), glm::value_ptr(inv) + 16);
  }
  const int ibmAccessor = b.add(ibm.data(), ibm.size() * 4, kFloat, "MAT4", n, -1);
  json sceneNodes = json::array();
  for (size_t j = 0; j < n; ++j)
    if (joints[j].parent < 0) sceneNodes.push_back(j);
  nodes.push_back({{"name", "character"}, {"mesh", 0}, {"skin", 0}});
  sceneNodes.push_back(n);
  json skinJoints = json::array();
  for (size_t j = 0; j < n; ++j) skinJoints.push_back(j);

  // 3. The take: one sampler per joint for rotations, and for translations of joints that move.
  json samplers = json::array(), channels = json::array();
  if (take.frames() > 0) {
    std::vector<float> times(take.frames());
    for (size_t f = 0; f < times.size(); ++f) times[f] = static_cast<float>(static_cast<double>(f) * take.frameTime);
    const int input = b.add(times.data(), times.size() * 4, kFloat, "SCALAR", times.size(), -1,
                            {{"min", {times.front()}}, {"max", {times.back()}}});
    for (size_t j = 0; j < n; ++j) {
      std::vector<float> q;
      glm::quat previous = take.locals[0][j].rotation;
      bool moves = false;
      std::vector<float> t;
      for (size_t f = 0; f < take.frames(); ++f) {
        glm::quat r = glm::normalize(take.locals[f][j].rotation);
        if (glm::dot(r, previous) < 0) r = -r;  // the short way between frames for LINEAR interpolation
        previous = r;
        q.insert(q.end(), {r.x, r.y, r.z, r.w});
        const glm::vec3 p = take.locals[f][j].translation;
        t.insert(t.end(), {p.x, p.y, p.z});
        moves = moves || glm::length(p - joints[j].rest.translation) > 1e-7f;
      }
      samplers.push_back({{"input", input},
                          {"output", b.add(q.data(), q.size() * 4, kFloat, "VEC4", take.frames(), -1)},
                          {"interpolation", "LINEAR"}});
      channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", j}, {"path", "rotation"}}}});
      if (!moves) continue;
      samplers.push_back({{"input", input},
                          {"output", b.add(t.data(), t.size() * 4, kFloat, "VEC3", take.frames(), -1)},
                          {"interpolation", "LINEAR"}});
      channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", j}, {"path", "translation"}}}});
    }
  }

  json gltf;
  gltf["asset"] = {{"version", "2.0"}, {"generator", "IMPS Puppeteer export"}};
  gltf["scene"] = 0;
  gltf["scenes"] = json::array({json{{"nodes", sceneNodes}}});
  gltf["nodes"] = nodes;
  gltf["meshes"] = json::array(
      {json{{"name", "implicit skin"},
            {"primitives", json::array({json{{"attributes", attributes}, {"indices", indices}, {"mode", 4}}})}}});
  gltf["skins"] = json::array({json{{"joints", skinJoints}, {"inverseBindMatrices", ibmAccessor}}});
  if (!channels.empty())
    gltf["animations"] = json::array({json{{"name", "take"}, {"samplers", samplers}, {"channels", channels}}});
  gltf["accessors"] = b.accessors;
  gltf["bufferViews"] = b.views;
  gltf["buffers"] = json::array({json{{"byteLength", (b.bin.size() + 3) / 4 * 4}}});
  return glbContainer(gltf.dump(), b.bin);
}

std::expected<void, Diagnostics> writeSkinnedGlb(const Character& character, const Take& take,
                                                 const GltfExportOptions& options, const std::string& path) {
  const auto bytes = encodeSkinnedGlb(character, take, options);
  if (!bytes) return std::unexpected(bytes.error());
  if (auto saved = writeFileAtomically(path, *bytes); !saved)
    return std::unexpected(singleError({}, saved.error().message));
  return {};
}

}  // namespace imps::app
