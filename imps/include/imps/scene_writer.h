// SPDX-License-Identifier: MIT
// Writing an imps::Scene as an IMPS scene file (docs/scene-format.md), in one canonical layout.
#pragma once

#include <string>

#include "imps/io_error.h"
#include "imps/scene.h"

namespace imps {

// The scene as text: `#VRML V2.0 utf8`, a blank line, the polygonizer or scene graph root, then the BlendGroups,
// two-space indented. Shapes, blends, RigidTransforms, UniformHash and polygonizer nodes are written with every
// field of their kind (MarchingCubes' cellSize only when set, i.e. not 0); a Material with diffuseColor and the
// fields that differ from the VRML defaults; optional nodes and blendParam only when present. Floats use the
// shortest form that reads back to the same float, so readScene(writeScene(s)) == s for every scene readScene
// returns, and writeScene is a fixed point: writeScene(read(writeScene(s))) == writeScene(s) byte for byte.
//
// A node with a non-empty `useOf` is written `USE NAME` (its fields are not written); one with a `name` is written
// `DEF NAME Type { ... }`. The scene must make sense as a file for the output to read back: names must be
// identifiers, each `useOf` must name a node DEF'd earlier in writing order, and values must pass readScene's
// checks. Pure function; thread-safe.
std::string writeScene(const Scene& scene);

// Saves writeScene(scene) to `path` without ever leaving a partly written file there: writes a temporary file in
// the same directory, flushes and fsyncs it, then renames it over `path` (an existing file keeps its permissions).
// On failure leaves `path` as it was, removes the temporary file and returns atomic_file.h's IoError (message
// "cannot save 'PATH': STEP: REASON").
IoResult<void> saveSceneFile(const Scene& scene, const std::string& path);

}  // namespace imps
