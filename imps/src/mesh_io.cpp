// SPDX-License-Identifier: MIT
// Mesh export: OBJ, binary PLY and glTF 2.0 binary, built in memory and saved atomically.
// Based on: Khronos Group, "glTF 2.0 Specification" (2021), sections 3.6-3.7 (accessors, buffers) and 4 (GLB);
// Greg Turk, "The PLY Polygon File Format" (1994); Wavefront, "Object Files (.obj)" (Advanced Visualizer manual).
#include "imps/mesh_io.h"

#include "imps/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>

#include "imps/check.h"

namespace imps {
namespace {

// The binary formats are little-endian; the writers copy floats and integers as they sit in memory.
static_assert(std::endian::native == std::endian::little, "mesh writers assume a little-endian host");

bool allFinite(const std::vector<float>& values) {
  return std::all_of(values.begin(), values.end(), [](float x) { return std::isfinite(x); });
}

// Checks Mesh's invariants; returns "" when the mesh can be written, else what is wrong.
std::string meshProblem(const Mesh& mesh) {
  if (mesh.positions.size() % 3 != 0) return "invalid mesh: positions.size() is not a multiple of 3";
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    return "invalid mesh: normals are neither empty nor as long as positions";
  if (!mesh.colors.empty() && mesh.colors.size() != mesh.positions.size())
    return "invalid mesh: colors are neither empty nor as long as positions";
  if (mesh.indices.size() % 3 != 0) return "invalid mesh: indices.size() is not a multiple of 3";
  if (mesh.vertexCount() > UINT32_MAX) return "invalid mesh: more than 2^32 - 1 vertices";
  const size_t vertexCount = mesh.vertexCount();
  for (size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= vertexCount) {
      return "invalid mesh: index " + std::to_string(mesh.indices[i]) + " at indices[" + std::to_string(i) +
             "] is not below the vertex count " + std::to_string(vertexCount);
    }
  }
  if (!allFinite(mesh.positions)) return "invalid mesh: a position is not finite";
  if (!allFinite(mesh.normals)) return "invalid mesh: a normal is not finite";
  if (!allFinite(mesh.colors)) return "invalid mesh: a color is not finite";
  return {};
}

float clampColor(float c) { return std::clamp(c, 0.0f, 1.0f); }
uint8_t quantizeColor(float c) { return static_cast<uint8_t>(clampColor(c) * 255.0f + 0.5f); }

// Appends raw bytes at a write cursor into a pre-sized buffer (no per-element reallocation checks).
class ByteCursor {
 public:
  explicit ByteCursor(uint8_t* at) : at_(at) {}
  template <class T>
  void put(const T& value) {
    std::memcpy(at_, &value, sizeof(T));
    at_ += sizeof(T);
  }
  void put(const void* data, size_t size) {
    if (size == 0) return;
    std::memcpy(at_, data, size);
    at_ += size;
  }
  uint8_t* at() const { return at_; }

 private:
  uint8_t* at_;
};

// Text output for OBJ: std::to_chars into a growing byte buffer (no locale, shortest round-trip floats).
class TextOut {
 public:
  explicit TextOut(size_t reserve) { bytes_.reserve(reserve); }
  void text(std::string_view s) { bytes_.insert(bytes_.end(), s.begin(), s.end()); }
  void number(float x) {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
    bytes_.insert(bytes_.end(), buffer, result.ptr);
  }
  void number(uint64_t x) {
    char buffer[24];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x);
    bytes_.insert(bytes_.end(), buffer, result.ptr);
  }
  std::vector<uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<uint8_t> bytes_;
};


std::string lowercase(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::unexpected<Diagnostics> invalid(std::string problem) {
  return std::unexpected(singleError({}, std::move(problem)));
}

}  // namespace

std::expected<void, Diagnostics> saveEncodedMesh(const std::expected<std::vector<uint8_t>, Diagnostics>& bytes,
                                                 const std::string& path) {
  if (!bytes) return std::unexpected(singleError({}, path + ": " + bytes.error().all().front().message));
  if (auto saved = writeFileAtomically(path, *bytes); !saved)
    return std::unexpected(singleError({}, saved.error().message));
  return {};
}

std::optional<MeshFormat> meshFormatForPath(std::string_view path) {
  const size_t slash = path.find_last_of('/');
  const std::string_view name = slash == std::string_view::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  if (dot == std::string_view::npos) return std::nullopt;
  const std::string extension = lowercase(name.substr(dot));
  if (extension == ".obj") return MeshFormat::Obj;
  if (extension == ".ply") return MeshFormat::Ply;
  if (extension == ".glb") return MeshFormat::Glb;
  return std::nullopt;
}

