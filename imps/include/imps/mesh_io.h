// SPDX-License-Identifier: MIT
// Mesh export: Wavefront OBJ, binary PLY and glTF 2.0 binary (.glb), each written atomically.
#pragma once

#include <cstdint>
#include <expected>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imps/diagnostic.h"
#include "imps/mesh.h"

namespace imps {

// The file formats writeMesh() knows, chosen by the path's extension (case-insensitive).
enum class MeshFormat { Obj, Ply, Glb };

// The format for `path`'s extension (".obj", ".ply", ".glb", any case), or nullopt for anything else.
std::optional<MeshFormat> meshFormatForPath(std::string_view path);

// What every writer does with a mesh:
// - The mesh must satisfy Mesh's invariants (positions, normals and colors in whole triples, normals/colors empty
//   or as long as positions, whole triangles, every index < vertexCount()) and hold only finite numbers; otherwise
//   nothing is written and the error says what is wrong.
// - Empty normals or colors are left out of the file (OBJ `v x y z` and `f a b c`, no PLY properties, no glTF
//   attribute). Colors are linear RGB clamped to [0, 1]; PLY stores them as round(255 * c).
// - Output is deterministic: the same mesh always gives the same bytes.
// - The save is atomic (imps/atomic_file.h): the bytes go to a temporary file beside `path`, which is flushed,
//   fsync'ed and renamed over `path`. On any failure `path` is untouched and the temporary file is removed.
// - A writer fails for a bad mesh or extension (content) or a failed save (I/O); both come back as one error without
//   a location whose message names the file as the command line prints it: "PATH: invalid mesh: ..." or the save's
//   "cannot save 'PATH': STEP: REASON". (Every caller treats both alike: an output that could not be written.)
//   Thread-safe for distinct paths.

// Writes `mesh` to `path` in the format its extension names (.obj, .ply or .glb). Any other extension is an error
// naming the supported ones.
std::expected<void, Diagnostics> writeMesh(const Mesh& mesh, const std::string& path);

// Wavefront OBJ text: `v x y z [r g b]`, `vn x y z`, `f a//a b//b c//c` (1-based; vertex and normal share indices).
// Numbers use the shortest form that reads back to the same float.
std::expected<void, Diagnostics> writeObj(const Mesh& mesh, const std::string& path);

// PLY, format binary_little_endian 1.0: vertex {float x y z, float nx ny nz, uchar red green blue},
// face {list uchar uint vertex_indices}.
std::expected<void, Diagnostics> writePly(const Mesh& mesh, const std::string& path);

// glTF 2.0 binary: one scene, one node, one mesh with one triangle primitive; attributes POSITION (with min/max),
// NORMAL, COLOR_0 (float VEC3) and UNSIGNED_INT indices in one buffer; asset.generator "IMPS Puppeteer". A mesh
// without triangles gives a scene with one node and no mesh (glTF forbids empty accessors).
std::expected<void, Diagnostics> writeGlb(const Mesh& mesh, const std::string& path);

// The bytes the writers above put in the file, for callers that store or send them elsewhere. For a mesh the writers
// would reject, one error without a location saying what is wrong ("invalid mesh: ...").
std::expected<std::vector<uint8_t>, Diagnostics> encodeObj(const Mesh& mesh);
std::expected<std::vector<uint8_t>, Diagnostics> encodePly(const Mesh& mesh);
std::expected<std::vector<uint8_t>, Diagnostics> encodeGlb(const Mesh& mesh);

// The writers' last step, for callers with bytes of their own (textured exports, several objects): saves `bytes` to
// `path` atomically, or fails as the writers do: the encoder's error as "PATH: " + its message, or the save's.
std::expected<void, Diagnostics> saveEncodedMesh(const std::expected<std::vector<uint8_t>, Diagnostics>& bytes,
                                                 const std::string& path);

// An encoded image a textured mesh's layers name (mesh.layerImages index a list of these): PNG or JPEG bytes.
struct MeshImage {
  std::string name;      // file name for OBJ's .mtl and the glTF image's name, e.g. "skin.png"
  std::string mimeType;  // "image/png" or "image/jpeg"
  std::vector<uint8_t> bytes;
};

// Textured glTF 2.0 binary (issue 11): the mesh cut by splitByTexture (texturing.h) into one triangle primitive per
// image, each with its own POSITION, NORMAL, COLOR_0 and (textured parts) TEXCOORD_0 (glTF's v = 1 - ours), and a
// material whose pbrMetallicRoughness.baseColorTexture is the image, embedded in the BIN chunk (one image per
// texture, no atlas; sampler REPEAT, trilinear). COLOR_0 multiplies the texture as the renderers modulate the
// colour. The untextured part gets a plain material. An untextured mesh, or no images, gives encodeGlb(mesh).
// Fails like encodeGlb, and when a layer names an image outside `images`; writeTexturedGlb as writeMesh does.
std::expected<std::vector<uint8_t>, Diagnostics> encodeTexturedGlb(const Mesh& mesh,
                                                                   const std::vector<MeshImage>& images);
std::expected<void, Diagnostics> writeTexturedGlb(const Mesh& mesh, const std::vector<MeshImage>& images,
                                                  const std::string& path);

// Textured Wavefront OBJ: the OBJ text (`v`, `vt` u v, `vn`, `usemtl`, `f a/a/a …`, one group per splitByTexture
// part, `mtllib` naming `mtlName`) and the .mtl text (one `newmtl` per part; `map_Kd` the image's name for
// textured parts). The caller writes the images beside them under their names. Fails like encodeTexturedGlb.
struct TexturedObj {
  std::vector<uint8_t> obj;
  std::vector<uint8_t> mtl;
};
std::expected<TexturedObj, Diagnostics> encodeTexturedObj(const Mesh& mesh, const std::vector<MeshImage>& images,
                                                          const std::string& mtlName);

}  // namespace imps
