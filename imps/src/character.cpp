// SPDX-License-Identifier: MIT
// Character compilation: scene graph -> joints, joint-local primitives and the blend graph (thesis 3.7).
#include "imps/character.h"

#include <algorithm>
#include <filesystem>
#include <map>

namespace imps {

glm::quat toQuat(const Rotation& r) {
  const float len = glm::length(r.axis);
  if (len == 0.0f || r.angle == 0.0f) return glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  return glm::angleAxis(r.angle, r.axis / len);
}

BlendFunction BlendFunction::fromNode(const BlendNode& node) {
  BlendFunction b;
  b.kind = node.kind;
  switch (node.kind) {
    case BlendKind::Exponential:
      b.defaultParam = -1.0f / node.variance;
      b.fastExp = node.fastExp;
      break;
    case BlendKind::BlancSchlick: b.defaultParam = node.hardness; break;
    case BlendKind::Elliptical: b.defaultParam = node.blendRange; break;
  }
  return b;
}

TexGen texGenOf(const ShapeNode& shape, const TexGenNode& node) {
  TexGen g;
  g.type = node.kind == TexGenKind::Plane ? TexGenType::Plane : TexGenType::Sphere;
  const glm::vec3 centre = shape.kind == ShapeKind::LineSeg ? 0.5f * (shape.point1 + shape.point2) : shape.center;
  g.origin = centre + node.translation;
  g.rotation = toQuat(node.rotation);
  g.width = node.width;
  g.height = node.height;
  return g;
}

class CharacterBuilder {
 public:
  explicit CharacterBuilder(const Scene& scene) : scene_(scene) {}

  std::expected<Character, Diagnostics> build() {
    const SceneNode* root = scene_.sceneGraph();
    SourceLoc fileLoc{scene_.fileName, 0, 0};
    if (!root) {
      diags_.error(fileLoc, "the scene has no scene graph (expected a RigidTransform or a blend node)");
      return std::unexpected(diags_);
    }
    if (const auto* t = std::get_if<Tesselator3MPNode>(&scene_.polygonizer)) c_.iso_ = t->isoValue;
    if (const auto* m = std::get_if<MarchingCubesNode>(&scene_.polygonizer)) c_.iso_ = m->isoValue;

    if (const auto* flat = std::get_if<BlendNode>(root)) {
      c_.blend_ = BlendFunction::fromNode(*flat);
      blendSource_ = flat;
      c_.hierarchical_ = false;
      for (const SceneNode& child : flat->children) walk(child, -1, c_.blend_.defaultParam);
    } else {
      // A hierarchical character has one blend function: the polygonizer's blendingFunction, else that of the
      // first blend node nested in the hierarchy (appendix A.2.2's mcSimpleBip01.wrl style).
      blendSource_ = scene_.blendingFunction();
      if (!blendSource_) blendSource_ = firstBlendNode(*root);
      c_.blend_ = blendSource_ ? BlendFunction::fromNode(*blendSource_) : BlendFunction{};
      c_.hierarchical_ = true;
      walk(*root, -1, c_.blend_.defaultParam);
    }
    if (!diags_.hasErrors() && c_.primitives_.empty())
      diags_.error(fileLoc, "the scene graph holds no primitives (Metaball, Ellipsoid or LineSeg)");
    if (diags_.hasErrors()) return std::unexpected(diags_);
    buildBlendGraph();
    if (diags_.hasErrors()) return std::unexpected(diags_);
    return std::move(c_);
  }

 private:
  static const BlendNode* firstBlendNode(const SceneNode& node) {
    if (const auto* b = std::get_if<BlendNode>(&node)) return b;
    if (const auto* t = std::get_if<TransformNode>(&node))
      for (const SceneNode& child : t->children)
        if (const BlendNode* b = firstBlendNode(child)) return b;
    return nullptr;
  }

  // `defaultParam`: the blendParam of shapes that give none (the innermost enclosing blend node's).
  void walk(const SceneNode& node, int joint, float defaultParam) {
    if (const auto* t = std::get_if<TransformNode>(&node)) {
      Joint j;
      j.name = t->name.empty() ? "joint" + std::to_string(c_.joints_.size()) : t->name;
      j.parent = joint;
      j.rest = {toQuat(t->rotation), t->translation};
      const int index = static_cast<int>(c_.joints_.size());
      jointNames_[j.name].push_back(index);
      c_.joints_.push_back(std::move(j));
      for (const SceneNode& child : t->children) walk(child, index, defaultParam);
    } else if (const auto* s = std::get_if<ShapeNode>(&node)) {
      addPrimitive(*s, joint, defaultParam);
    } else if (const auto* b = std::get_if<BlendNode>(&node)) {
      // A nested blend node scopes its parameters over the shapes it wraps; which shapes blend is still the
      // blending rule's (a blend node is not a joint and does not group anything).
      if (b->kind != c_.blend_.kind) {
        const char* mine = blendTypeName(b->kind);
        diags_.error(b->loc, std::string("this ") + mine + " differs from the character's blend function, " +
                                 blendTypeName(c_.blend_.kind) + " (" + sourceOf(blendSource_) +
                                 "): a character has one blend function; give every blend node the same type, or "
                                 "set the polygonizer's blendingFunction " + mine + " { ... }");
        return;
      }
      const float param = BlendFunction::fromNode(*b).defaultParam;
      for (const SceneNode& child : b->children) walk(child, joint, param);
    }
  }

