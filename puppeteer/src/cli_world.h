// SPDX-License-Identifier: MIT
// VRML 97 worlds and clips on the command line: telling them from IMPS character scenes, and `puppeteer check` for
// them (docs/cli.md, docs/world-format.md).
#pragma once

#include <string>

namespace imps::app {

// Whether `path` is a VRML 97 world or clip file rather than an IMPS character scene: a .wrl/.wrz/.gz file starting
// `#VRML` whose text (decompressed) names none of the IMPS-only node types (Tesselator3MP, MarchingCubes,
// RigidTransform, Metaball, LineSeg, Ellipsoid, the blends, BlendGroup, UniformHash) as a whole word, comments
// included. A file that cannot be read is not a world (the scene reader then reports why).
bool isWorldFile(const std::string& path);

// `puppeteer check WORLD [--json]`: reads the world and its clips, prints the clips (TimeSensor, duration, loop,
// targets, each track's interpolator, field and key count) and props (Shapes: geometry, size, the Transform path),
// or the file:line:column errors. Returns kExitOk or kExitInvalidInput.
int runWorldCheck(const std::string& path, bool json);

}  // namespace imps::app
