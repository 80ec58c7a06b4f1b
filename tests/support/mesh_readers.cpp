// SPDX-License-Identifier: MIT
// Test-only mesh readers: binary PLY, OBJ and (through tinygltf) GLB.
#include "mesh_readers.h"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

// Debian ships tiny_gltf.h both as a header-only library (define TINYGLTF_IMPLEMENTATION in one file) and as
// libtinygltf.so. We compile the implementation here, in the one test-support file that uses it, so the tests need
// no extra link setup. Images are never loaded, so stb (which Debian keeps under /usr/include/stb, off the
// default include path) is switched off; the JSON parser is nlohmann's, as in Debian's build.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

namespace imps::test {
namespace {

bool fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

std::optional<std::string> readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<std::string_view> splitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    size_t j = i;
    while (j < line.size() && line[j] != ' ' && line[j] != '\t' && line[j] != '\r') ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

template <class T>
bool parseNumber(std::string_view text, T* value) {
  const auto result = std::from_chars(text.data(), text.data() + text.size(), *value);
  return result.ec == std::errc() && result.ptr == text.data() + text.size();
}

// ---- PLY ----

struct PlyProperty {
  std::string name;
  std::string type;       // scalar type, or the item type of a list
  std::string countType;  // non-empty for lists
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

size_t plyTypeSize(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

template <class T>
double loadAs(const char* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  return static_cast<double>(value);
}

double plyValue(const std::string& type, const char* p) {
  if (type == "char" || type == "int8") return loadAs<int8_t>(p);
  if (type == "uchar" || type == "uint8") return loadAs<uint8_t>(p);
  if (type == "short" || type == "int16") return loadAs<int16_t>(p);
  if (type == "ushort" || type == "uint16") return loadAs<uint16_t>(p);
  if (type == "int" || type == "int32") return loadAs<int32_t>(p);
  if (type == "uint" || type == "uint32") return loadAs<uint32_t>(p);
  if (type == "float" || type == "float32") return loadAs<float>(p);
  return loadAs<double>(p);
}

// ---- GLB ----

// Reads `components` floats (or unsigned integers for indices) per element of accessor `index` into `out`.
bool readAccessor(const tinygltf::Model& model, int index, int components, std::vector<double>* out,
                  std::string* error) {
  if (index < 0 || static_cast<size_t>(index) >= model.accessors.size()) return fail(error, "bad accessor index");
  const tinygltf::Accessor& accessor = model.accessors[static_cast<size_t>(index)];
  if (accessor.bufferView < 0) return fail(error, "accessor without bufferView");
  const tinygltf::BufferView& view = model.bufferViews[static_cast<size_t>(accessor.bufferView)];
  const tinygltf::Buffer& buffer = model.buffers[static_cast<size_t>(view.buffer)];
  const int componentSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(accessor.componentType));
  const int accessorComponents = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
  if (componentSize <= 0 || accessorComponents < components) return fail(error, "unexpected accessor type");
  const int stride = accessor.ByteStride(view);
  if (stride <= 0) return fail(error, "bad byte stride");
  const size_t begin = view.byteOffset + accessor.byteOffset;
  const size_t elementSize = static_cast<size_t>(componentSize * accessorComponents);
  if (accessor.count > 0 &&
      (begin + static_cast<size_t>(stride) * (accessor.count - 1) + elementSize > view.byteOffset + view.byteLength ||
       view.byteOffset + view.byteLength > buffer.data.size())) {
    return fail(error, "accessor runs past its buffer");
  }
  out->clear();
  out->reserve(accessor.count * static_cast<size_t>(components));
  for (size_t e = 0; e < accessor.count; ++e) {
    const auto* element = reinterpret_cast<const char*>(buffer.data.data() + begin + e * static_cast<size_t>(stride));
    for (int c = 0; c < components; ++c) {
      const char* p = element + c * componentSize;
      switch (accessor.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: out->push_back(loadAs<float>(p)); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: out->push_back(loadAs<uint32_t>(p)); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: out->push_back(loadAs<uint16_t>(p)); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out->push_back(loadAs<uint8_t>(p)); break;
        default: return fail(error, "unsupported component type " + std::to_string(accessor.componentType));
      }
    }
  }
  return true;
}

std::vector<float> toFloats(const std::vector<double>& values) {
  std::vector<float> out(values.size());
  std::transform(values.begin(), values.end(), out.begin(), [](double v) { return static_cast<float>(v); });
  return out;
}

}  // namespace

bool readPly(const std::string& path, Mesh* mesh, std::string* error) {
  const std::optional<std::string> file = readFile(path);
  if (!file) return fail(error, path + ": cannot read");
  const std::string& data = *file;
  const size_t headerEnd = data.find("end_header\n");
  if (data.rfind("ply\n", 0) != 0 || headerEnd == std::string::npos) return fail(error, path + ": not a PLY file");

  // Header.
  std::vector<PlyElement> elements;
  std::istringstream header(data.substr(0, headerEnd));
  std::string line;
  bool binaryLittleEndian = false;
  while (std::getline(header, line)) {
    const std::vector<std::string_view> w = splitWords(line);
    if (w.empty()) continue;
    if (w[0] == "format") {
      binaryLittleEndian = w.size() == 3 && w[1] == "binary_little_endian" && w[2] == "1.0";
    } else if (w[0] == "element" && w.size() == 3) {
      PlyElement element;
      element.name = w[1];
      if (!parseNumber(w[2], &element.count)) return fail(error, path + ": bad element count");
      elements.push_back(element);
    } else if (w[0] == "property") {
      if (elements.empty()) return fail(error, path + ": property before any element");
      PlyProperty property;
      if (w.size() == 5 && w[1] == "list") {
        property = {std::string(w[4]), std::string(w[3]), std::string(w[2])};
      } else if (w.size() == 3) {
        property = {std::string(w[2]), std::string(w[1]), ""};
      } else {
        return fail(error, path + ": bad property line '" + line + "'");
      }
      if (plyTypeSize(property.type) == 0 || (!property.countType.empty() && plyTypeSize(property.countType) == 0))
        return fail(error, path + ": unknown property type in '" + line + "'");
      elements.back().properties.push_back(property);
    }
  }
  if (!binaryLittleEndian) return fail(error, path + ": only format binary_little_endian 1.0 is supported");

  // Body.
  mesh->clear();
  const char* p = data.data() + headerEnd + std::strlen("end_header\n");
  const char* end = data.data() + data.size();
  auto need = [&](size_t bytes) { return static_cast<size_t>(end - p) >= bytes; };
  for (const PlyElement& element : elements) {
    const bool isVertex = element.name == "vertex";
    const bool isFace = element.name == "face";
    for (size_t item = 0; item < element.count; ++item) {
      float position[3] = {0, 0, 0}, normal[3] = {0, 0, 0}, color[3] = {0, 0, 0};
      bool hasNormal = false, hasColor = false, sawFaceList = false;
      for (const PlyProperty& property : element.properties) {
        const size_t size = plyTypeSize(property.type);
        if (!property.countType.empty()) {
          if (!need(plyTypeSize(property.countType))) return fail(error, path + ": truncated");
          const auto count = static_cast<size_t>(plyValue(property.countType, p));
          p += plyTypeSize(property.countType);
          if (!need(count * size)) return fail(error, path + ": truncated");
          if (isFace && !sawFaceList) {
            sawFaceList = true;
            if (count < 3) return fail(error, path + ": face with fewer than 3 corners");
            const auto corner = [&](size_t k) { return static_cast<uint32_t>(plyValue(property.type, p + k * size)); };
            for (size_t k = 1; k + 1 < count; ++k) {
              mesh->indices.insert(mesh->indices.end(), {corner(0), corner(k), corner(k + 1)});
            }
          }
          p += count * size;
          continue;
        }
        if (!need(size)) return fail(error, path + ": truncated");
        const double value = plyValue(property.type, p);
        p += size;
        if (!isVertex) continue;
        const std::string& n = property.name;
        const bool isByte = size == 1;
        const auto asColor = [&] { return static_cast<float>(isByte ? value / 255.0 : value); };
        if (n == "x") position[0] = static_cast<float>(value);
        if (n == "y") position[1] = static_cast<float>(value);
        if (n == "z") position[2] = static_cast<float>(value);
        if (n == "nx" || n == "ny" || n == "nz") {
          hasNormal = true;
          normal[n[1] - 'x'] = static_cast<float>(value);
        }
        if (n == "red" || n == "r") color[0] = asColor(), hasColor = true;
        if (n == "green" || n == "g") color[1] = asColor(), hasColor = true;
        if (n == "blue" || n == "b") color[2] = asColor(), hasColor = true;
      }
      if (isVertex) {
        mesh->positions.insert(mesh->positions.end(), position, position + 3);
        if (hasNormal) mesh->normals.insert(mesh->normals.end(), normal, normal + 3);
        if (hasColor) mesh->colors.insert(mesh->colors.end(), color, color + 3);
      }
    }
  }
  if (p != end) return fail(error, path + ": " + std::to_string(end - p) + " bytes after the last element");
  for (const uint32_t i : mesh->indices) {
    if (i >= mesh->vertexCount()) return fail(error, path + ": index out of range");
  }
  return true;
}

bool readObj(const std::string& path, Mesh* mesh, std::string* error) {
  const std::optional<std::string> file = readFile(path);
  if (!file) return fail(error, path + ": cannot read");
  mesh->clear();
  std::vector<float> normals;
  size_t coloredVertices = 0;
  std::string_view rest = *file;
  for (int lineNumber = 1; !rest.empty(); ++lineNumber) {
    const size_t newline = rest.find('\n');
    const std::string_view line = rest.substr(0, newline);
    rest = newline == std::string_view::npos ? std::string_view() : rest.substr(newline + 1);
    const std::string where = path + ":" + std::to_string(lineNumber) + ": ";
    const std::vector<std::string_view> w = splitWords(line);
    if (w.empty() || w[0][0] == '#') continue;
    if (w[0] == "v" || w[0] == "vn") {
      if (w.size() != 4 && !(w[0] == "v" && w.size() == 7)) return fail(error, where + "expected 3 (or 6) numbers");
      float values[6];
      for (size_t k = 1; k < w.size(); ++k) {
        if (!parseNumber(w[k], &values[k - 1])) return fail(error, where + "bad number '" + std::string(w[k]) + "'");
      }
      std::vector<float>& target = w[0] == "v" ? mesh->positions : normals;
      target.insert(target.end(), values, values + 3);
      if (w.size() == 7) {
        mesh->colors.insert(mesh->colors.end(), values + 3, values + 6);
        ++coloredVertices;
      }
    } else if (w[0] == "f") {
      if (w.size() < 4) return fail(error, where + "face with fewer than 3 corners");
      std::vector<uint32_t> corners;
      for (size_t k = 1; k < w.size(); ++k) {
        const std::string_view corner = w[k];
        const size_t slash = corner.find('/');
        long vertex = 0;
        if (!parseNumber(corner.substr(0, slash), &vertex) || vertex == 0)
          return fail(error, where + "bad corner '" + std::string(corner) + "'");
        const long vertexCount = static_cast<long>(mesh->vertexCount());
        if (vertex < 0) vertex += vertexCount + 1;
        if (vertex < 1 || vertex > vertexCount) return fail(error, where + "vertex index out of range");
        const size_t secondSlash = slash == std::string_view::npos ? slash : corner.find('/', slash + 1);
        if (secondSlash != std::string_view::npos) {
          long normal = 0;
          if (!parseNumber(corner.substr(secondSlash + 1), &normal)) return fail(error, where + "bad normal index");
          if (normal < 0) normal += static_cast<long>(normals.size() / 3) + 1;
          if (normal != vertex) return fail(error, where + "normal index differs from vertex index");
        }
        corners.push_back(static_cast<uint32_t>(vertex - 1));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        mesh->indices.insert(mesh->indices.end(), {corners[0], corners[k], corners[k + 1]});
      }
    }
  }
  if (coloredVertices != 0 && coloredVertices != mesh->vertexCount())
    return fail(error, path + ": only some vertices have colours");
  if (!normals.empty() && normals.size() != mesh->positions.size())
    return fail(error, path + ": normal count differs from vertex count");
  mesh->normals = std::move(normals);
  return true;
}

bool loadGlbModel(const std::string& path, tinygltf::Model* model, std::string* error, std::string* warning) {
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromFile(model, &err, &warn, path);
  if (error) *error = err;
  if (warning) *warning = warn;
  return ok && err.empty();
}

bool readGlb(const std::string& path, Mesh* mesh, std::string* error, std::string* warning) {
  tinygltf::Model model;
  std::string err;
  if (!loadGlbModel(path, &model, &err, warning)) return fail(error, path + ": tinygltf: " + err);
  mesh->clear();
  if (model.meshes.empty()) return true;
  if (model.meshes[0].primitives.empty()) return fail(error, path + ": mesh without primitives");
  const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
  if (primitive.mode != TINYGLTF_MODE_TRIANGLES) return fail(error, path + ": primitive is not triangles");
  std::vector<double> values;
  const auto attribute = [&](const char* name) {
    const auto found = primitive.attributes.find(name);
    return found == primitive.attributes.end() ? -1 : found->second;
  };
  if (attribute("POSITION") < 0) return fail(error, path + ": no POSITION");
  if (!readAccessor(model, attribute("POSITION"), 3, &values, error)) return false;
  mesh->positions = toFloats(values);
  if (attribute("NORMAL") >= 0) {
    if (!readAccessor(model, attribute("NORMAL"), 3, &values, error)) return false;
    mesh->normals = toFloats(values);
  }
  if (attribute("COLOR_0") >= 0) {
    const tinygltf::Accessor& accessor = model.accessors[static_cast<size_t>(attribute("COLOR_0"))];
    if (accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) return fail(error, path + ": COLOR_0 not float");
    if (!readAccessor(model, attribute("COLOR_0"), 3, &values, error)) return false;
    mesh->colors = toFloats(values);
  }
  if (primitive.indices < 0) return fail(error, path + ": no indices");
  if (!readAccessor(model, primitive.indices, 1, &values, error)) return false;
  mesh->indices.resize(values.size());
  std::transform(values.begin(), values.end(), mesh->indices.begin(),
                 [](double v) { return static_cast<uint32_t>(v); });
  return true;
}

}  // namespace imps::test