  static std::string sourceOf(const BlendNode* b) {
    if (!b) return "the default, as no blend node or blendingFunction is given";
    return "from " + std::to_string(b->loc.line) + ":" + std::to_string(b->loc.column);
  }

  void addPrimitive(const ShapeNode& s, int joint, float defaultParam) {
    CharacterPrimitive p;
    const size_t index = c_.primitives_.size();
    switch (s.kind) {
      case ShapeKind::Metaball: p.local = Primitive::metaball(s.center, s.radius); break;
      case ShapeKind::Ellipsoid: p.local = Primitive::ellipsoid(s.center, toQuat(s.orientation), s.radii); break;
      case ShapeKind::LineSeg: p.local = Primitive::lineSeg(s.point1, s.point2, s.radius1, s.radius2); break;
    }
    static const char* kKindNames[] = {"metaball", "ellipsoid", "lineseg"};
    p.name = s.name.empty() ? kKindNames[static_cast<int>(s.kind)] + std::to_string(index) : s.name;
    p.joint = joint;
    p.blendParam = s.blendParam.value_or(defaultParam);
    const bool wrongSign = c_.blend_.kind == BlendKind::Exponential ? !(p.blendParam < 0.0f) : !(p.blendParam > 0.0f);
    if (wrongSign || !std::isfinite(p.blendParam)) {
      diags_.error(s.loc, c_.blend_.kind == BlendKind::Exponential
                              ? "blendParam is the blobbiness of ExponentialBlend and must be negative"
                              : "blendParam must be positive for this blend");
    }
    if (s.material) p.color = s.material->diffuseColor;
    if (s.texGen || s.texture) {
      p.texGen = texGenOf(s, s.texGen.value_or(TexGenNode{}));
      c_.textured_ = true;
    }
    if (s.texture) p.texture = textureIndex(*s.texture);
    shapeNames_[p.name].push_back(index);
    c_.primitives_.push_back(std::move(p));
  }

  // The entry of Character::textures() for this url, added on first use.
  int textureIndex(const ImageTextureNode& t) {
    namespace fs = std::filesystem;
    const fs::path url(t.url);
    const std::string path =
        url.is_absolute() ? url.string() : (fs::path(scene_.fileName).parent_path() / url).string();
    for (size_t k = 0; k < c_.textures_.size(); ++k)
      if (c_.textures_[k].path == path) return static_cast<int>(k);
    c_.textures_.push_back({t.url, path, t.loc});
    return static_cast<int>(c_.textures_.size() - 1);
  }

  // The nearest ancestor joint (excluding j) that directly holds primitives; -1 if none.
  int shapeParent(int j, const std::vector<int>& primitiveCount) const {
    for (int a = j >= 0 ? c_.joints_[j].parent : -1; a >= 0; a = c_.joints_[a].parent)
      if (primitiveCount[a] > 0) return a;
    return -1;
  }

  // The twin classes: primitives of one joint (any joint in a flat scene) with the same BlendGroup memberships.
  // `groupMembers[g]`: the primitives BlendGroup g names.
  std::vector<uint32_t> twinClasses(const std::vector<std::vector<uint32_t>>& groupMembers, size_t& classCount) const {
    const size_t n = c_.primitives_.size();
    std::vector<std::vector<uint32_t>> memberships(n);
    for (size_t g = 0; g < groupMembers.size(); ++g)
      for (uint32_t i : groupMembers[g])
        if (memberships[i].empty() || memberships[i].back() != g) memberships[i].push_back(static_cast<uint32_t>(g));
    std::map<std::pair<int, std::vector<uint32_t>>, uint32_t> ids;
    std::vector<uint32_t> classOf(n);
    for (size_t i = 0; i < n; ++i) {
      const int joint = c_.hierarchical_ ? c_.primitives_[i].joint : -1;
      classOf[i] = ids.try_emplace({joint, std::move(memberships[i])}, static_cast<uint32_t>(ids.size())).first->second;
    }
    classCount = ids.size();
    return classOf;
  }

