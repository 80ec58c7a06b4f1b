// SPDX-License-Identifier: MIT
// A world (docs/world-format.md, "Worlds"): a VRML 97 file placing several IMPS characters with standard `Inline`
// nodes under `Transform`s, each character optionally with a keyframed clip inlined beside it, plus polygonal props
// (its own Shapes and those of inlined VRML 97 files). Each character keeps its own scene file, so the app gives
// it its own polygonizer and skeleton cache.
#pragma once

#include <expected>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/scene.h"
#include "imps/vrml_clip.h"
#include "imps/vrml_props.h"

namespace imps {

// One Transform above a character or prop: its DEF name ("" without one) and its fields as the file gives them.
struct WorldTransform {
  std::string def;
  TransformValues rest;
};

// One character of a world.
struct WorldCharacter {
  // The DEF name of its Inline, else of the nearest DEF'd Transform above it, else its scene file's stem; made
  // unique in the world by appending _2, _3, … (with a warning).
  std::string name;
  std::string scenePath;  // the Inline's url resolved against the world file's folder
  SourceLoc loc;          // the Inline's url field
  Rigid placement;        // the Transforms above the Inline (rigid: a scaling or mirroring placement is an error)
  Scene scene;
  Character character;
  // A clip inlined beside it (an Inline of a VRML 97 file with clips in the same children list, `url "jump.wrl"` or
  // `url "jump.wrl#TIMER"` for the TimeSensor TIMER), or nullopt. Its targets drive the joints of the same name.
  std::optional<Clip> clip;
  std::string clipPath;  // that file, resolved
  SourceLoc clipLoc;     // its Inline's url
  std::vector<WorldTransform> chain;  // the Transforms above the Inline, outermost first (placement = their product)
};

struct World {
  std::string fileName;
  std::vector<WorldCharacter> characters;  // in file order (depth first)
  // Every Shape of the world file and of the VRML 97 files it inlines, in world coordinates (the file's pose).
  std::vector<Prop> props;
  // The same meshes below their Transforms (propLocal[i] in the coordinates under propChains[i]); for a prop riding
  // on a character's joint (propCharacter[i] >= 0: under a Transform beside the character named after its joint
  // propJoint[i]), in that joint's frame, props[i] holding it at the character's rest pose.
  std::vector<Mesh> propLocal;
  std::vector<std::vector<WorldTransform>> propChains;
  std::vector<int> propCharacter, propJoint;
  // The world file's own clips (its TimeSensors driving its Transforms), all played from 0 s: they move the
  // characters' placements and the props under the Transforms they drive.
  std::vector<Clip> clips;

  // Where everything is `seconds` into the world's clips: each character's placement (rigid: a driven scale is
  // divided out) and each prop's mesh in world coordinates. Without clips, the file's pose. Props riding on a joint
  // are left at rest: their character's pose moves them (propLocal by the joint's world transform).
  struct Pose {
    std::vector<Rigid> placements;
    std::vector<Mesh> props;
  };
  Pose poseAt(double seconds) const;
  // The driven Transforms' fields at `seconds` (every clip sampled; a later clip wins a Transform both drive).
  std::map<std::string, TransformValues, std::less<>> transformsAt(double seconds) const;
  // The product of a chain's Transforms, those in `moved` taking its values.
  static glm::mat4 chainMatrix(const std::vector<WorldTransform>& chain,
                               const std::map<std::string, TransformValues, std::less<>>& moved);

  // The character called `name`, or -1.
  int findCharacter(std::string_view name) const;
  std::vector<std::string> characterNames() const;
};

// Whether `text` (a decompressed .wrl) names one of the node types only the IMPS character dialect has
// (Tesselator3MP, MarchingCubes, RigidTransform, Metaball, LineSeg, Ellipsoid, the blends, BlendGroup, UniformHash)
// as a whole word, comments included: such a file is an IMPS character scene rather than a VRML 97 world.
bool namesImpsNodes(std::string_view text);

// Reads the world file at `path` (readVrmlFile) and every file its Inlines name (url strings resolved against the
// world's folder; the first url that exists is used, `#NAME` picks a clip). An inlined file is an IMPS character when
// namesImpsNodes says so (read and compiled: its own errors keep their file:line:column), else a VRML 97 file whose
// Shapes are props placed where the Inline is and whose clips drive the character inlined beside it.
//
// Errors, `file:line:column: error: …` at the world's Inline (or the inlined file's own diagnostics): a url that names
// no readable file, an inlined file that is neither an IMPS scene nor VRML 97, a character under a scaling or
// mirroring Transform, two characters in one children list, a `#NAME` naming no clip, an inlined world that inlines
// further files (not followed). Warnings: a clip Inline with no character beside it (its Shapes are still props), a
// world without characters, renamed duplicate names, and the readers' warnings. Thread-safe.
std::expected<World, Diagnostics> readWorldFile(const std::string& path, Diagnostics* warnings = nullptr);

}  // namespace imps
