// SPDX-License-Identifier: MIT
// Several named meshes in one file (a world's characters and props): each object its own node in glTF, its own
// `o` object in OBJ; PLY, which has no objects, gets them merged.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

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
// (vertex colours are). Every mesh must satisfy Mesh's invariants with finite numbers, else nullopt and *error names
// the object. Deterministic.
std::optional<std::vector<uint8_t>> encodeGlbObjects(std::span<const NamedMesh> objects, std::string* error);

// Wavefront OBJ text: per object `o NAME` (white space in names replaced by '_'), then its `v x y z [r g b]`,
// `vn` and `f a//a …` lines with indices running on through the file (1-based).
std::optional<std::vector<uint8_t>> encodeObjObjects(std::span<const NamedMesh> objects, std::string* error);

// Writes the objects to `path` by its extension: .glb and .obj as above, .ply as one merged mesh (writePly). Atomic
// like writeMesh (imps/mesh_io.h); false and *error "path: reason" on failure.
bool writeMeshObjects(std::span<const NamedMesh> objects, const std::string& path, std::string* error);

}  // namespace imps
