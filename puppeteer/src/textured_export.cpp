// SPDX-License-Identifier: MIT
// Textured mesh export: the images as glTF/OBJ want them, and the files beside each other.
#include "textured_export.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

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

// The texture files as PNG or JPEG bytes: the file itself when it is one, else the decoded image as PNG.
bool encodedImages(const Character& character, const std::vector<RgbaImage>& images, const std::string& stem,
                   std::vector<MeshImage>& out, std::string* error) {
  for (size_t k = 0; k < character.textures().size(); ++k) {
    const CharacterTexture& t = character.textures()[k];
    const std::string ext = lowerExtension(t.path);
    MeshImage image;
    const bool jpeg = ext == ".jpg" || ext == ".jpeg";
    if (ext == ".png" || jpeg) {
      auto bytes = readFileText(t.path, size_t{256} << 20);  // texture files: at most 256 MiB
      if (!bytes) {
        if (error) *error = t.path + ": " + bytes.error();
        return false;
      }
      image.bytes.assign(bytes->begin(), bytes->end());
      image.mimeType = jpeg ? "image/jpeg" : "image/png";
    } else {
      std::string reason;
      auto png = k < images.size() ? encodePng(images[k].rgba, images[k].width, images[k].height, &reason)
                                   : std::nullopt;
      if (!png) {
        if (error) *error = t.path + ": " + (reason.empty() ? "no image" : reason);
        return false;
      }
      image.bytes = std::move(*png);
      image.mimeType = "image/png";
    }
    image.name = stem + "_" + std::to_string(k) + (jpeg ? ".jpg" : ".png");
    out.push_back(std::move(image));
  }
  return true;
}

}  // namespace

bool writeTexturedMesh(const Mesh& mesh, const Character& character, const std::vector<RgbaImage>& images,
                       const std::string& path, std::string* error) {
  const std::string ext = lowerExtension(path);
  if (!mesh.textured() || ext == ".ply") return writeMesh(mesh, path, error);
  const std::filesystem::path target(path);
  const std::string stem = target.stem().string();
  std::vector<MeshImage> encoded;
  if (!encodedImages(character, images, stem, encoded, error)) return false;
  if (ext == ".glb") return writeTexturedGlb(mesh, encoded, path, error);
  if (ext != ".obj") return writeMesh(mesh, path, error);
  std::string problem;
  const auto obj = encodeTexturedObj(mesh, encoded, stem + ".mtl", &problem);
  if (!obj) {
    if (error) *error = path + ": " + problem;
    return false;
  }
  for (const MeshImage& image : encoded)
    if (!writeFileAtomically((target.parent_path() / image.name).string(), image.bytes, error)) return false;
  if (!writeFileAtomically((target.parent_path() / (stem + ".mtl")).string(), obj->mtl, error)) return false;
  return writeFileAtomically(path, obj->obj, error);
}

}  // namespace imps::app
