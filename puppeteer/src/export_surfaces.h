// SPDX-License-Identifier: MIT
// A take baked into the implicit skin itself, every frame: numbered PLY (or OBJ) files, one mesh per frame with
// vertex colours. Numbered files because Houdini ($F), Blender (Stop-motion-OBJ, Mesh Sequence Cache via a script)
// and every DCC read them with no plug-in, and because Marching Cubes and the tesselator change the vertex count
// every frame, which glTF morph targets and point caches cannot hold.
#pragma once

#include <expected>
#include <functional>
#include <string>

#include "export_take.h"
#include "imps/diagnostic.h"
#include "imps/scene.h"

namespace imps::app {

struct SurfaceSequenceOptions {
  float cellSize = 0.02f;    // Marching Cubes cell, metres
  bool particles = false;    // the particle tesselator (the scene's settings) instead of Marching Cubes
  std::function<void(size_t framesDone)> progress;  // called after every frame
};

// The file for frame `frame` of `pattern` ("take_####.ply": the run of '#' becomes the zero-padded frame number).
std::string sequenceFileName(const std::string& pattern, size_t frame);

// Writes one mesh per frame of `take` (files named by sequenceFileName, each written atomically; the pattern's
// folder is created when missing). With particles the
// tesselator settles on the first frame, then runs the scene's updates per render between frames. Fails (files
// already written stay) as imps::writeMesh does, one error without a location naming the file, or
// "FOLDER: cannot create the folder: REASON".
std::expected<void, Diagnostics> writeSurfaceSequence(const Scene& scene, const Character& character, const Take& take,
                                                      const SurfaceSequenceOptions& options,
                                                      const std::string& pattern);

}  // namespace imps::app
