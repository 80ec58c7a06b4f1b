// SPDX-License-Identifier: MIT
// Test-only mesh readers (binary PLY, OBJ, GLB) that read back what imps/mesh_io.h writes.
#pragma once

#include <string>

#include "imps/mesh.h"

namespace tinygltf {
class Model;
}

namespace imps::test {

// Each reader fills *mesh (replacing its contents) and returns true, or returns false with a message in *error
// (if non-null) and leaves *mesh in an unspecified state. Attributes the file lacks stay empty in the mesh.

// PLY, format binary_little_endian 1.0: a `vertex` element with scalar properties (x y z required; nx ny nz and
// red green blue (uchar, mapped to c / 255) or float r g b optional; others skipped) and a `face` element whose
// first property is a list of vertex indices; polygons with more than three corners are fanned into triangles.
bool readPly(const std::string& path, Mesh* mesh, std::string* error);

// Wavefront OBJ subset: `v x y z [r g b]`, `vn x y z`, `f` with `a`, `a/t`, `a//n` or `a/t/n` corners (negative
// indices count from the end). A corner's normal index must equal its vertex index (Mesh shares one index for
// both). Polygons are fanned into triangles; other statements are ignored.
bool readObj(const std::string& path, Mesh* mesh, std::string* error);

// glTF 2.0 binary through tinygltf (an independent parser). *warning receives tinygltf's warnings (if non-null).
// Reads the first primitive of the first mesh: POSITION, NORMAL, COLOR_0 (float VEC3/VEC4) and indices.
bool readGlb(const std::string& path, Mesh* mesh, std::string* error, std::string* warning = nullptr);

// Loads a .glb into a tinygltf model, for tests that inspect the document itself. Returns tinygltf's verdict;
// errors and warnings go to *error and *warning (if non-null).
bool loadGlbModel(const std::string& path, tinygltf::Model* model, std::string* error, std::string* warning);

}  // namespace imps::test
