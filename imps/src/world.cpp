// SPDX-License-Identifier: MIT
// Worlds: Inlines of IMPS characters and VRML 97 files under Transforms, resolved into placed characters, their
// clips and props (see imps/world.h).
#include "imps/world.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <utility>

#include <glm/gtc/quaternion.hpp>

#include "imps/file_read.h"
#include "imps/gzip.h"
#include "imps/scene_reader.h"
#include "imps/skeleton_cache.h"
#include "imps/vrml_file.h"

namespace imps {

namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxInputBytes = size_t{256} << 20;

// The node types only the IMPS scene dialect has (docs/scene-format.md).
constexpr std::string_view kImpsNodes[] = {"Tesselator3MP", "MarchingCubes", "RigidTransform", "Metaball", "LineSeg",
                                           "Ellipsoid", "ExponentialBlend", "BlancSchlickBlend", "EllipticalBlend",
                                           "BlendGroup", "UniformHash"};

bool isNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

// What an Inline's url names once read.
struct Inlined {
  enum class Kind { Character, Vrml } kind = Kind::Vrml;
  std::string path;      // resolved
  std::string fragment;  // after '#': a clip's TimeSensor
  SourceLoc loc;         // the url field
  std::string defName;   // the Inline's DEF name
  glm::mat4 matrix{1.0f};
  std::vector<WorldTransform> chain;  // the Transforms above, outermost first
  std::string nearestDef;  // the nearest DEF'd Transform above
  std::optional<VrmlFile> file;  // Kind::Vrml
};

class WorldReader {
 public:
  WorldReader(const VrmlFile& file, Diagnostics& d)
      : file_(file), d_(d), folder_(fs::path(file.fileName).parent_path()) {}

  // Walks the world's nodes; every children list's Inlines are resolved together (a clip drives its sibling).
  // `chain_` holds the Transforms above the node (their DEF names and fields), so a world clip can move them.
  void walk(const VrmlNode& written, const std::string& nearest, const glm::mat4& matrix, int depth) {
    if (depth > 256) return;
    const VrmlNode& node = written.resolved();
    if (node.type == "Shape") {
      shape(written, nearest, matrix);
      return;
    }
    glm::mat4 here = matrix;
    std::string nearestDef = nearest;
    const bool transform = node.type == "Transform";
    if (transform) {
      const TransformValues v = transformValuesOf(node);
      here = matrix * v.matrix();
      if (!written.defName.empty()) nearestDef = written.defName;
      chain_.push_back({written.defName, v});
    }
    if (transform || node.type == "Group" || node.type == "Anchor" || node.type == "Billboard" ||
        node.type == "Collision" || written.protoBody) {
      for (const VrmlField& field : node.fields)
        if (field.name == "children") siblings(field.nodes, nearestDef, here, depth);
    }
    if (transform) chain_.pop_back();
  }

  void siblings(const std::vector<VrmlNodeRef>& nodes, const std::string& nearest, const glm::mat4& matrix, int depth) {
    // The Inlines first: a character among them claims the Transforms beside it named after its joints.
    std::vector<Inlined> inlined;
    for (const VrmlNodeRef& child : nodes) {
      const VrmlNode& n = child->resolved();
      if (n.type == "Inline")
        if (auto i = resolve(*child, n, nearest, matrix)) inlined.push_back(std::move(*i));
    }
    const int character = group(std::move(inlined));
    for (const VrmlNodeRef& child : nodes) {
      const VrmlNode& n = child->resolved();
      if (n.type == "Inline") continue;
      const int joint = character >= 0 && n.type == "Transform" && !child->defName.empty()
                            ? characters_[size_t(character)].character.findJoint(child->defName)
                            : -1;
      if (joint >= 0) {
        attach(n, child->defName, character, joint, depth);
        continue;
      }
      walk(*child, nearest, matrix, depth + 1);
    }
  }

