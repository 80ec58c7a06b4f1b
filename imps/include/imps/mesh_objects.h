// SPDX-License-Identifier: MIT
// Several named meshes in one file (a world's characters and props): each object its own node in glTF, its own
// `o` object in OBJ; PLY, which has no objects, gets them merged.
#pragma once

#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <vector>

#include "imps/diagnostic.h"
#include "imps/mesh.h"

namespace imps {

// One object of a file. The mesh is not owned and must outlive the call.
struct NamedMesh {
  std::string name;
  const Mesh* mesh = nullptr;
};

// glTF 2.0 binary: one scene whose root nodes are the objects, in order, each node named and holding its own mesh
// (one triangle primitive: POSITION with min/max, NORMAL and COLOR_0 when the mesh has them, UNSIGNED_INT indices)
// in one shared buffer; an object without triangles is a node without a mesh. Texture layers are not written
// (vertex colours are). Every mesh must satisfy Mesh's invariants with finite numbers, else one error (without a
// location) names the object. Deterministic.
std::expected<std::vector<uint8_t>, Diagnostics> encodeGlbObjects(std::span<const NamedMesh> objects);

// Wavefront OBJ text: per object `o NAME` (white space in names replaced by '_'), then its `v x y z [r g b]`,
// `vn` and `f a//a …` lines with indices running on through the file (1-based).
std::expected<std::vector<uint8_t>, Diagnostics> encodeObjObjects(std::span<const NamedMesh> objects);

// Writes the objects to `path` by its extension: .glb and .obj as above, .ply as one merged mesh (writePly). Atomic
// like writeMesh (imps/mesh_io.h), and fails as it does ("PATH: reason", or the save's "cannot save 'PATH': ...").
std::expected<void, Diagnostics> writeMeshObjects(std::span<const NamedMesh> objects, const std::string& path);

}  // namespace imps
