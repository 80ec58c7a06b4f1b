// SPDX-License-Identifier: MIT
// The scene document: what an IMPS scene file says, node for node (thesis appendix A; docs/scene-format.md).
//
// This is a faithful, typed image of the file, not the evaluable character: `Character::fromScene` (character.h)
// turns it into joints, primitives and a blend graph. Reading then writing then reading a file gives an equal
// Scene (operator== compares every field, names and USE references included, but not source locations).
// Units: metres and radians. Colours are linear RGB in [0, 1].
#pragma once

#include <cstdint>

#include <glm/vec3.hpp>

#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "imps/diagnostic.h"

namespace imps {

// VRML SFRotation: a rotation of `angle` radians about `axis` (need not be unit length in the file; a zero axis
// with a zero angle is the identity).
struct Rotation {
  glm::vec3 axis{0.0f, 0.0f, 1.0f};
  float angle = 0.0f;
  bool operator==(const Rotation&) const = default;
};

// VRML 2 Material; IMPS uses diffuseColor for the surface colour and keeps the rest for the renderer.
struct Material {
  std::string name;  // DEF name, or empty
  glm::vec3 diffuseColor{0.8f, 0.8f, 0.8f};
  glm::vec3 emissiveColor{0.0f, 0.0f, 0.0f};
  glm::vec3 specularColor{0.0f, 0.0f, 0.0f};
  float ambientIntensity = 0.2f;
  float shininess = 0.2f;
  float transparency = 0.0f;
  std::string useOf;  // when this node was written `USE NAME`: NAME (the fields are the DEF'd node's)
  SourceLoc loc;      // not compared
  bool operator==(const Material& o) const;
};

// A texture-coordinate generator (thesis 3.9: ImTexGenSphere, ImTexGenPlane): `TexGenSphere` or `TexGenPlane`.
// Its frame is centred on its primitive (a Metaball's or Ellipsoid's center, a LineSeg's midpoint) and axis-aligned
// with the primitive's joint, then moved by `translation` and turned by `rotation` (both in the joint's frame); it
// follows the primitive through the skeleton cache. The mappings are imps/texgen.h's.
enum class TexGenKind { Sphere, Plane };
struct TexGenNode {
  TexGenKind kind = TexGenKind::Sphere;
  glm::vec3 translation{0.0f, 0.0f, 0.0f};
  Rotation rotation;
  // TexGenPlane: the projected slide's size in metres along the generator's local x (u) and y (v); each > 0.
  float width = 2.0f;
  float height = 2.0f;
  SourceLoc loc;  // not compared
  bool operator==(const TexGenNode& o) const;
};

// VRML 2 `ImageTexture { url "file.png" }`: an image (PNG, JPEG, EXR, ...) whose path is relative to the scene
// file's directory (or absolute). Exactly one url.
struct ImageTextureNode {
  std::string url;
  SourceLoc loc;  // of the url string; not compared
  bool operator==(const ImageTextureNode& o) const { return url == o.url; }
};

enum class ShapeKind { Metaball, Ellipsoid, LineSeg };

// An implicit primitive: `Metaball`, `Ellipsoid` or `LineSeg` node. Only the fields of its kind are meaningful;
// the others keep their defaults (and are neither written nor compared).
struct ShapeNode {
  ShapeKind kind = ShapeKind::Metaball;
  std::string name;  // DEF name, or empty
  // Metaball: center, radius (> 0).
  glm::vec3 center{0.0f, 0.0f, 0.0f};
  float radius = 1.0f;
  // Ellipsoid: center, orientation (rotation from the ellipsoid's local axes to its parent's), radii (the three
  // semi-axis lengths a, b, c along local x, y, z; each > 0).
  Rotation orientation;
  glm::vec3 radii{1.0f, 1.0f, 1.0f};
  // LineSeg: endpoints point1/point2 with radii radius1/radius2 (each > 0). Equal endpoints make a metaball.
  glm::vec3 point1{0.0f, 0.0f, 0.0f};
  glm::vec3 point2{0.0f, 1.0f, 0.0f};
  float radius1 = 1.0f;
  float radius2 = 1.0f;
  // Per-primitive blend parameter (thesis: ImShape's blendParam): blobbiness B < 0 for ExponentialBlend,
  // hardness > 0 for BlancSchlickBlend, blend range > 0 for EllipticalBlend. Unset: the blend's default.
  std::optional<float> blendParam;
  std::optional<Material> material;
  // Texturing (thesis 3.9; docs/scene-format.md): the image that modulates the surface colour near this primitive,
  // and the generator of its texture coordinates. A texture without texGen uses a TexGenSphere with the defaults.
  std::optional<TexGenNode> texGen;
  std::optional<ImageTextureNode> texture;
  std::string useOf;  // see Material::useOf
  SourceLoc loc;      // not compared
  bool operator==(const ShapeNode& o) const;
};

enum class BlendKind { Exponential, BlancSchlick, Elliptical };
// The node type that spells a blend kind in a file: "ExponentialBlend", "BlancSchlickBlend", "EllipticalBlend".
const char* blendTypeName(BlendKind kind);

// A blending function node: `ExponentialBlend`, `BlancSchlickBlend` or `EllipticalBlend`. As the
// `blendingFunction` of a polygonizer it carries no children; as the root of a flat scene graph it holds the
// primitives (and RigidTransforms) that all blend together.
struct BlendNode;
struct TransformNode;
using SceneNode = std::variant<ShapeNode, TransformNode, BlendNode>;

struct BlendNode {
  BlendKind kind = BlendKind::Exponential;
  std::string name;
  // ExponentialBlend: `variance` v > 0 sets the default blobbiness B = -1/v (thesis eq. 2.1-2.3 with r = 1);
  // `fastExp` TRUE uses Schraudolph's fast exponential approximation instead of std::exp.
  float variance = 1.0f;
  bool fastExp = false;
  // BlancSchlickBlend: default `hardness` > 0 (support ends at normalised squared distance 1 + 1/hardness).
  float hardness = 1.0f;
  // EllipticalBlend: default `blendRange` > 0, in units of the primitives' normalised field 1 - d.
  float blendRange = 0.5f;
  std::vector<SceneNode> children;
  std::string useOf;
  SourceLoc loc;
  bool operator==(const BlendNode& o) const;
};

// `RigidTransform`: rotation then translation (no scale), the thesis's only transform. Every RigidTransform is a
// joint of the character; its DEF name is the joint's name.
struct TransformNode {
  std::string name;
  glm::vec3 translation{0.0f, 0.0f, 0.0f};
  Rotation rotation;
  std::vector<SceneNode> children;
  std::string useOf;
  SourceLoc loc;
  bool operator==(const TransformNode& o) const;
};

// `UniformHash`: Heckbert's spatial hash for particle neighbour queries (thesis 3.7).
struct UniformHash {
  float cubeSize = 0.6f;
  int bitsPerDim = 3;
  bool operator==(const UniformHash&) const = default;
};

// How the particle tesselator's mesh gets its texture coordinates (`textureMode`, ours; docs/scene-format.md):
// Projective: every vertex takes its layers' generators' mapping of its position (thesis 3.9; the texture slides
// over the skin as blends change). Carried: each particle carries its coordinates through the differential transforms
// and its own motion over the surface, so the texture stretches with the skin (Tesselator::carryTexcoords). Marching
// Cubes is always projective.
enum class TextureMode : uint8_t { Projective, Carried };

// `Tesselator3MP`: the particle polygonizer, every field of thesis figure A-1 plus `seed` and `textureMode`.
struct Tesselator3MPNode {
  float deltaT = 0.045f;
  float desiredRadius = 0.3f;
  float queryRadius = 0.8f;
  float energyCoeff = 10.0f;
  float surfaceCoeff = 30.0f;
  float fissioningFrac = 0.5f;
  float isoValue = 1.0f;
  bool useSimpleRadii = true;
  int numThreads = 1;
  int updatesPerRender = 1;
  float colorWidth = 3.0f;
  bool doDifferentialTransforms = true;
  int seed = 1;  // ours: fixed seed for deterministic runs
  TextureMode textureMode = TextureMode::Projective;  // ours
  std::optional<BlendNode> blendingFunction;
  UniformHash spatialSubdivision;
  std::optional<SceneNode> sceneGraph;
  SourceLoc desiredRadiusLoc;  // where desiredRadius was given (unset: the default); not compared
  bool operator==(const Tesselator3MPNode& o) const;
};

// `MarchingCubes`: the grid polygonizer. Resolution is either `cellSize` (metres, > 0) or the thesis's
// `xResolution yResolution zResolution` (cells along each axis of the scene's bounds); 0 means unset. With neither,
// the command line or the default cell applies.
struct MarchingCubesNode {
  float cellSize = 0.0f;
  int xResolution = 0;
  int yResolution = 0;
  int zResolution = 0;
  float isoValue = 1.0f;
  int numThreads = 0;  // 0: all cores
  std::optional<BlendNode> blendingFunction;
  std::optional<SceneNode> sceneGraph;
  SourceLoc resolutionLoc;  // where cellSize or x/y/zResolution was last given (unset: neither); not compared
  bool operator==(const MarchingCubesNode& o) const;
};

// `BlendGroup { members [ "A" "B" … ] blend TRUE }` (top level, ours): overrides the hierarchy's blending rule.
// Members are DEF names of primitives or of RigidTransforms (standing for the primitives directly under them).
// With `blend TRUE` every pair of members blends; with `blend FALSE` no pair does. Later groups win.
struct BlendGroupNode {
  std::vector<std::string> members;
  bool blend = true;
  SourceLoc loc;
  bool operator==(const BlendGroupNode& o) const { return members == o.members && blend == o.blend; }
};

// A whole file: at most one polygonizer node or bare scene graph root, plus any BlendGroups.
struct Scene {
  std::variant<std::monostate, Tesselator3MPNode, MarchingCubesNode> polygonizer;
  std::optional<SceneNode> root;  // used only when polygonizer is monostate (a bare RigidTransform or blend root)
  std::vector<BlendGroupNode> blendGroups;
  std::string fileName;  // not compared

  // The scene graph, wherever it lives (polygonizer's sceneGraph or the bare root); null when there is none.
  const SceneNode* sceneGraph() const;
  SceneNode* sceneGraph();
  // The polygonizer's blendingFunction, if it has one.
  const BlendNode* blendingFunction() const;

  bool operator==(const Scene& o) const;
};

}  // namespace imps