  // A Transform named after a joint of the character beside it: its children ride on that joint, in the joint's
  // posed frame (the Transform's own fields are replaced by the joint's pose, as in a clip file).
  void attach(const VrmlNode& transform, const std::string& name, int character, int joint, int depth) {
    if (attachCharacter_ >= 0) {
      d_.error(transform.loc, "Transform " + name + " rides on a joint inside another joint's Transform; attach it "
                              "beside the character instead");
      return;
    }
    const std::vector<WorldTransform> outer = std::exchange(chain_, {});
    attachCharacter_ = character, attachJoint_ = joint;
    for (const VrmlField& field : transform.fields)
      if (field.name == "children") siblings(field.nodes, name, glm::mat4(1.0f), depth + 1);
    attachCharacter_ = attachJoint_ = -1;
    chain_ = outer;
  }

  // A Shape of the world: its mesh in its own coordinates (readProps of the Shape alone) under the current chain.
  void shape(const VrmlNode& written, const std::string& nearest, const glm::mat4& matrix) {
    VrmlFile alone;
    alone.fileName = file_.fileName;
    alone.roots.push_back(VrmlNodeRef(&written, [](const VrmlNode*) {}));  // not owned: the file outlives it
    for (Prop& p : readProps(alone, &d_)) {
      if (p.name == "prop1") p.name = nearest.empty() ? "prop" + std::to_string(props_.size() + 1) : nearest;
      addProp(std::move(p), matrix);
    }
  }

  void addProp(Prop p, const glm::mat4& matrix) {
    propLocal_.push_back(p.mesh);
    propChains_.push_back(chain_);
    propCharacter_.push_back(attachCharacter_);
    propJoint_.push_back(attachJoint_);
    p.mesh = transformed(p.mesh, matrix);
    if (attachCharacter_ >= 0) {
      // At rest, where the character stands: the joint's world transform (placement included), then the mesh.
      const WorldCharacter& c = characters_[size_t(attachCharacter_)];
      SkeletonCache rest(c.character);
      rest.setPlacement(c.placement);
      rest.update();
      propLocal_.back() = p.mesh;  // in the joint's frame
      p.mesh = transformed(p.mesh, rest.world(attachJoint_));
    }
    props_.push_back(std::move(p));
  }

  World finish() && {
    World world;
    world.fileName = file_.fileName;
    world.characters = std::move(characters_);
    world.props = std::move(props_);
    world.propLocal = std::move(propLocal_);
    world.propChains = std::move(propChains_);
    world.propCharacter = std::move(propCharacter_);
    world.propJoint = std::move(propJoint_);
    return world;
  }