  void buildBlendGraph() {
    std::vector<std::vector<uint32_t>> groupMembers;
    for (const BlendGroupNode& g : scene_.blendGroups) groupMembers.push_back(blendGroupMembers(g));
    size_t classCount = 0;
    std::vector<uint32_t> classOf = twinClasses(groupMembers, classCount);
    BlendGraph graph(classOf, classCount);
    std::vector<int> jointOf(classCount, -1);
    for (size_t i = 0; i < classOf.size(); ++i) jointOf[classOf[i]] = c_.primitives_[i].joint;

    // The rule: siblings, parent and children (hierarchical); everything (flat).
    std::vector<int> count(c_.joints_.size(), 0);
    for (const auto& p : c_.primitives_)
      if (p.joint >= 0) ++count[p.joint];
    std::vector<int> parentOf(classCount, -1);  // each class's joint's nearest primitive-holding ancestor
    for (uint32_t a = 0; a < classCount; ++a)
      if (jointOf[a] >= 0) parentOf[a] = shapeParent(jointOf[a], count);
    for (uint32_t a = 0; a < classCount; ++a)
      for (uint32_t b = a + 1; b < classCount; ++b) {
        const int ja = jointOf[a], jb = jointOf[b];
        const bool related = !c_.hierarchical_ || ja == jb || (ja >= 0 && parentOf[a] == jb) ||
                             (jb >= 0 && parentOf[b] == ja);
        graph.setBlend(a, b, related);
      }
    // BlendGroups override the rule, later groups winning. Each group's members are a union of twin classes.
    for (size_t g = 0; g < groupMembers.size(); ++g) {
      std::vector<uint32_t> classes;
      for (uint32_t i : groupMembers[g]) classes.push_back(classOf[i]);
      std::sort(classes.begin(), classes.end());
      classes.erase(std::unique(classes.begin(), classes.end()), classes.end());
      const bool blend = scene_.blendGroups[g].blend;
      for (uint32_t a : classes) {
        graph.setSelfBlend(a, blend);
        for (uint32_t b : classes) graph.setBlend(a, b, blend);
      }
    }

    c_.graph_ = std::move(graph);
    if (c_.graph_.complete()) {
      c_.sets_ = BlendSets::all(c_.primitives_.size());
      return;
    }
    constexpr size_t kMaxBlendSets = 100000;
    auto cliques = c_.graph_.maximalCliques(kMaxBlendSets);
    if (!cliques) {
      diags_.error({scene_.fileName, 0, 0}, "the BlendGroups make more than " + std::to_string(kMaxBlendSets) +
                                                " blend sets (maximal cliques of the blend graph); group primitives "
                                                "that should blend together instead of removing many single pairs");
      return;
    }
    for (const auto& set : *cliques) c_.sets_.add(set);
  }

  // The primitives a BlendGroup names (a primitive's DEF name, or a RigidTransform's for all its primitives),
  // ascending; unknown names are errors with a suggestion.
  std::vector<uint32_t> blendGroupMembers(const BlendGroupNode& g) {
    std::vector<uint32_t> members;
    for (const std::string& name : g.members) {
      std::vector<uint32_t> found = primitivesNamed(name);
      if (found.empty()) {
        std::vector<std::string> known;
        for (const auto& [k, v] : shapeNames_) known.push_back(k);
        for (const auto& [k, v] : jointNames_) known.push_back(k);
        const std::string guess = closestMatch(name, known);
        diags_.error(g.loc, "BlendGroup member '" + name + "' names no primitive or RigidTransform" +
                                (guess.empty() ? "" : "; did you mean '" + guess + "'?"));
      }
      members.insert(members.end(), found.begin(), found.end());
    }
    std::sort(members.begin(), members.end());
    members.erase(std::unique(members.begin(), members.end()), members.end());
    return members;
  }

  std::vector<uint32_t> primitivesNamed(const std::string& name) const {
    std::vector<uint32_t> out;
    if (auto it = shapeNames_.find(name); it != shapeNames_.end())
      for (size_t i : it->second) out.push_back(static_cast<uint32_t>(i));
    if (auto it = jointNames_.find(name); it != jointNames_.end())
      for (int j : it->second)
        for (size_t i = 0; i < c_.primitives_.size(); ++i)
          if (c_.primitives_[i].joint == j) out.push_back(static_cast<uint32_t>(i));
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  const Scene& scene_;
  const BlendNode* blendSource_ = nullptr;  // where the character's blend function comes from, if from a node
  Character c_;
  Diagnostics diags_;
  std::map<std::string, std::vector<size_t>> shapeNames_;
  std::map<std::string, std::vector<int>> jointNames_;
};

std::expected<Character, Diagnostics> Character::fromScene(const Scene& scene) {
  return CharacterBuilder(scene).build();
}

int Character::findJoint(std::string_view name) const {
  for (size_t j = 0; j < joints_.size(); ++j)
    if (joints_[j].name == name) return static_cast<int>(j);
  return -1;
}

}  // namespace imps
