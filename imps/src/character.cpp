// Character compilation: scene graph -> joints, joint-local primitives and the blend graph (thesis 3.7).
#include "imps/character.h"

#include <algorithm>
#include <map>
#include <set>

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
      c_.hierarchical_ = false;
      for (const SceneNode& child : flat->children) walk(child, -1);
    } else {
      const BlendNode* fn = scene_.blendingFunction();
      c_.blend_ = fn ? BlendFunction::fromNode(*fn) : BlendFunction{};
      c_.hierarchical_ = true;
      walk(*root, -1);
    }
    if (!diags_.hasErrors() && c_.primitives_.empty())
      diags_.error(fileLoc, "the scene graph holds no primitives (Metaball, Ellipsoid or LineSeg)");
    if (diags_.hasErrors()) return std::unexpected(diags_);
    buildBlendGraph();
    if (diags_.hasErrors()) return std::unexpected(diags_);
    return std::move(c_);
  }

 private:
  void walk(const SceneNode& node, int joint) {
    if (const auto* t = std::get_if<TransformNode>(&node)) {
      Joint j;
      j.name = t->name.empty() ? "joint" + std::to_string(c_.joints_.size()) : t->name;
      j.parent = joint;
      j.rest = {toQuat(t->rotation), t->translation};
      const int index = static_cast<int>(c_.joints_.size());
      jointNames_[j.name].push_back(index);
      c_.joints_.push_back(std::move(j));
      for (const SceneNode& child : t->children) walk(child, index);
    } else if (const auto* s = std::get_if<ShapeNode>(&node)) {
      addPrimitive(*s, joint);
    } else if (const auto* b = std::get_if<BlendNode>(&node)) {
      diags_.error(b->loc, "a blend node may only be the root of a flat scene graph; in a hierarchical scene "
                           "give the polygonizer a blendingFunction instead");
    }
  }

  void addPrimitive(const ShapeNode& s, int joint) {
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
    p.blendParam = s.blendParam.value_or(c_.blend_.defaultParam);
    const bool wrongSign = c_.blend_.kind == BlendKind::Exponential ? !(p.blendParam < 0.0f) : !(p.blendParam > 0.0f);
    if (wrongSign || !std::isfinite(p.blendParam)) {
      diags_.error(s.loc, c_.blend_.kind == BlendKind::Exponential
                              ? "blendParam is the blobbiness of ExponentialBlend and must be negative"
                              : "blendParam must be positive for this blend");
    }
    if (s.material) p.color = s.material->diffuseColor;
    shapeNames_[p.name].push_back(index);
    c_.primitives_.push_back(std::move(p));
  }

  // The nearest ancestor joint (excluding j) that directly holds primitives; -1 if none.
  int shapeParent(int j, const std::vector<int>& primitiveCount) const {
    for (int a = j >= 0 ? c_.joints_[j].parent : -1; a >= 0; a = c_.joints_[a].parent)
      if (primitiveCount[a] > 0) return a;
    return -1;
  }

  void buildBlendGraph() {
    const size_t n = c_.primitives_.size();
    std::vector<std::set<uint32_t>> nb(n);
    if (c_.hierarchical_) {
      std::vector<int> count(c_.joints_.size(), 0);
      for (const auto& p : c_.primitives_)
        if (p.joint >= 0) ++count[p.joint];
      std::vector<int> parentOf(c_.joints_.size());
      for (size_t j = 0; j < c_.joints_.size(); ++j) parentOf[j] = shapeParent(static_cast<int>(j), count);
      for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b) {
          const int ja = c_.primitives_[a].joint, jb = c_.primitives_[b].joint;
          const bool siblings = ja == jb;
          const bool parentChild = (ja >= 0 && parentOf[ja] == jb && jb >= 0) || (jb >= 0 && parentOf[jb] == ja && ja >= 0);
          if (siblings || parentChild) {
            nb[a].insert(static_cast<uint32_t>(b));
            nb[b].insert(static_cast<uint32_t>(a));
          }
        }
    } else if (!scene_.blendGroups.empty()) {
      // A flat scene blends everything with everything; only BlendGroups need the pairs spelled out.
      for (size_t a = 0; a < n; ++a)
        for (size_t b = 0; b < n; ++b)
          if (a != b) nb[a].insert(static_cast<uint32_t>(b));
    }

    // BlendGroups override the hierarchy, later groups winning.
    for (const BlendGroupNode& g : scene_.blendGroups) {
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
      for (uint32_t a : members)
        for (uint32_t b : members) {
          if (a == b) continue;
          if (g.blend) nb[a].insert(b);
          else nb[a].erase(b);
        }
    }

    c_.neighbours_.resize(n);
    for (size_t i = 0; i < n; ++i) c_.neighbours_[i].assign(nb[i].begin(), nb[i].end());

    if (!c_.hierarchical_ && scene_.blendGroups.empty()) {
      c_.sets_ = BlendSets::all(n);
      return;
    }
    // One set per primitive: itself and its neighbours; drop duplicates and subsets (they never win the max,
    // since the blends are monotone in every term).
    std::vector<std::vector<uint32_t>> sets(n);
    for (size_t i = 0; i < n; ++i) {
      sets[i] = c_.neighbours_[i];
      sets[i].insert(std::lower_bound(sets[i].begin(), sets[i].end(), static_cast<uint32_t>(i)),
                     static_cast<uint32_t>(i));
    }
    std::vector<bool> keep(n, true);
    for (size_t a = 0; a < n; ++a)
      for (size_t b = 0; b < n && keep[a]; ++b) {
        if (a == b || !keep[b]) continue;
        const bool subset = std::includes(sets[b].begin(), sets[b].end(), sets[a].begin(), sets[a].end());
        if (subset && (sets[a].size() < sets[b].size() || a > b)) keep[a] = false;
      }
    for (size_t i = 0; i < n; ++i)
      if (keep[i]) c_.sets_.add(sets[i]);
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
  Character c_;
  Diagnostics diags_;
  std::map<std::string, std::vector<size_t>> shapeNames_;
  std::map<std::string, std::vector<int>> jointNames_;
};

std::expected<Character, Diagnostics> Character::fromScene(const Scene& scene) { return CharacterBuilder(scene).build(); }

int Character::findJoint(std::string_view name) const {
  for (size_t j = 0; j < joints_.size(); ++j)
    if (joints_[j].name == name) return static_cast<int>(j);
  return -1;
}

}  // namespace imps