 private:
  // Reads the file an Inline names; nullopt after reporting why.
  std::optional<Inlined> resolve(const VrmlNode& written, const VrmlNode& node, const std::string& nearest,
                                 const glm::mat4& matrix) {
    const VrmlField* url = node.field("url");
    const SourceLoc at = url != nullptr ? url->valueLoc : node.loc;
    if (url == nullptr || url->strings.empty()) {
      d_.error(at, "Inline has no url: give the IMPS scene or VRML 97 file to place here, e.g. url \"beanito.wrl\"");
      return std::nullopt;
    }
    // VRML 97 4.5.2: the first url that can be used; relative ones against the world file's folder.
    std::string tried;
    for (const std::string& u : url->strings) {
      std::string name = u, fragment;
      if (const size_t hash = name.find('#'); hash != std::string::npos) {
        fragment = name.substr(hash + 1);
        name.resize(hash);
      }
      if (name.starts_with("file://")) name = name.substr(7);
      if (name.find("://") != std::string::npos) {
        tried += (tried.empty() ? "" : ", ") + u + " (not fetched)";
        continue;
      }
      const fs::path path = fs::path(name).is_absolute() ? fs::path(name) : folder_ / name;
      std::error_code ec;
      if (!fs::is_regular_file(path, ec)) {
        tried += (tried.empty() ? "" : ", ") + path.string() + " (no such file)";
        continue;
      }
      auto bytes = readFileText(path, kMaxInputBytes);
      if (!bytes) {
        d_.error(at, "Inline: cannot read '" + path.string() + "': " + bytes.error().message);
        return std::nullopt;
      }
      std::string text = std::move(*bytes);
      if (isGzip(text)) {
        auto inflated = gunzip(text, kMaxInputBytes);
        if (inflated) text = std::move(*inflated);  // a corrupt stream: the VRML reader says why below
      }
      Inlined i;
      i.path = path.string();
      i.fragment = fragment;
      i.loc = at;
      i.defName = written.defName;
      i.matrix = matrix;
      i.chain = chain_;
      i.nearestDef = nearest;
      const bool vrml = text.starts_with("#VRML") || text.starts_with("\xEF\xBB\xBF#VRML");
      if (!vrml) {
        d_.error(at, "Inline '" + u + "' (" + i.path +
                         ") is neither an IMPS character scene nor a VRML 97 file (it does not start with #VRML)");
        return std::nullopt;
      }
      if (namesImpsNodes(text)) {
        i.kind = Inlined::Kind::Character;
        return i;
      }
      Diagnostics inner;
      auto file = readVrml(text, i.path, &inner);
      if (!file) {
        d_.error(at,
                 "Inline '" + u + "': " + i.path + " is not an IMPS character scene, and does not read as VRML 97:");
        d_.append(file.error());
        return std::nullopt;
      }
      d_.append(inner);
      i.file = std::move(*file);
      return i;
    }
    d_.error(at, "Inline: no url names a file that can be read (tried " + tried + ")");
    return std::nullopt;
  }

  // The Inlines of one children list: at most one character, driven by the clips inlined beside it.
  // Returns the character's index in characters_, or -1.
  int group(std::vector<Inlined> inlined) {
    int character = -1;
    for (size_t k = 0; k < inlined.size(); ++k) {
      if (inlined[k].kind != Inlined::Kind::Character) continue;
      if (character >= 0) {
        d_.error(inlined[k].loc, "a second character Inline in the same children list (the first is at line " +
                                     std::to_string(inlined[size_t(character)].loc.line) +
                                     "): give each character a Transform of its own, so its clip and placement are "
                                     "its alone");
        return -1;
      }
      if (attachCharacter_ >= 0) {
        d_.error(inlined[k].loc, "a character inside a Transform riding on another character's joint; place it "
                                 "beside, under a Transform of its own");
        return -1;
      }
      character = int(k);
    }
    std::optional<Clip> clip;
    const Inlined* clipFrom = nullptr;
    for (Inlined& i : inlined) {
      if (i.kind != Inlined::Kind::Vrml) continue;
      nestedInlines(i);
      {
        const std::vector<WorldTransform> outer = std::exchange(chain_, i.chain);
        for (Prop& p : readProps(*i.file, &d_)) addProp(std::move(p), i.matrix);
        chain_ = outer;
      }
      auto clips = readClips(*i.file, &d_);
      if (!clips) {
        d_.append(clips.error());
        continue;
      }
      if (clips->clips.empty()) {
        if (!i.fragment.empty()) d_.error(i.loc, "'" + i.path + "' has no clips, so '#" + i.fragment + "' names none");
        continue;
      }
      const Clip* chosen = &clips->clips.front();
      if (!i.fragment.empty()) {
        chosen = nullptr;
        std::vector<std::string> names;
        for (const Clip& c : clips->clips) {
          names.push_back(c.name);
          if (c.name == i.fragment) chosen = &c;
        }
        if (chosen == nullptr) {
          const std::string guess = closestMatch(i.fragment, names);
          d_.error(i.loc, "'" + i.path + "' has no clip (TimeSensor) '" + i.fragment + "'" +
                              (guess.empty() ? "" : " (did you mean '" + guess + "'?)"));
          continue;
        }
      }
      if (character < 0) {
        d_.warning(i.loc, "the clip " + chosen->name + " in '" + i.path +
                              "' drives no character: inline it beside a character, in the same children list");
        continue;
      }
      if (clip) {
        d_.warning(i.loc, "a second clip beside the character; the first (" + clip->name + ") plays");
        continue;
      }
      clip = *chosen;
      clipFrom = &i;
    }
    if (character < 0) return -1;
    Inlined& c = inlined[size_t(character)];
    return addCharacter(c, std::move(clip), clipFrom) ? int(characters_.size()) - 1 : -1;
  }