std::expected<std::vector<uint8_t>, Diagnostics> encodeObj(const Mesh& mesh) {
  if (std::string problem = meshProblem(mesh); !problem.empty()) return invalid(std::move(problem));
  const bool hasNormals = !mesh.normals.empty();
  const bool hasColors = !mesh.colors.empty();
  TextOut out(mesh.vertexCount() * (hasColors ? 80 : 40) * (hasNormals ? 2 : 1) + mesh.triangleCount() * 40 + 128);
  out.text("# IMPS Puppeteer mesh: ");
  out.number(uint64_t{mesh.vertexCount()});
  out.text(" vertices, ");
  out.number(uint64_t{mesh.triangleCount()});
  out.text(" triangles\n");
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    out.text("v ");
    out.number(mesh.positions[3 * v]);
    out.text(" ");
    out.number(mesh.positions[3 * v + 1]);
    out.text(" ");
    out.number(mesh.positions[3 * v + 2]);
    if (hasColors) {
      for (int k = 0; k < 3; ++k) {
        out.text(" ");
        out.number(clampColor(mesh.colors[3 * v + k]));
      }
    }
    out.text("\n");
  }
  if (hasNormals) {
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
      out.text("vn ");
      out.number(mesh.normals[3 * v]);
      out.text(" ");
      out.number(mesh.normals[3 * v + 1]);
      out.text(" ");
      out.number(mesh.normals[3 * v + 2]);
      out.text("\n");
    }
  }
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    out.text("f");
    for (int k = 0; k < 3; ++k) {
      const uint64_t oneBased = uint64_t{mesh.indices[3 * t + k]} + 1;
      out.text(" ");
      out.number(oneBased);
      if (hasNormals) {
        out.text("//");
        out.number(oneBased);
      }
    }
    out.text("\n");
  }
  return out.take();
}

std::expected<std::vector<uint8_t>, Diagnostics> encodePly(const Mesh& mesh) {
  if (std::string problem = meshProblem(mesh); !problem.empty()) return invalid(std::move(problem));
  const bool hasNormals = !mesh.normals.empty();
  const bool hasColors = !mesh.colors.empty();
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment generated by IMPS Puppeteer\nelement vertex " +
      std::to_string(mesh.vertexCount()) + "\nproperty float x\nproperty float y\nproperty float z\n";
  if (hasNormals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  if (hasColors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  header += "element face " + std::to_string(mesh.triangleCount()) +
            "\nproperty list uchar uint vertex_indices\nend_header\n";

  const size_t vertexStride = 12 + (hasNormals ? 12 : 0) + (hasColors ? 3 : 0);
  constexpr size_t kFaceStride = 1 + 3 * sizeof(uint32_t);
  std::vector<uint8_t> bytes(header.size() + vertexStride * mesh.vertexCount() + kFaceStride * mesh.triangleCount());
  ByteCursor out(bytes.data());
  out.put(header.data(), header.size());
  const float* p = mesh.positions.data();
  const float* n = mesh.normals.data();
  const float* c = mesh.colors.data();
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    out.put(p + 3 * v, 12);
    if (hasNormals) out.put(n + 3 * v, 12);
    if (hasColors) {
      const uint8_t rgb[3] = {quantizeColor(c[3 * v]), quantizeColor(c[3 * v + 1]), quantizeColor(c[3 * v + 2])};
      out.put(rgb, 3);
    }
  }
  const uint32_t* idx = mesh.indices.data();
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    out.put(uint8_t{3});
    out.put(idx + 3 * t, 12);
  }
  IMPS_CHECK_EQ(static_cast<size_t>(out.at() - bytes.data()), bytes.size());
  return bytes;
}

