// SPDX-License-Identifier: MIT
// Textured mesh export: the images as glTF/OBJ want them, and the files beside each other.
#include "textured_export.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <span>

#include "imps/atomic_file.h"
#include "imps/file_read.h"
#include "imps/mesh_io.h"

namespace imps::app {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// The texture files as PNG or JPEG bytes: the file itself when it is one, else the decoded image as PNG; or why
// one cannot be had, "path: reason".
std::expected<std::vector<MeshImage>, Diagnostics> encodedImages(const Character& character,
                                                                 const std::vector<RgbaImage>& images,
                                                                 const std::string& stem) {
  std::vector<MeshImage> out;
  for (size_t k = 0; k < character.textures().size(); ++k) {
    const CharacterTexture& t = character.textures()[k];
    const std::string ext = lowerExtension(t.path);
    MeshImage image;
    const bool jpeg = ext == ".jpg" || ext == ".jpeg";
    if (ext == ".png" || jpeg) {
      auto bytes = readFileText(t.path, size_t{256} << 20);  // texture files: at most 256 MiB
      if (!bytes) return std::unexpected(singleError({}, t.path + ": " + bytes.error().message));
      image.bytes.assign(bytes->begin(), bytes->end());
      image.mimeType = jpeg ? "image/jpeg" : "image/png";
    } else {
      if (k >= images.size()) return std::unexpected(singleError({}, t.path + ": no image"));
      auto png = encodePng(images[k].rgba, images[k].width, images[k].height);
      if (!png) return std::unexpected(singleError({}, t.path + ": " + png.error().all().front().message));
      image.bytes = std::move(*png);
      image.mimeType = "image/png";
    }
    image.name = stem + "_" + std::to_string(k) + (jpeg ? ".jpg" : ".png");
    out.push_back(std::move(image));
  }
  return out;
}

}  // namespace

std::expected<void, Diagnostics> writeTexturedMesh(const Mesh& mesh, const Character& character,
                                                   const std::vector<RgbaImage>& images, const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (!mesh.textured() || ext == ".ply") return writeMesh(mesh, path);
  const std::filesystem::path target(path);
  const std::string stem = target.stem().string();
  auto encoded = encodedImages(character, images, stem);
  if (!encoded) return std::unexpected(encoded.error());
  if (ext == ".glb") return writeTexturedGlb(mesh, *encoded, path);
  if (ext != ".obj") return writeMesh(mesh, path);
  const auto obj = encodeTexturedObj(mesh, *encoded, stem + ".mtl");
  if (!obj) return std::unexpected(singleError({}, path + ": " + obj.error().all().front().message));
  auto save = [](const std::string& file, std::span<const uint8_t> bytes) -> std::expected<void, Diagnostics> {
    if (auto saved = writeFileAtomically(file, bytes); !saved)
      return std::unexpected(singleError({}, saved.error().message));
    return {};
  };
  for (const MeshImage& image : *encoded)
    if (auto saved = save((target.parent_path() / image.name).string(), image.bytes); !saved) return saved;
  if (auto saved = save((target.parent_path() / (stem + ".mtl")).string(), obj->mtl); !saved) return saved;
  return save(path, obj->obj);
}

}  // namespace imps::app