  // An inlined VRML file's own Inlines are not followed (a world is one level deep).
  void nestedInlines(const Inlined& i) {
    std::vector<const VrmlNode*> stack;
    for (const VrmlNodeRef& r : i.file->roots) stack.push_back(r.get());
    size_t visited = 0;
    while (!stack.empty() && ++visited < 100000) {
      const VrmlNode& n = stack.back()->resolved();
      stack.pop_back();
      if (n.type == "Inline") {
        d_.error(i.loc, "'" + i.path + "' inlines further files (line " + std::to_string(n.loc.line) +
                            "); a world inlines characters, clips and props one level deep");
        return;
      }
      for (const VrmlField& f : n.fields)
        for (const VrmlNodeRef& child : f.nodes) stack.push_back(child.get());
    }
  }

  // False after reporting why the character could not be added.
  bool addCharacter(Inlined& c, std::optional<Clip> clip, const Inlined* clipFrom) {
    // The placement must be rigid: IMPS characters' fields are not scaled.
    const glm::mat3 m(c.matrix);
    const float sx = glm::length(m[0]), sy = glm::length(m[1]), sz = glm::length(m[2]);
    constexpr float kTolerance = 1e-4f;
    if (std::abs(sx - 1.0f) > kTolerance || std::abs(sy - 1.0f) > kTolerance || std::abs(sz - 1.0f) > kTolerance ||
        glm::determinant(m) < 0.0f) {
      d_.error(c.loc, "the Transforms above this character scale or mirror it (scale " + std::to_string(sx) + " " +
                          std::to_string(sy) + " " + std::to_string(sz) +
                          "); a character is placed rigidly: scale it in its own scene file");
      return false;
    }
    Diagnostics sceneWarnings;
    auto scene = readSceneFile(c.path, &sceneWarnings);
    d_.append(sceneWarnings);
    if (!scene) {
      d_.note(c.loc, "in the character Inline'd here");
      d_.append(scene.error());
      return false;
    }
    auto character = Character::fromScene(*scene);
    if (!character) {
      d_.note(c.loc, "in the character Inline'd here");
      d_.append(character.error());
      return false;
    }
    Rigid placement;
    placement.rotation = glm::normalize(glm::quat_cast(m));
    placement.translation = glm::vec3(c.matrix[3]);
    std::string name = !c.defName.empty() ? c.defName : !c.nearestDef.empty() ? c.nearestDef
                                                                             : fs::path(c.path).stem().string();
    if (used_.contains(name)) {
      std::string unique;
      for (int k = 2; used_.contains(unique = name + "_" + std::to_string(k)); ++k) {
      }
      d_.warning(c.loc, "a second character named '" + name + "' is called '" + unique + "'");
      name = unique;
    }
    used_[name] = 1;
    characters_.push_back(WorldCharacter{name, c.path, c.loc, placement, std::move(*scene), std::move(*character),
                                         std::move(clip), clipFrom ? clipFrom->path : std::string(),
                                         clipFrom ? clipFrom->loc : SourceLoc{}, c.chain});
    return true;
  }