std::expected<std::vector<uint8_t>, Diagnostics> encodeGlb(const Mesh& mesh) {
  if (std::string problem = meshProblem(mesh); !problem.empty()) return invalid(std::move(problem));
  using nlohmann::json;
  constexpr int kFloat = 5126, kUnsignedInt = 5125, kTriangles = 4;
  constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

  // Pass 1: the BIN chunk's layout, one tightly packed bufferView per attribute (all 4-byte multiples, so every
  // view is aligned), and the accessors describing them.
  const bool hasTriangles = mesh.triangleCount() > 0;
  const bool hasNormals = hasTriangles && !mesh.normals.empty();
  const bool hasColors = hasTriangles && !mesh.colors.empty();
  const size_t attributeBytes = mesh.positions.size() * sizeof(float);
  const size_t indexBytes = mesh.indices.size() * sizeof(uint32_t);
  size_t binSize = 0;
  json bufferViews = json::array();
  json accessors = json::array();
  json attributes = json::object();
  auto addView = [&](size_t size, int target) {
    bufferViews.push_back({{"buffer", 0}, {"byteOffset", binSize}, {"byteLength", size}, {"target", target}});
    binSize += size;
    return bufferViews.size() - 1;
  };
  auto addVec3Accessor = [&](size_t view) {
    accessors.push_back(
        {{"bufferView", view}, {"componentType", kFloat}, {"count", mesh.vertexCount()}, {"type", "VEC3"}});
    return accessors.size() - 1;
  };
  if (hasTriangles) {
    const size_t positionAccessor = addVec3Accessor(addView(attributeBytes, kArrayBuffer));
    // glTF requires POSITION min/max; they must be the exact float values, which survive the trip through double.
    const MeshBounds box = bounds(mesh);
    accessors[positionAccessor]["min"] = {double{box.min.x}, double{box.min.y}, double{box.min.z}};
    accessors[positionAccessor]["max"] = {double{box.max.x}, double{box.max.y}, double{box.max.z}};
    attributes["POSITION"] = positionAccessor;
    if (hasNormals) attributes["NORMAL"] = addVec3Accessor(addView(attributeBytes, kArrayBuffer));
    if (hasColors) attributes["COLOR_0"] = addVec3Accessor(addView(attributeBytes, kArrayBuffer));
    const size_t indexView = addView(indexBytes, kElementArrayBuffer);
    accessors.push_back({{"bufferView", indexView}, {"componentType", kUnsignedInt}, {"count", mesh.indices.size()},
                         {"type", "SCALAR"}});
  }

  // Pass 2: the JSON chunk. nlohmann::json keeps keys sorted, so the text is deterministic.
  json gltf;
  gltf["asset"] = {{"version", "2.0"}, {"generator", "IMPS Puppeteer"}};
  gltf["scene"] = 0;
  gltf["scenes"] = json::array({json{{"nodes", json::array({0})}}});
  if (hasTriangles) {
    gltf["nodes"] = json::array({json{{"mesh", 0}}});
    json primitive = {{"attributes", attributes}, {"indices", accessors.size() - 1}, {"mode", kTriangles}};
    gltf["meshes"] = json::array({json{{"primitives", json::array({primitive})}}});
    gltf["accessors"] = std::move(accessors);
    gltf["bufferViews"] = std::move(bufferViews);
    gltf["buffers"] = json::array({json{{"byteLength", binSize}}});
  } else {
    gltf["nodes"] = json::array({json::object()});
  }
  std::string jsonText = gltf.dump();

  // Pass 3: the GLB container, assembled in one allocation (fresh pages are the main cost for big meshes):
  // 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros.
  auto padded = [](size_t size) { return (size + 3) & ~size_t{3}; };
  const size_t jsonChunk = padded(jsonText.size());
  const size_t binChunk = padded(binSize);
  const size_t total = 12 + 8 + jsonChunk + (hasTriangles ? 8 + binChunk : 0);
  if (total > UINT32_MAX) {
    return invalid("mesh too large for GLB (more than 4 GiB)");
  }
  jsonText.resize(jsonChunk, ' ');
  std::vector<uint8_t> bytes(total, 0);
  ByteCursor out(bytes.data());
  out.put(uint32_t{0x46546C67});  // "glTF"
  out.put(uint32_t{2});
  out.put(static_cast<uint32_t>(total));
  out.put(static_cast<uint32_t>(jsonChunk));
  out.put(uint32_t{0x4E4F534A});  // "JSON"
  out.put(jsonText.data(), jsonText.size());
  if (hasTriangles) {
    out.put(static_cast<uint32_t>(binChunk));
    out.put(uint32_t{0x004E4942});  // "BIN\0"
    // Same order as the bufferViews above.
    out.put(mesh.positions.data(), attributeBytes);
    if (hasNormals) out.put(mesh.normals.data(), attributeBytes);
    if (hasColors) {
      for (const float c : mesh.colors) out.put(clampColor(c));
    }
    out.put(mesh.indices.data(), indexBytes);
    // The zero padding of the BIN chunk is already in `bytes`.
    IMPS_CHECK_EQ(static_cast<size_t>(out.at() - bytes.data()) + (binChunk - binSize), total);
  }
  return bytes;
}

std::expected<void, Diagnostics> writeObj(const Mesh& mesh, const std::string& path) {
  return saveEncodedMesh(encodeObj(mesh), path);
}

std::expected<void, Diagnostics> writePly(const Mesh& mesh, const std::string& path) {
  return saveEncodedMesh(encodePly(mesh), path);
}

std::expected<void, Diagnostics> writeGlb(const Mesh& mesh, const std::string& path) {
  return saveEncodedMesh(encodeGlb(mesh), path);
}

std::expected<void, Diagnostics> writeMesh(const Mesh& mesh, const std::string& path) {
  const std::optional<MeshFormat> format = meshFormatForPath(path);
  if (!format) return invalid(path + ": unsupported mesh file extension (supported: .obj, .ply, .glb)");
  switch (*format) {
    case MeshFormat::Obj: return writeObj(mesh, path);
    case MeshFormat::Ply: return writePly(mesh, path);
    case MeshFormat::Glb: return writeGlb(mesh, path);
  }
  return invalid(path + ": unknown mesh format");
}

}  // namespace imps
