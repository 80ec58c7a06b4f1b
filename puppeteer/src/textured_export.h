// SPDX-License-Identifier: MIT
// Writing a textured mesh with its images: glTF binary with the images embedded, OBJ with an .mtl and the images
// beside it (docs/cli.md, `puppeteer mesh`).
#pragma once

#include <expected>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/mesh.h"
#include "png.h"

namespace imps::app {

// Writes `mesh` to `path` by its extension, as imps::writeMesh does, and for a textured mesh (mesh.h's layers)
// also its textures: `.glb` embeds every image (PNG and JPEG files verbatim, others re-encoded as PNG) with
// TEXCOORD_0 and baseColorTexture materials (imps::encodeTexturedGlb); `.obj` writes STEM.mtl and each image as
// STEM_K.EXT beside it (K the texture's index in character.textures()), then the OBJ; `.ply` has no textures.
// `images` are loadTextures(character)'s. Every file is written atomically; on failure (files already written stay)
// fails as imps::writeMesh does: one error without a location, "path: reason" (a texture file named by its path) or
// the save's "cannot save 'path': ...".
std::expected<void, Diagnostics> writeTexturedMesh(const Mesh& mesh, const Character& character,
                                                   const std::vector<RgbaImage>& images, const std::string& path);

}  // namespace imps::app