  const VrmlFile& file_;
  Diagnostics& d_;
  fs::path folder_;
  std::vector<WorldCharacter> characters_;
  std::vector<Prop> props_;
  std::vector<Mesh> propLocal_;
  std::vector<std::vector<WorldTransform>> propChains_;
  std::vector<WorldTransform> chain_;
  std::vector<int> propCharacter_, propJoint_;
  int attachCharacter_ = -1, attachJoint_ = -1;  // inside a Transform riding on a character's joint
  std::map<std::string, int, std::less<>> used_;
};

// The rotation of an affine matrix's linear part with its scale divided out.
Rigid rigidOf(const glm::mat4& m) {
  glm::mat3 r(m);
  for (int k = 0; k < 3; ++k) {
    const float length = glm::length(r[k]);
    if (length > 0.0f) r[k] /= length;
  }
  Rigid out;
  out.rotation = glm::normalize(glm::quat_cast(r));
  out.translation = glm::vec3(m[3]);
  return out;
}

}  // namespace

std::map<std::string, TransformValues, std::less<>> World::transformsAt(double seconds) const {
  std::map<std::string, TransformValues, std::less<>> out;
  for (const Clip& c : clips)
    for (auto& [name, values] : c.sample(c.fraction(seconds))) out[name] = values;
  return out;
}

glm::mat4 World::chainMatrix(const std::vector<WorldTransform>& chain,
                             const std::map<std::string, TransformValues, std::less<>>& moved) {
  glm::mat4 m(1.0f);
  for (const WorldTransform& t : chain) {
    const auto it = t.def.empty() ? moved.end() : moved.find(t.def);
    m = m * (it != moved.end() ? it->second : t.rest).matrix();
  }
  return m;
}

World::Pose World::poseAt(double seconds) const {
  Pose pose;
  const auto moved = transformsAt(seconds);
  for (const WorldCharacter& c : characters)
    pose.placements.push_back(clips.empty() ? c.placement : rigidOf(chainMatrix(c.chain, moved)));
  for (size_t p = 0; p < props.size(); ++p) {
    const bool still = clips.empty() || p >= propLocal.size() || (p < propCharacter.size() && propCharacter[p] >= 0);
    pose.props.push_back(still ? props[p].mesh : transformed(propLocal[p], chainMatrix(propChains[p], moved)));
  }
  return pose;
}

int World::findCharacter(std::string_view name) const {
  for (size_t k = 0; k < characters.size(); ++k)
    if (characters[k].name == name) return int(k);
  return -1;
}

std::vector<std::string> World::characterNames() const {
  std::vector<std::string> names;
  for (const WorldCharacter& c : characters) names.push_back(c.name);
  return names;
}

bool namesImpsNodes(std::string_view text) {
  for (std::string_view word : kImpsNodes) {
    for (size_t at = text.find(word); at != std::string_view::npos; at = text.find(word, at + 1)) {
      const bool before = at == 0 || !isNameChar(text[at - 1]);
      const bool after = at + word.size() == text.size() || !isNameChar(text[at + word.size()]);
      if (before && after) return true;
    }
  }
  return false;
}

std::expected<World, Diagnostics> readWorldFile(const std::string& path, Diagnostics* warnings) {
  Diagnostics d;
  auto file = readVrmlFile(path, &d);
  if (!file) {
    if (warnings != nullptr) warnings->append(d);
    return std::unexpected(file.error());
  }
  WorldReader reader(*file, d);
  reader.siblings(file->roots, "", glm::mat4(1.0f), 0);
  World world = std::move(reader).finish();
  if (auto clips = readClips(*file, &d); clips)
    world.clips = std::move(clips->clips);
  else
    d.append(clips.error());
  if (!d.hasErrors() && world.characters.empty())
    d.warning(SourceLoc{path, 1, 1}, "the world places no character (an Inline of an IMPS scene file)");
  Diagnostics errors, rest;
  for (const Diagnostic& x : d.all()) {
    if (x.severity == Severity::Error) {
      errors.error(x.loc, x.message);
    } else if (x.severity == Severity::Note && d.hasErrors()) {
      errors.note(x.loc, x.message);
    } else if (x.severity == Severity::Warning) {
      rest.warning(x.loc, x.message);
    } else {
      rest.note(x.loc, x.message);
    }
  }
  if (warnings != nullptr) warnings->append(rest);
  if (errors.hasErrors()) return std::unexpected(errors);
  return world;
}

}  // namespace imps
