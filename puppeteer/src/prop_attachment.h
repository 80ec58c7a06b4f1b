// Polygonal props (imps/vrml_props.h) in a character's world: loaded from `--prop FILE.wrl[@JOINT]`, a prop on a
// joint following the joint's posed world transform (Beanito's hat), others staying where the file puts them.
#pragma once

#include <expected>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/mesh.h"
#include "imps/skeleton_cache.h"

namespace imps::app {

struct AttachedProp {
  std::string name;  // the prop's name in its file
  Mesh mesh;         // in the joint's frame (the world's when joint < 0)
  int joint = -1;
};

// Reads every `FILE.wrl[@JOINT]` spec: all the Shapes of FILE, attached to JOINT when given. Errors are whole
// messages: the file's `file:line:column` errors, or "--prop SPEC: the scene has no joint 'X'". Warnings (skipped
// nodes, bad faces) are appended to `warnings`.
std::expected<std::vector<AttachedProp>, std::string> loadProps(const std::vector<std::string>& specs,
                                                                const Character& character, std::string* warnings);

// Appends every prop to `mesh`, posed by the skeleton cache's current world transforms (call update() first).
void appendPosedProps(Mesh& mesh, const std::vector<AttachedProp>& props, const SkeletonCache& skeleton);

}  // namespace imps::app
