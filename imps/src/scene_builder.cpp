// SPDX-License-Identifier: MIT
// SceneBuilder: IMPS node types, their fields and the checks on them, filling an imps::Scene from parser events.
#include "scene_builder.h"

#include <array>
#include <charconv>
#include <cmath>
#include <glm/geometric.hpp>
#include <limits>
#include <optional>
#include <utility>

#include "imps/parallel.h"

namespace imps::vrml {

namespace {

enum class NodeType {
  Tesselator3MP,
  MarchingCubes,
  ExponentialBlend,
  BlancSchlickBlend,
  EllipticalBlend,
  UniformHash,
  RigidTransform,
  Metaball,
  Ellipsoid,
  LineSeg,
  Material,
  BlendGroup,
  TexGenSphere,
  TexGenPlane,
  ImageTexture,
};

constexpr std::array<const char*, 15> kNodeTypeNames = {
    "Tesselator3MP", "MarchingCubes", "ExponentialBlend", "BlancSchlickBlend", "EllipticalBlend", "UniformHash",
    "RigidTransform", "Metaball", "Ellipsoid", "LineSeg", "Material", "BlendGroup", "TexGenSphere", "TexGenPlane",
    "ImageTexture"};

// What a node-valued field accepts, as a mask of node classes.
enum NodeClass : unsigned {
  kShapeClass = 1u << 0,
  kTransformClass = 1u << 1,
  kBlendClass = 1u << 2,
  kMaterialClass = 1u << 3,
  kHashClass = 1u << 4,
  kPolygonizerClass = 1u << 5,
  kBlendGroupClass = 1u << 6,
  kTexGenClass = 1u << 7,
  kTextureClass = 1u << 8,
  kSceneGraphClasses = kShapeClass | kTransformClass | kBlendClass,
};

enum class FieldType { Bool, Int, Float, Vec3, Color, Rotation, Strings, Node, Nodes };
enum class Constraint {
  None, Positive, NonNegative, AtLeastOne, BitsPerDim, UnitInterval, Threads, Resolution,
  OneString,  // Strings: exactly one, not empty
  TextureModeName,  // Strings: exactly one of "projective", "carried"
};

// Bounds on sizes a scene asks for (the command line's --threads and --res take the same ranges; kMaxThreads is
// imps/parallel.h's).
constexpr int kMaxResolution = 4096;

// A field's value once its type is checked.
struct Value {
  bool b = false;
  int i = 0;
  float f = 0.0f;
  glm::vec3 v{0.0f};
  Rotation r;
  std::vector<std::string> strings;
};

using NodeData = SceneBuilder::NodeData;
using Setter = void (*)(NodeData&, const Value&);

}  // namespace

struct SceneBuilder::FieldSpec {
  const char* name;
  FieldType type;
  Constraint constraint = Constraint::None;
  Setter set = nullptr;     // scalar fields
  unsigned accepts = 0;          // node fields: NodeClass mask
  const char* acceptsText = "";  // node fields: what the field takes, for messages
};

namespace {

using FieldSpec = SceneBuilder::FieldSpec;

#define IMPS_SET(Type, member, part) [](NodeData& n, const Value& x) { std::get<Type>(n).member = x.part; }

const char* const kSceneGraphText = "a shape, RigidTransform or blend node";
const char* const kBlendText = "a blend node (ExponentialBlend, BlancSchlickBlend or EllipticalBlend)";

const std::vector<FieldSpec> kTesselatorFields = {
    {"deltaT", FieldType::Float, Constraint::Positive, IMPS_SET(Tesselator3MPNode, deltaT, f), 0, ""},
    {"desiredRadius", FieldType::Float, Constraint::Positive, IMPS_SET(Tesselator3MPNode, desiredRadius, f), 0, ""},
    {"queryRadius", FieldType::Float, Constraint::None, IMPS_SET(Tesselator3MPNode, queryRadius, f), 0, ""},
    {"energyCoeff", FieldType::Float, Constraint::None, IMPS_SET(Tesselator3MPNode, energyCoeff, f), 0, ""},
    {"surfaceCoeff", FieldType::Float, Constraint::None, IMPS_SET(Tesselator3MPNode, surfaceCoeff, f), 0, ""},
    {"fissioningFrac", FieldType::Float, Constraint::None, IMPS_SET(Tesselator3MPNode, fissioningFrac, f), 0, ""},
    {"isoValue", FieldType::Float, Constraint::Positive, IMPS_SET(Tesselator3MPNode, isoValue, f), 0, ""},
    {"useSimpleRadii", FieldType::Bool, Constraint::None, IMPS_SET(Tesselator3MPNode, useSimpleRadii, b), 0, ""},
    {"numThreads", FieldType::Int, Constraint::Threads, IMPS_SET(Tesselator3MPNode, numThreads, i), 0, ""},
    {"updatesPerRender", FieldType::Int, Constraint::AtLeastOne, IMPS_SET(Tesselator3MPNode, updatesPerRender, i),
     0, ""},
    {"colorWidth", FieldType::Float, Constraint::None, IMPS_SET(Tesselator3MPNode, colorWidth, f), 0, ""},
    {"doDifferentialTransforms", FieldType::Bool, Constraint::None,
     IMPS_SET(Tesselator3MPNode, doDifferentialTransforms, b), 0, ""},
    {"seed", FieldType::Int, Constraint::None, IMPS_SET(Tesselator3MPNode, seed, i), 0, ""},
    {"textureMode", FieldType::Strings, Constraint::TextureModeName,
     [](NodeData& n, const Value& x) {
       std::get<Tesselator3MPNode>(n).textureMode =
           x.strings.front() == "carried" ? TextureMode::Carried : TextureMode::Projective;
     },
     0, ""},
    {"blendingFunction", FieldType::Node, Constraint::None, nullptr, kBlendClass, kBlendText},
    {"spatialSubdivision", FieldType::Node, Constraint::None, nullptr, kHashClass, "a UniformHash"},
    {"sceneGraph", FieldType::Node, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const std::vector<FieldSpec> kMarchingCubesFields = {
    {"cellSize", FieldType::Float, Constraint::Positive, IMPS_SET(MarchingCubesNode, cellSize, f), 0, ""},
    {"xResolution", FieldType::Int, Constraint::Resolution, IMPS_SET(MarchingCubesNode, xResolution, i), 0, ""},
    {"yResolution", FieldType::Int, Constraint::Resolution, IMPS_SET(MarchingCubesNode, yResolution, i), 0, ""},
    {"zResolution", FieldType::Int, Constraint::Resolution, IMPS_SET(MarchingCubesNode, zResolution, i), 0, ""},
    {"isoValue", FieldType::Float, Constraint::Positive, IMPS_SET(MarchingCubesNode, isoValue, f), 0, ""},
    {"numThreads", FieldType::Int, Constraint::Threads, IMPS_SET(MarchingCubesNode, numThreads, i), 0, ""},
    {"blendingFunction", FieldType::Node, Constraint::None, nullptr, kBlendClass, kBlendText},
    {"sceneGraph", FieldType::Node, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const std::vector<FieldSpec> kExponentialFields = {
    {"variance", FieldType::Float, Constraint::Positive, IMPS_SET(BlendNode, variance, f), 0, ""},
    {"fastExp", FieldType::Bool, Constraint::None, IMPS_SET(BlendNode, fastExp, b), 0, ""},
    {"children", FieldType::Nodes, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const std::vector<FieldSpec> kBlancSchlickFields = {
    {"hardness", FieldType::Float, Constraint::Positive, IMPS_SET(BlendNode, hardness, f), 0, ""},
    {"children", FieldType::Nodes, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const std::vector<FieldSpec> kEllipticalFields = {
    {"blendRange", FieldType::Float, Constraint::Positive, IMPS_SET(BlendNode, blendRange, f), 0, ""},
    {"children", FieldType::Nodes, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const std::vector<FieldSpec> kUniformHashFields = {
    {"cubeSize", FieldType::Float, Constraint::Positive, IMPS_SET(UniformHash, cubeSize, f), 0, ""},
    {"bitsPerDim", FieldType::Int, Constraint::BitsPerDim, IMPS_SET(UniformHash, bitsPerDim, i), 0, ""},
};

const std::vector<FieldSpec> kRigidTransformFields = {
    {"translation", FieldType::Vec3, Constraint::None, IMPS_SET(TransformNode, translation, v), 0, ""},
    {"rotation", FieldType::Rotation, Constraint::None, IMPS_SET(TransformNode, rotation, r), 0, ""},
    {"children", FieldType::Nodes, Constraint::None, nullptr, kSceneGraphClasses, kSceneGraphText},
};

const FieldSpec kBlendParamField = {"blendParam", FieldType::Float, Constraint::None,
                                    [](NodeData& n, const Value& x) { std::get<ShapeNode>(n).blendParam = x.f; }, 0,
                                    ""};
const FieldSpec kMaterialField = {"material", FieldType::Node, Constraint::None, nullptr, kMaterialClass,
                                  "a Material"};

const FieldSpec kTexGenField = {"texGen", FieldType::Node, Constraint::None, nullptr, kTexGenClass,
                                "a TexGenSphere or TexGenPlane"};
const FieldSpec kTextureField = {"texture", FieldType::Node, Constraint::None, nullptr, kTextureClass,
                                 "an ImageTexture"};

const std::vector<FieldSpec> kMetaballFields = {
    {"center", FieldType::Vec3, Constraint::None, IMPS_SET(ShapeNode, center, v), 0, ""},
    {"radius", FieldType::Float, Constraint::Positive, IMPS_SET(ShapeNode, radius, f), 0, ""},
    kBlendParamField,
    kMaterialField,
    kTexGenField,
    kTextureField,
};

const std::vector<FieldSpec> kEllipsoidFields = {
    {"center", FieldType::Vec3, Constraint::None, IMPS_SET(ShapeNode, center, v), 0, ""},
    {"orientation", FieldType::Rotation, Constraint::None, IMPS_SET(ShapeNode, orientation, r), 0, ""},
    {"radii", FieldType::Vec3, Constraint::Positive, IMPS_SET(ShapeNode, radii, v), 0, ""},
    kBlendParamField,
    kMaterialField,
    kTexGenField,
    kTextureField,
};

const std::vector<FieldSpec> kLineSegFields = {
    {"point1", FieldType::Vec3, Constraint::None, IMPS_SET(ShapeNode, point1, v), 0, ""},
    {"point2", FieldType::Vec3, Constraint::None, IMPS_SET(ShapeNode, point2, v), 0, ""},
    {"radius1", FieldType::Float, Constraint::Positive, IMPS_SET(ShapeNode, radius1, f), 0, ""},
    {"radius2", FieldType::Float, Constraint::Positive, IMPS_SET(ShapeNode, radius2, f), 0, ""},
    kBlendParamField,
    kMaterialField,
    kTexGenField,
    kTextureField,
};

const std::vector<FieldSpec> kTexGenSphereFields = {
    {"translation", FieldType::Vec3, Constraint::None, IMPS_SET(TexGenNode, translation, v), 0, ""},
    {"rotation", FieldType::Rotation, Constraint::None, IMPS_SET(TexGenNode, rotation, r), 0, ""},
};

const std::vector<FieldSpec> kTexGenPlaneFields = {
    {"translation", FieldType::Vec3, Constraint::None, IMPS_SET(TexGenNode, translation, v), 0, ""},
    {"rotation", FieldType::Rotation, Constraint::None, IMPS_SET(TexGenNode, rotation, r), 0, ""},
    {"width", FieldType::Float, Constraint::Positive, IMPS_SET(TexGenNode, width, f), 0, ""},
    {"height", FieldType::Float, Constraint::Positive, IMPS_SET(TexGenNode, height, f), 0, ""},
};

const std::vector<FieldSpec> kImageTextureFields = {
    {"url", FieldType::Strings, Constraint::OneString,
     [](NodeData& n, const Value& x) { std::get<ImageTextureNode>(n).url = x.strings.front(); }, 0, ""},
};

const std::vector<FieldSpec> kMaterialFields = {
    {"diffuseColor", FieldType::Color, Constraint::UnitInterval, IMPS_SET(Material, diffuseColor, v), 0, ""},
    {"emissiveColor", FieldType::Color, Constraint::UnitInterval, IMPS_SET(Material, emissiveColor, v), 0, ""},
    {"specularColor", FieldType::Color, Constraint::UnitInterval, IMPS_SET(Material, specularColor, v), 0, ""},
    {"ambientIntensity", FieldType::Float, Constraint::UnitInterval, IMPS_SET(Material, ambientIntensity, f), 0, ""},
    {"shininess", FieldType::Float, Constraint::UnitInterval, IMPS_SET(Material, shininess, f), 0, ""},
    {"transparency", FieldType::Float, Constraint::UnitInterval, IMPS_SET(Material, transparency, f), 0, ""},
};

const std::vector<FieldSpec> kBlendGroupFields = {
    {"members", FieldType::Strings, Constraint::None, IMPS_SET(BlendGroupNode, members, strings), 0, ""},
    {"blend", FieldType::Bool, Constraint::None, IMPS_SET(BlendGroupNode, blend, b), 0, ""},
};

#undef IMPS_SET

const std::vector<FieldSpec>& fieldsOf(NodeType type) {
  switch (type) {
    case NodeType::Tesselator3MP: return kTesselatorFields;
    case NodeType::MarchingCubes: return kMarchingCubesFields;
    case NodeType::ExponentialBlend: return kExponentialFields;
    case NodeType::BlancSchlickBlend: return kBlancSchlickFields;
    case NodeType::EllipticalBlend: return kEllipticalFields;
    case NodeType::UniformHash: return kUniformHashFields;
    case NodeType::RigidTransform: return kRigidTransformFields;
    case NodeType::Metaball: return kMetaballFields;
    case NodeType::Ellipsoid: return kEllipsoidFields;
    case NodeType::LineSeg: return kLineSegFields;
    case NodeType::Material: return kMaterialFields;
    case NodeType::BlendGroup: return kBlendGroupFields;
    case NodeType::TexGenSphere: return kTexGenSphereFields;
    case NodeType::TexGenPlane: return kTexGenPlaneFields;
    case NodeType::ImageTexture: return kImageTextureFields;
  }
  return kMaterialFields;
}

std::optional<NodeType> nodeTypeNamed(const std::string& name) {
  for (size_t i = 0; i < kNodeTypeNames.size(); ++i)
    if (name == kNodeTypeNames[i]) return static_cast<NodeType>(i);
  return std::nullopt;
}

template <class T, class Kind>
T withKind(Kind kind) {
  T node;
  node.kind = kind;
  return node;
}

NodeData emptyNode(NodeType type) {
  switch (type) {
    case NodeType::Tesselator3MP: return Tesselator3MPNode{};
    case NodeType::MarchingCubes: return MarchingCubesNode{};
    case NodeType::ExponentialBlend: return withKind<BlendNode>(BlendKind::Exponential);
    case NodeType::BlancSchlickBlend: return withKind<BlendNode>(BlendKind::BlancSchlick);
    case NodeType::EllipticalBlend: return withKind<BlendNode>(BlendKind::Elliptical);
    case NodeType::UniformHash: return UniformHash{};
    case NodeType::RigidTransform: return TransformNode{};
    case NodeType::Metaball: return withKind<ShapeNode>(ShapeKind::Metaball);
    case NodeType::Ellipsoid: return withKind<ShapeNode>(ShapeKind::Ellipsoid);
    case NodeType::LineSeg: return withKind<ShapeNode>(ShapeKind::LineSeg);
    case NodeType::Material: return Material{};
    case NodeType::BlendGroup: return BlendGroupNode{};
    case NodeType::TexGenSphere: return withKind<TexGenNode>(TexGenKind::Sphere);
    case NodeType::TexGenPlane: return withKind<TexGenNode>(TexGenKind::Plane);
    case NodeType::ImageTexture: return ImageTextureNode{};
  }
  return {};
}

unsigned classOf(const NodeData& node) {
  switch (node.index()) {
    case 1:
    case 2: return kPolygonizerClass;
    case 3: return kBlendClass;
    case 4: return kHashClass;
    case 5: return kTransformClass;
    case 6: return kShapeClass;
    case 7: return kMaterialClass;
    case 8: return kBlendGroupClass;
    case 9: return kTexGenClass;
    case 10: return kTextureClass;
    default: return 0;
  }
}

// The node's DEF name and USE record, for the node types that keep them.
template <class F>
void withNaming(NodeData& node, F&& f) {
  if (auto* s = std::get_if<ShapeNode>(&node)) f(s->name, s->useOf, s->loc);
  if (auto* t = std::get_if<TransformNode>(&node)) f(t->name, t->useOf, t->loc);
  if (auto* b = std::get_if<BlendNode>(&node)) f(b->name, b->useOf, b->loc);
  if (auto* m = std::get_if<Material>(&node)) f(m->name, m->useOf, m->loc);
}

bool isNameable(const NodeData& node) {
  return std::holds_alternative<ShapeNode>(node) || std::holds_alternative<TransformNode>(node) ||
         std::holds_alternative<BlendNode>(node) || std::holds_alternative<Material>(node);
}

SceneNode toSceneNode(NodeData&& node) {
  if (auto* s = std::get_if<ShapeNode>(&node)) return std::move(*s);
  if (auto* t = std::get_if<TransformNode>(&node)) return std::move(*t);
  return std::move(std::get<BlendNode>(node));
}

// Stands for a field name the node type does not have (no setter, accepts nothing).
FieldSpec unknownField(const std::string& name) {
  return FieldSpec{name.c_str(), FieldType::Bool, Constraint::None, nullptr, 0, ""};
}

std::string formatFloat(float f) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, f);
  return std::string(buffer, result.ptr);
}

std::string position(const SourceLoc& loc) { return std::to_string(loc.line) + ":" + std::to_string(loc.column); }

std::string didYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string best = closestMatch(word, candidates);
  return best.empty() ? "" : "; did you mean '" + best + "'?";
}

std::string sourceText(const FieldValue& value) {
  std::string out;
  for (const Token& t : value.items) out += (out.empty() ? "" : " ") + t.text;
  return out;
}

const char* expectation(FieldType type) {
  switch (type) {
    case FieldType::Bool: return "TRUE or FALSE";
    case FieldType::Int: return "an integer";
    case FieldType::Float: return "a number";
    case FieldType::Vec3:
    case FieldType::Color: return "3 numbers";
    case FieldType::Rotation: return "4 numbers (axis x y z, angle in radians)";
    case FieldType::Strings: return "a string or a list of strings";
    case FieldType::Node: return "a node";
    case FieldType::Nodes: return "a node or a list of nodes";
  }
  return "?";
}

size_t expectedCount(FieldType type) {
  switch (type) {
    case FieldType::Vec3:
    case FieldType::Color: return 3;
    case FieldType::Rotation: return 4;
    default: return 1;
  }
}

std::string shapeTypeName(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::Metaball: return "Metaball";
    case ShapeKind::Ellipsoid: return "Ellipsoid";
    case ShapeKind::LineSeg: return "LineSeg";
  }
  return "?";
}

}  // namespace

struct SceneBuilder::Frame {
  bool skipped = false;  // an unknown node, or one inside a field that was refused: read but not checked
  NodeType type = NodeType::Material;
  std::string typeName;
  std::string defName;
  SourceLoc loc;
  NodeData data;
  std::map<std::string, SourceLoc> seen;  // fields given so far
  const FieldSpec* nodeField = nullptr;   // the node-valued field being read, if any
  bool nodeFieldSkipped = false;          // its nodes are read but dropped (the field was refused)
  int height = 1;
  size_t count = 1;
  std::vector<SourceLoc> memberLocs;
};

SceneBuilder::SceneBuilder(std::string fileName, DiagnosticSink& sink) : fileName_(std::move(fileName)), sink_(sink) {
  scene_.fileName = fileName_;
}

SceneBuilder::~SceneBuilder() = default;

bool SceneBuilder::skipping() const {
  return !frames_.empty() && (frames_.back().skipped || frames_.back().nodeFieldSkipped);
}

void SceneBuilder::beginNode(const NodeHeader& header) {
  Frame frame;
  frame.typeName = header.type;
  frame.defName = header.defName;
  frame.loc = header.typeLoc;
  // Written nodes count toward the same limit as USE copies: a million literal Metaballs would cost a gigabyte.
  if (++expandedNodes_ == kMaxExpandedNodes + 1)
    sink_.error(header.typeLoc, "the scene has more than " + std::to_string(kMaxExpandedNodes) +
                                    " nodes (written or copied by USE); the format's limit");
  if (skipping() || expandedNodes_ > kMaxExpandedNodes) {
    frame.skipped = true;
  } else if (const auto type = nodeTypeNamed(header.type)) {
    frame.type = *type;
    frame.data = emptyNode(*type);
    withNaming(frame.data, [&](std::string& name, std::string&, SourceLoc& loc) {
      name = header.defName;
      loc = header.typeLoc;
    });
    if (!header.defName.empty() && !isNameable(frame.data)) {
      sink_.error(header.defLoc, "DEF is not allowed on a " + header.type +
                                     " node: only shapes, RigidTransforms, blend nodes and Materials can be named");
    }
  } else {
    std::vector<std::string> candidates(kNodeTypeNames.begin(), kNodeTypeNames.end());
    sink_.error(header.typeLoc, "unknown node type '" + header.type + "'" + didYouMean(header.type, candidates));
    frame.skipped = true;
  }
  if (!header.defName.empty() && (frame.skipped || !isNameable(frame.data)))
    failedDefinitions_.insert(header.defName);
  frames_.push_back(std::move(frame));
}

void SceneBuilder::endNode(const SourceLoc&) {
  Frame frame = std::move(frames_.back());
  frames_.pop_back();
  if (frame.skipped) return;

  if (const auto* s = std::get_if<ShapeNode>(&frame.data); s && s->kind == ShapeKind::LineSeg) {
    const float length = glm::length(s->point2 - s->point1);
    if (std::abs(s->radius1 - s->radius2) >= length)
      sink_.warning(frame.loc, "one end sphere of this LineSeg contains the other (|radius1 - radius2| >= "
                               "|point2 - point1|), so it is just a sphere");
  }

  Finished finished{std::move(frame.data), frame.typeName, frame.loc, frame.height, frame.count,
                    std::move(frame.memberLocs)};
  if (!frame.defName.empty() && isNameable(finished.node)) {
    if (const auto it = definitions_.find(frame.defName); it != definitions_.end()) {
      sink_.warning(frame.loc, "'" + frame.defName + "' is defined again (first at " + position(it->second.loc) +
                                   "); USE refers to the latest definition");
    }
    if (std::holds_alternative<ShapeNode>(finished.node) || std::holds_alternative<TransformNode>(finished.node))
      memberNames_.insert(frame.defName);
    definitions_.insert_or_assign(frame.defName, Definition{finished, frame.loc});
    failedDefinitions_.erase(frame.defName);
  }
  deliver(std::move(finished));
}

void SceneBuilder::use(const std::string& name, const SourceLoc& loc) {
  if (skipping()) return;
  for (const Frame& open : frames_) {
    if (open.defName == name) {
      sink_.error(loc, "USE of '" + name + "' inside its own definition");
      return;
    }
  }
  const auto it = definitions_.find(name);
  if (it == definitions_.end()) {
    if (failedDefinitions_.contains(name)) return;  // the definition's own error was reported
    std::vector<std::string> candidates;
    for (const auto& [defined, definition] : definitions_) candidates.push_back(defined);
    sink_.error(loc, "USE of undefined name '" + name + "'" + didYouMean(name, candidates));
    return;
  }
  const Finished& defined = it->second.finished;
  // The copy lands one level below the open nodes; its subtree adds defined.height - 1 more.
  if (static_cast<int>(frames_.size()) + defined.height > kMaxNesting) {
    sink_.error(loc, "USE of '" + name + "' here nests nodes deeper than " + std::to_string(kMaxNesting) + " levels");
    return;
  }
  if (expandedNodes_ + defined.count > kMaxExpandedNodes) {
    sink_.error(loc, "USE of '" + name + "' here makes the scene larger than " + std::to_string(kMaxExpandedNodes) +
                         " nodes");
    return;
  }
  expandedNodes_ += defined.count;
  Finished copy = defined;
  copy.loc = loc;
  withNaming(copy.node, [&](std::string& copyName, std::string& useOf, SourceLoc& copyLoc) {
    copyName.clear();
    useOf = name;
    copyLoc = loc;
  });
  deliver(std::move(copy));
}

void SceneBuilder::null(const SourceLoc& loc) {
  if (frames_.empty()) sink_.error(loc, "NULL is only allowed as the value of a node field");
  // In a field NULL means "no node": the field keeps its default.
}

void SceneBuilder::beginNodeField(const std::string& name, const SourceLoc& nameLoc, bool bracketed) {
  Frame& frame = frames_.back();
  frame.nodeField = nullptr;
  frame.nodeFieldSkipped = true;
  if (frame.skipped) return;
  const std::vector<FieldSpec>& fields = fieldsOf(frame.type);
  const FieldSpec* spec = nullptr;
  for (const FieldSpec& f : fields)
    if (name == f.name) spec = &f;
  FieldValue nodeValue;  // for the common checks below: a node where a value was expected
  if (spec == nullptr || (spec->type != FieldType::Node && spec->type != FieldType::Nodes)) {
    storeField(frame, spec ? *spec : unknownField(name), nameLoc, nodeValue);
    return;
  }
  if (const auto seen = frame.seen.find(name); seen != frame.seen.end()) {
    sink_.error(nameLoc, "field '" + name + "' is given twice in " + frame.typeName + " (first at " +
                             position(seen->second) + ")");
    return;
  }
  frame.seen.emplace(name, nameLoc);
  if (spec->type == FieldType::Node && bracketed) {
    sink_.error(nameLoc, "field '" + name + "' of " + frame.typeName + " holds one node, not a list");
    return;
  }
  frame.nodeField = spec;
  frame.nodeFieldSkipped = false;
}

void SceneBuilder::endNodeField() {
  Frame& frame = frames_.back();
  frame.nodeField = nullptr;
  frame.nodeFieldSkipped = false;
}

namespace {

// What a field's constraint asks ("be > 0", "... in every component") if its number(s) break it, else "". An Int
// field's value is `i`; the others' are numbers[0 .. expectedCount(spec.type)).
std::string constraintBroken(const FieldSpec& spec, int i, const std::array<float, 4>& numbers) {
  const bool isInt = spec.type == FieldType::Int;
  const size_t n = expectedCount(spec.type);
  bool ok = true;
  for (size_t k = 0; k < n; ++k) {
    const double x = isInt ? double(i) : double(numbers[k]);
    switch (spec.constraint) {
      case Constraint::None:
      case Constraint::OneString:
      case Constraint::TextureModeName: break;
      case Constraint::Positive: ok = ok && x > 0.0; break;
      case Constraint::NonNegative: ok = ok && x >= 0.0; break;
      case Constraint::AtLeastOne: ok = ok && x >= 1.0; break;
      case Constraint::BitsPerDim: ok = ok && x >= 1.0 && x <= 10.0; break;
      case Constraint::UnitInterval: ok = ok && x >= 0.0 && x <= 1.0; break;
      case Constraint::Threads: ok = ok && x >= 0.0 && x <= kMaxThreads; break;
      case Constraint::Resolution: ok = ok && x >= 0.0 && x <= kMaxResolution; break;
    }
  }
  if (ok) return "";
  std::string rule;
  switch (spec.constraint) {
    case Constraint::Positive: rule = "be > 0"; break;
    case Constraint::NonNegative: rule = "be >= 0"; break;
    case Constraint::AtLeastOne: rule = "be >= 1"; break;
    case Constraint::BitsPerDim: rule = "be between 1 and 10"; break;
    case Constraint::UnitInterval: rule = "be between 0 and 1"; break;
    case Constraint::Threads: rule = "be between 0 and " + std::to_string(kMaxThreads) + " (0: all cores)"; break;
    case Constraint::Resolution:
      rule = "be between 0 and " + std::to_string(kMaxResolution) + " cells (0: unset)";
      break;
    case Constraint::None:
    case Constraint::OneString:
    case Constraint::TextureModeName: break;
  }
  if (n > 1) rule += " in every component";
  return rule;
}

}  // namespace

void SceneBuilder::field(const std::string& name, const SourceLoc& nameLoc, const FieldValue& value) {
  Frame& frame = frames_.back();
  if (frame.skipped) return;
  const FieldSpec* spec = nullptr;
  for (const FieldSpec& f : fieldsOf(frame.type))
    if (name == f.name) spec = &f;
  storeField(frame, spec ? *spec : unknownField(name), nameLoc, value);
}

// Checks one field against its spec and stores it. A spec with no setter and no accepts stands for an unknown
// field; `value` with no items and not bracketed stands for "a node was given".
void SceneBuilder::storeField(Frame& frame, const FieldSpec& spec, const SourceLoc& nameLoc,
                              const FieldValue& value) {
  if (!admitField(frame, spec, nameLoc)) return;
  const SourceLoc loc = value.items.empty() && !value.bracketed ? nameLoc : value.loc;
  for (const Token& t : value.items)
    if (t.kind == TokenKind::BadNumber) return;  // reported by the lexer

  // The shape of the value: a node, a list, or a run of numbers / strings / booleans.
  const bool isNodeValue = value.items.empty() && !value.bracketed;
  if (spec.type == FieldType::Node || spec.type == FieldType::Nodes) {
    if (value.bracketed && value.items.empty() && spec.type == FieldType::Nodes) return;  // `children []`
    if (value.bracketed && value.items.empty()) {
      sink_.error(nameLoc,
                  "field '" + std::string(spec.name) + "' of " + frame.typeName + " holds one node, not a list");
      return;
    }
    return mismatch(frame, spec, loc, describe(value.items.front()));
  }
  if (isNodeValue) return mismatch(frame, spec, loc, "a node");
  if (spec.type == FieldType::Strings) return storeStrings(frame, spec, loc, value);
  if (value.bracketed) return mismatch(frame, spec, loc, "a list");
  if (spec.type == FieldType::Bool) {
    const Token& t = value.items.front();
    if (t.kind != TokenKind::Identifier) return mismatch(frame, spec, loc, describe(t));
    if (value.items.size() > 1) return mismatch(frame, spec, loc, std::to_string(value.items.size()) + " values");
    Value v;
    v.b = t.text == "TRUE";
    spec.set(frame.data, v);
    return;
  }
  storeNumbers(frame, spec, loc, value);
}

// Whether a field may be stored in `frame`: its type has it and it was not given before (else reported).
bool SceneBuilder::admitField(Frame& frame, const FieldSpec& spec, const SourceLoc& nameLoc) {
  const std::string fieldName = spec.name;
  if (spec.set == nullptr && spec.accepts == 0) {
    std::vector<std::string> candidates;
    std::string list;
    for (const FieldSpec& f : fieldsOf(frame.type)) {
      candidates.emplace_back(f.name);
      list += (list.empty() ? "" : ", ") + std::string(f.name);
    }
    const std::string hint = didYouMean(fieldName, candidates);
    sink_.error(nameLoc, "unknown field '" + fieldName + "' in " + frame.typeName +
                             (hint.empty() ? " (its fields are: " + list + ")" : hint));
    return false;
  }
  if (const auto seen = frame.seen.find(fieldName); seen != frame.seen.end()) {
    sink_.error(nameLoc, "field '" + fieldName + "' is given twice in " + frame.typeName + " (first at " +
                             position(seen->second) + ")");
    return false;
  }
  frame.seen.emplace(fieldName, nameLoc);
  return true;
}

// "expected <what spec.type holds> for field 'F' of T, found <found>".
void SceneBuilder::mismatch(const Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const std::string& found) {
  sink_.error(loc, "expected " + std::string(expectation(spec.type)) + " for field '" + std::string(spec.name) +
                       "' of " + frame.typeName + ", found " + found);
}

// An MFString / SFString field: strings only, one unless bracketed, and the spec's constraint on them.
void SceneBuilder::storeStrings(Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const FieldValue& value) {
  const std::string field = "field '" + std::string(spec.name) + "' of " + frame.typeName;
  for (const Token& t : value.items)
    if (t.kind != TokenKind::String) return mismatch(frame, spec, loc, describe(t));
  if (!value.bracketed && value.items.size() > 1)
    return mismatch(frame, spec, loc, std::to_string(value.items.size()) + " strings");
  const std::string count = std::to_string(value.items.size()) + " strings";
  if (spec.constraint == Constraint::OneString && (value.items.size() != 1 || value.items.front().text.empty())) {
    sink_.error(loc, field + " must be one non-empty string, found " +
                         (value.items.size() == 1 ? std::string("an empty string") : count));
    return;
  }
  if (spec.constraint == Constraint::TextureModeName &&
      (value.items.size() != 1 ||
       (value.items.front().text != "projective" && value.items.front().text != "carried"))) {
    sink_.error(loc, field + " must be \"projective\" or \"carried\", found " +
                         (value.items.size() == 1 ? "\"" + value.items.front().text + "\"" : count));
    return;
  }
  Value v;
  for (const Token& t : value.items) {
    v.strings.push_back(t.text);
    frame.memberLocs.push_back(SourceLoc{fileName_, t.line, t.column});
  }
  spec.set(frame.data, v);
  if (auto* texture = std::get_if<ImageTextureNode>(&frame.data)) texture->loc = frame.memberLocs.front();
}

// A numeric field (SFInt32, SFFloat, SFVec3f, SFColor, SFRotation): exactly its count of numbers, each in range for
// its type, then the spec's constraint.
void SceneBuilder::storeNumbers(Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const FieldValue& value) {
  const std::string fieldName = spec.name, &typeName = frame.typeName;
  const std::string what = " for field '" + fieldName + "' of " + typeName;
  for (const Token& t : value.items)
    if (t.kind != TokenKind::Number) return mismatch(frame, spec, loc, describe(t));
  const size_t n = expectedCount(spec.type);
  if (value.items.size() != n)
    return mismatch(frame, spec, loc,
                    std::to_string(value.items.size()) + (value.items.size() == 1 ? " number" : " numbers"));
  Value v;
  std::array<float, 4> numbers{};
  for (size_t k = 0; k < n; ++k) {
    const Token& t = value.items[k];
    const SourceLoc tokenLoc{fileName_, t.line, t.column};
    std::string_view digits = t.text;
    if (digits.front() == '+') digits.remove_prefix(1);
    if (spec.type == FieldType::Int) {
      if (digits.find_first_of(".eE") != std::string_view::npos) return mismatch(frame, spec, loc, "'" + t.text + "'");
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), v.i);
      if (r.ec != std::errc() || r.ptr != digits.data() + digits.size()) {
        sink_.error(tokenLoc, "integer '" + t.text + "'" + what + " is out of range");
        return;
      }
    } else {
      const auto r = std::from_chars(digits.data(), digits.data() + digits.size(), numbers[k]);
      if (r.ec != std::errc() || r.ptr != digits.data() + digits.size() || !std::isfinite(numbers[k])) {
        sink_.error(tokenLoc, "number '" + t.text + "'" + what + " is out of range for a 32-bit float");
        return;
      }
    }
  }
  v.f = numbers[0];
  v.v = glm::vec3(numbers[0], numbers[1], numbers[2]);
  v.r = Rotation{glm::vec3(numbers[0], numbers[1], numbers[2]), numbers[3]};
  if (const std::string rule = constraintBroken(spec, v.i, numbers); !rule.empty()) {
    sink_.error(loc, "field '" + fieldName + "' of " + typeName + " must " + rule + ", found " + sourceText(value));
    return;
  }
  if (spec.type == FieldType::Rotation && v.r.axis == glm::vec3(0.0f) && v.r.angle != 0.0f) {
    sink_.error(loc, "field '" + fieldName + "' of " + typeName + " has a zero axis with a non-zero angle");
    return;
  }
  spec.set(frame.data, v);
  // Where the sizes whose cost depends on the character were given, for the polygonizers' limits' messages.
  if (auto* mc = std::get_if<MarchingCubesNode>(&frame.data);
      mc && fieldName != "isoValue" && fieldName != "numThreads")
    mc->resolutionLoc = loc;
  if (auto* t = std::get_if<Tesselator3MPNode>(&frame.data); t && fieldName == "desiredRadius")
    t->desiredRadiusLoc = loc;
}

void SceneBuilder::deliver(Finished child) {
  if (frames_.empty()) return deliverTop(std::move(child));
  Frame& parent = frames_.back();
  if (parent.skipped || parent.nodeFieldSkipped || parent.nodeField == nullptr) return;
  const FieldSpec& spec = *parent.nodeField;
  if ((classOf(child.node) & spec.accepts) == 0) {
    sink_.error(child.loc, "a " + child.typeName + " node is not allowed in field '" + spec.name + "' of " +
                               parent.typeName + " (it takes " + spec.acceptsText + ")");
    return;
  }
  const std::string field = spec.name;
  if (field == "blendingFunction" && !std::get<BlendNode>(child.node).children.empty()) {
    sink_.error(child.loc, "the blendingFunction of " + parent.typeName +
                               " must have no children; put the shapes in sceneGraph");
    return;
  }
  parent.height = std::max(parent.height, child.height + 1);
  parent.count += child.count;
  NodeData& p = parent.data;
  if (auto* t = std::get_if<Tesselator3MPNode>(&p)) {
    if (field == "blendingFunction") t->blendingFunction = std::get<BlendNode>(std::move(child.node));
    if (field == "spatialSubdivision") t->spatialSubdivision = std::get<UniformHash>(child.node);
    if (field == "sceneGraph") t->sceneGraph = toSceneNode(std::move(child.node));
  } else if (auto* m = std::get_if<MarchingCubesNode>(&p)) {
    if (field == "blendingFunction") m->blendingFunction = std::get<BlendNode>(std::move(child.node));
    if (field == "sceneGraph") m->sceneGraph = toSceneNode(std::move(child.node));
  } else if (auto* b = std::get_if<BlendNode>(&p)) {
    b->children.push_back(toSceneNode(std::move(child.node)));
  } else if (auto* x = std::get_if<TransformNode>(&p)) {
    x->children.push_back(toSceneNode(std::move(child.node)));
  } else if (auto* s = std::get_if<ShapeNode>(&p)) {
    if (field == "material") s->material = std::get<Material>(std::move(child.node));
    if (field == "texGen") {
      s->texGen = std::get<TexGenNode>(std::move(child.node));
      s->texGen->loc = child.loc;
    }
    if (field == "texture") s->texture = std::get<ImageTextureNode>(std::move(child.node));
  }
}

void SceneBuilder::deliverTop(Finished child) {
  const unsigned kind = classOf(child.node);
  if (kind == kBlendGroupClass) {
    scene_.blendGroups.push_back(std::get<BlendGroupNode>(std::move(child.node)));
    scene_.blendGroups.back().loc = child.loc;
    memberLocs_.push_back(std::move(child.memberLocs));
    return;
  }
  if ((kind & (kPolygonizerClass | kSceneGraphClasses)) == 0) {
    sink_.error(child.loc, "a " + child.typeName +
                               " node cannot be at top level (a file holds one polygonizer or scene graph root, "
                               "plus BlendGroups)");
    return;
  }
  if (!rootType_.empty()) {
    sink_.error(child.loc, "a second scene root '" + child.typeName + "': the file already has one (the " +
                               rootType_ + " at " + position(rootLoc_) +
                               "); a file holds at most one polygonizer or scene graph root");
    return;
  }
  rootType_ = child.typeName;
  rootLoc_ = child.loc;
  if (auto* t = std::get_if<Tesselator3MPNode>(&child.node)) {
    scene_.polygonizer = std::move(*t);
  } else if (auto* m = std::get_if<MarchingCubesNode>(&child.node)) {
    scene_.polygonizer = std::move(*m);
  } else {
    scene_.root = toSceneNode(std::move(child.node));
  }
}

void SceneBuilder::checkBlendParams(const SceneNode& node, BlendKind inForce) {
  if (const auto* blend = std::get_if<BlendNode>(&node)) {
    for (const SceneNode& c : blend->children) checkBlendParams(c, blend->kind);
  } else if (const auto* transform = std::get_if<TransformNode>(&node)) {
    for (const SceneNode& c : transform->children) checkBlendParams(c, inForce);
  } else if (const auto* shape = std::get_if<ShapeNode>(&node); shape && shape->blendParam) {
    const float p = *shape->blendParam;
    const std::string head = "blendParam " + formatFloat(p) + " of " + shapeTypeName(shape->kind) + " must be ";
    const std::string under = std::string(" under ") + blendTypeName(inForce);
    if (inForce == BlendKind::Exponential && !(p < 0.0f))
      sink_.error(shape->loc, head + "negative" + under + " (it is the blobbiness B)");
    if (inForce == BlendKind::BlancSchlick && !(p > 0.0f))
      sink_.error(shape->loc, head + "> 0" + under + " (it is the hardness)");
    if (inForce == BlendKind::Elliptical && !(p > 0.0f))
      sink_.error(shape->loc, head + "> 0" + under + " (it is the blend range)");
  }
}

Scene SceneBuilder::finish(bool parsedToEnd) {
  if (parsedToEnd && !sink_.full()) {
    for (size_t g = 0; g < scene_.blendGroups.size(); ++g) {
      const BlendGroupNode& group = scene_.blendGroups[g];
      for (size_t k = 0; k < group.members.size(); ++k) {
        const std::string& member = group.members[k];
        const SourceLoc& loc = k < memberLocs_[g].size() ? memberLocs_[g][k] : group.loc;
        if (memberNames_.contains(member)) continue;
        if (definitions_.contains(member)) {
          sink_.error(loc, "BlendGroup member '" + member + "' is not a shape or RigidTransform");
          continue;
        }
        std::vector<std::string> candidates(memberNames_.begin(), memberNames_.end());
        sink_.error(loc, "BlendGroup member '" + member + "' names no DEF'd shape or RigidTransform" +
                             didYouMean(member, candidates));
      }
    }
    if (const SceneNode* graph = scene_.sceneGraph()) {
      const BlendNode* function = scene_.blendingFunction();
      checkBlendParams(*graph, function ? function->kind : BlendKind::Exponential);
    }
  }
  return std::move(scene_);
}

}  // namespace imps::vrml
