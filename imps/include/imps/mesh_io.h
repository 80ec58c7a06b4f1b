// Mesh export: Wavefront OBJ, binary PLY and glTF 2.0 binary (.glb), each written atomically.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imps/mesh.h"

namespace imps {

// The file formats writeMesh() knows, chosen by the path's extension (case-insensitive).
enum class MeshFormat { Obj, Ply, Glb };

// The format for `path`'s extension (".obj", ".ply", ".glb", any case), or nullopt for anything else.
std::optional<MeshFormat> meshFormatForPath(std::string_view path);

// What every writer does with a mesh:
// - The mesh must satisfy Mesh's invariants (positions, normals and colors in whole triples, normals/colors empty
//   or as long as positions, whole triangles, every index < vertexCount()) and hold only finite numbers; otherwise
//   nothing is written and *error says what is wrong.
// - Empty normals or colors are left out of the file (OBJ `v x y z` and `f a b c`, no PLY properties, no glTF
//   attribute). Colors are linear RGB clamped to [0, 1]; PLY stores them as round(255 * c).
// - Output is deterministic: the same mesh always gives the same bytes.
// - The save is atomic: the bytes go to a temporary file beside `path`, which is flushed, fsync'ed and renamed over
//   `path`. On any failure `path` is untouched, the temporary file is removed, *error (if non-null) holds
//   "path: reason" and the function returns false. Thread-safe for distinct paths.

// Writes `mesh` to `path` in the format its extension names (.obj, .ply or .glb). Any other extension is an error
// naming the supported ones.
bool writeMesh(const Mesh& mesh, const std::string& path, std::string* error);

// Wavefront OBJ text: `v x y z [r g b]`, `vn x y z`, `f a//a b//b c//c` (1-based; vertex and normal share indices).
// Numbers use the shortest form that reads back to the same float.
bool writeObj(const Mesh& mesh, const std::string& path, std::string* error);

// PLY, format binary_little_endian 1.0: vertex {float x y z, float nx ny nz, uchar red green blue},
// face {list uchar uint vertex_indices}.
bool writePly(const Mesh& mesh, const std::string& path, std::string* error);

// glTF 2.0 binary: one scene, one node, one mesh with one triangle primitive; attributes POSITION (with min/max),
// NORMAL, COLOR_0 (float VEC3) and UNSIGNED_INT indices in one buffer; asset.generator "IMPS Puppeteer". A mesh
// without triangles gives a scene with one node and no mesh (glTF forbids empty accessors).
bool writeGlb(const Mesh& mesh, const std::string& path, std::string* error);

// The bytes the writers above put in the file, for callers that store or send them elsewhere. Each returns
// std::nullopt (and sets *error) for a mesh the writers would reject.
std::optional<std::vector<uint8_t>> encodeObj(const Mesh& mesh, std::string* error);
std::optional<std::vector<uint8_t>> encodePly(const Mesh& mesh, std::string* error);
std::optional<std::vector<uint8_t>> encodeGlb(const Mesh& mesh, std::string* error);

}  // namespace imps
