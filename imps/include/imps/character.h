// SPDX-License-Identifier: MIT
// A character: the scene graph compiled into joints, joint-local primitives and the blend graph.
//
// Joints are the scene's RigidTransforms, addressed by DEF name (unnamed ones get "joint<N>"). Each primitive belongs
// to the joint whose RigidTransform directly contains it (or to no joint, -1, at the root of a flat scene).
// The unwanted-blending rule (thesis 3.7, figure 3-1): a primitive blends with its siblings (same joint), its parent
// (primitives of the nearest ancestor joint that holds primitives) and its children (primitives of joints whose
// nearest primitive-holding ancestor is its joint) — never with a grandparent or grandchild. BlendGroup nodes then
// add (blend TRUE) or remove (blend FALSE) pairs, later groups winning. A flat scene (blend node at the root) blends
// everything with everything. Two primitives blend only if they are neighbours in this graph: the field's blend
// sets are its maximal cliques (blend_graph.h).
#pragma once

#include <expected>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include "imps/blend_graph.h"
#include "imps/diagnostic.h"
#include "imps/field.h"
#include "imps/primitives.h"
#include "imps/scene.h"
#include "imps/texgen.h"

namespace imps {

// A rigid transform: x -> rotation * x + translation.
struct Rigid {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 translation{0.0f};
  glm::vec3 apply(const glm::vec3& x) const { return rotation * x + translation; }
  Rigid operator*(const Rigid& b) const { return {rotation * b.rotation, rotation * b.translation + translation}; }
  Rigid inverse() const {
    const glm::quat inv = glm::conjugate(rotation);
    return {inv, -(inv * translation)};
  }
};

// Converts a VRML axis-angle rotation to a unit quaternion (identity for a zero axis).
glm::quat toQuat(const Rotation& r);

struct Joint {
  std::string name;
  int parent = -1;  // index of the parent joint, -1 for a root
  Rigid rest;       // the file's translation and rotation, relative to the parent
};

struct CharacterPrimitive {
  std::string name;  // DEF name or "<kind><N>"
  int joint = -1;    // owning joint, -1 for none
  Primitive local;   // in the joint's frame (world frame when joint == -1)
  float blendParam = 0.0f;
  glm::vec3 color{0.8f};
  // Texturing (thesis 3.9): the primitive's texture-coordinate generator in the joint's frame (set when the shape
  // has a texGen or a texture; a texture alone gets a default TexGenSphere), and its image, an index into
  // Character::textures() (-1: none, the surface keeps its colour).
  std::optional<TexGen> texGen;
  int texture = -1;
};

// An image a primitive's ImageTexture names: the url as written, and the path to read (relative urls resolved
// against the scene file's directory). Primitives naming the same path share one entry.
struct CharacterTexture {
  std::string url;
  std::string path;
  SourceLoc loc;  // the url in the scene file
};

// The joint-local generator of a shape's TexGenSphere / TexGenPlane: centred on the shape (a LineSeg's midpoint),
// moved by its translation and turned by its rotation, in the joint's frame.
TexGen texGenOf(const ShapeNode& shape, const TexGenNode& node);

class Character {
 public:
  // Compiles a scene. Errors (with the scene's source locations): no scene graph, no primitives, a nested blend
  // node of another type than the character's blend function, a blendParam of the wrong sign for the blend in
  // force. A blend node inside the graph gives its parameters to the shapes it wraps (their default blendParam).
  static std::expected<Character, Diagnostics> fromScene(const Scene& scene);

  const std::vector<Joint>& joints() const { return joints_; }
  const std::vector<CharacterPrimitive>& primitives() const { return primitives_; }
  const std::vector<CharacterTexture>& textures() const { return textures_; }
  // Whether any primitive has a texture-coordinate generator (texGen or texture).
  bool textured() const { return textured_; }
  const BlendFunction& blend() const { return blend_; }
  float iso() const { return iso_; }  // the iso-value, as Field::iso()
  bool hierarchical() const { return hierarchical_; }
  // Index of the joint with this name, or -1.
  int findJoint(std::string_view name) const;
  // Whether primitives a and b (a != b) are blend neighbours. Constant time.
  bool blends(size_t a, size_t b) const { return graph_.blends(graph_.classOf(a), graph_.classOf(b)); }
  // Primitives that primitive i blends with (ascending, excluding i).
  std::vector<uint32_t> blendNeighbours(size_t i) const { return graph_.neighbours(i); }
  const BlendGraph& blendGraph() const { return graph_; }
  // The sets the field takes its maximum over (field.h): the maximal cliques of the blend graph; one set of
  // everything when everything blends.
  const BlendSets& blendSets() const { return sets_; }

 private:
  std::vector<Joint> joints_;
  std::vector<CharacterPrimitive> primitives_;
  std::vector<CharacterTexture> textures_;
  BlendGraph graph_{{}, 0};
  BlendSets sets_;
  BlendFunction blend_;
  float iso_ = 1.0f;
  bool hierarchical_ = false;
  bool textured_ = false;
  friend class CharacterBuilder;
};

}  // namespace imps
