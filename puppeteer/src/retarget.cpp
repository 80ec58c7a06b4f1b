// SPDX-License-Identifier: MIT
// Retargeting clips onto a character (see retarget.h): name rules, hierarchy checks, rest-pose correction, scale.
#include "retarget.h"

#include "sim/bvh_session.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>

namespace imps::app {
namespace {

// ---- Name rules -------------------------------------------------------------------------------------------------

// Words of a joint name: camelCase, separators and digits split ("LHipJoint" → L Hip Joint, "Spine1" → Spine 1).
std::vector<std::string> words(std::string_view name) {
  std::vector<std::string> out;
  std::string word;
  auto flush = [&] {
    if (!word.empty()) out.push_back(word);
    word.clear();
  };
  for (size_t i = 0; i < name.size(); ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (!std::isalnum(c)) {
      flush();
      continue;
    }
    if (!word.empty()) {
      const auto prev = static_cast<unsigned char>(name[i - 1]);
      const bool next = i + 1 < name.size() && std::islower(static_cast<unsigned char>(name[i + 1]));
      if ((std::isupper(c) && std::islower(prev)) || (std::isupper(c) && std::isupper(prev) && next) ||
          (std::isdigit(c) != 0) != (std::isdigit(prev) != 0))
        flush();
    }
    word += static_cast<char>(std::tolower(c));
  }
  flush();
  return out;
}

struct Rule {
  const char* key;
  BodyRole role;
};
// Keys are the joined words without side and digits.
constexpr std::array kRules = {
    Rule{"hips", BodyRole::Hips},        Rule{"pelvis", BodyRole::Hips},      Rule{"spine", BodyRole::Spine},
    Rule{"lowerback", BodyRole::Spine},  Rule{"chest", BodyRole::Spine},      Rule{"upperchest", BodyRole::Spine},
    Rule{"torso", BodyRole::Spine},      Rule{"abdomen", BodyRole::Spine},    Rule{"upperback", BodyRole::Spine},
    Rule{"neck", BodyRole::Neck},        Rule{"head", BodyRole::Head},        Rule{"clavicle", BodyRole::Clavicle},
    Rule{"collar", BodyRole::Clavicle},  Rule{"collarbone", BodyRole::Clavicle}, Rule{"upperarm", BodyRole::UpperArm},
    Rule{"uparm", BodyRole::UpperArm},   Rule{"arm", BodyRole::UpperArm},     Rule{"humerus", BodyRole::UpperArm},
    Rule{"forearm", BodyRole::Forearm},  Rule{"lowerarm", BodyRole::Forearm}, Rule{"lowarm", BodyRole::Forearm},
    Rule{"elbow", BodyRole::Forearm},    Rule{"radius", BodyRole::Forearm},   Rule{"hand", BodyRole::Hand},
    Rule{"wrist", BodyRole::Hand},       Rule{"upleg", BodyRole::Thigh},      Rule{"upperleg", BodyRole::Thigh},
    Rule{"thigh", BodyRole::Thigh},      Rule{"femur", BodyRole::Thigh},      Rule{"leg", BodyRole::Calf},
    Rule{"lowleg", BodyRole::Calf},      Rule{"lowerleg", BodyRole::Calf},    Rule{"calf", BodyRole::Calf},
    Rule{"shin", BodyRole::Calf},        Rule{"knee", BodyRole::Calf},        Rule{"tibia", BodyRole::Calf},
    Rule{"foot", BodyRole::Foot},        Rule{"ankle", BodyRole::Foot},       Rule{"toe", BodyRole::Toe},
    Rule{"toes", BodyRole::Toe},         Rule{"toebase", BodyRole::Toe},
};

BodyRole lookup(const std::string& key) {
  for (const Rule& r : kRules)
    if (key == r.key) return r.role;
  return BodyRole::None;
}

// Role from key and side, resolving the keys whose meaning depends on the side ("hip") or the hierarchy
// ("shoulder", left to the caller).
void classify(NameRole& r) {
  if (r.key == "hip") r.role = r.side == BodySide::Centre ? BodyRole::Hips : BodyRole::Thigh;
  else if (r.key == "shoulder" && r.side != BodySide::Centre) r.ambiguousShoulder = true, r.role = BodyRole::Clavicle;
  else r.role = lookup(r.key);
}

bool isSide(const std::string& w, BodySide* side) {
  if (w == "l" || w == "left") return *side = BodySide::Left, true;
  if (w == "r" || w == "right") return *side = BodySide::Right, true;
  return false;
}

const char* roleName(BodyRole role) {
  switch (role) {
    case BodyRole::None: return "none";
    case BodyRole::Hips: return "hips";
    case BodyRole::Spine: return "spine";
    case BodyRole::Neck: return "neck";
    case BodyRole::Head: return "head";
    case BodyRole::Clavicle: return "clavicle";
    case BodyRole::UpperArm: return "upper arm";
    case BodyRole::Forearm: return "forearm";
    case BodyRole::Hand: return "hand";
    case BodyRole::Thigh: return "thigh";
    case BodyRole::Calf: return "calf";
    case BodyRole::Foot: return "foot";
    case BodyRole::Toe: return "toe";
  }
  return "?";
}

}  // namespace

NameRole roleFromName(std::string_view name) {
  // A namespace ("mixamorig:Hips") and the Biped's "Bip01 " prefix carry no body part.
  if (const size_t colon = name.rfind(':'); colon != std::string_view::npos) name.remove_prefix(colon + 1);
  std::vector<std::string> w = words(name);
  if (!w.empty() && (w[0] == "bip" || w[0] == "biped")) {
    w.erase(w.begin());
    while (!w.empty() && std::isdigit(static_cast<unsigned char>(w[0][0]))) w.erase(w.begin());
  }
  NameRole r;
  for (const std::string& word : w) {
    if (std::isdigit(static_cast<unsigned char>(word[0]))) continue;
    if (isSide(word, &r.side)) continue;
    r.key += word;
  }
  classify(r);
  // Glued sides: CMU's ASF names ("lhumerus", "rfemur"), "LThumb".
  if (r.role == BodyRole::None && !r.ambiguousShoulder && r.side == BodySide::Centre && r.key.size() > 2 &&
      (r.key[0] == 'l' || r.key[0] == 'r')) {
    NameRole glued = r;
    glued.side = r.key[0] == 'l' ? BodySide::Left : BodySide::Right;
    glued.key = r.key.substr(1);
    classify(glued);
    if (glued.role != BodyRole::None) return glued;
  }
  return r;
}

std::string describeRole(BodyRole role, BodySide side) {
  if (role == BodyRole::None) return "none";
  const char* s = side == BodySide::Left ? "left " : side == BodySide::Right ? "right " : "";
  return s + std::string(roleName(role));
}

size_t RetargetReport::mapped() const {
  return static_cast<size_t>(
      std::count_if(entries.begin(), entries.end(), [](const Entry& e) { return !e.target.empty(); }));
}

std::string RetargetReport::str() const {
  std::string s;
  for (const Entry& e : entries)
    s += "  " + e.source + (e.target.empty() ? " (unmapped)" : " -> " + e.target) + ": " + e.why + "\n";
  if (!characterIdle.empty()) {
    s += "  character joints no clip joint drives (kept at rest):";
    for (const std::string& j : characterIdle) s += " " + j;
    s += "\n";
  }
  char scale[64];
  std::snprintf(scale, sizeof scale, "%.6g", translationScale);
  s += "  translation scale " + std::string(scale) + " m per clip unit: " + scaleWhy + "\n";
  return s;
}

namespace {

// ---- Matching ---------------------------------------------------------------------------------------------------

bool isAncestor(const sim::BvhClip& clip, int ancestor, int joint) {
  for (int j = joint; j >= 0; j = clip.joints[static_cast<size_t>(j)].parent)
    if (j == ancestor) return true;
  return false;
}

// Clip roles with "shoulder" resolved by the hierarchy: a clavicle when a child is an upper arm by name.
std::vector<NameRole> clipRoles(const sim::BvhClip& clip) {
  std::vector<NameRole> roles;
  for (const sim::BvhJoint& j : clip.joints) roles.push_back(roleFromName(j.name));
  for (size_t j = 0; j < roles.size(); ++j) {
    if (!roles[j].ambiguousShoulder) continue;
    bool armBelow = false;
    for (size_t k = j + 1; k < roles.size(); ++k)
      if (clip.joints[k].parent == static_cast<int>(j) && roles[k].role == BodyRole::UpperArm) armBelow = true;
    roles[j].role = armBelow ? BodyRole::Clavicle : BodyRole::UpperArm;
  }
  return roles;
}

std::vector<NameRole> characterRoles(const Character& character) {
  std::vector<NameRole> roles;
  for (const Joint& j : character.joints()) roles.push_back(roleFromName(j.name));
  for (size_t j = 0; j < roles.size(); ++j) {
    if (!roles[j].ambiguousShoulder) continue;
    bool armBelow = false;
    for (size_t k = 0; k < roles.size(); ++k)
      if (character.joints()[k].parent == static_cast<int>(j) && roles[k].role == BodyRole::UpperArm) armBelow = true;
    roles[j].role = armBelow ? BodyRole::Clavicle : BodyRole::UpperArm;
  }
  return roles;
}

// Nearest ancestor of character joint j that has a source, or -1.
int mappedAncestor(const Character& character, const std::vector<int>& source, int j) {
  for (int a = character.joints()[static_cast<size_t>(j)].parent; a >= 0;
       a = character.joints()[static_cast<size_t>(a)].parent)
    if (source[static_cast<size_t>(a)] >= 0) return a;
  return -1;
}

// Automatic: per character joint with a role, the k-th clip joint of the same role and side for its k-th
// occurrence, kept only when the hierarchy agrees (its mapped character ancestor's clip joint is a clip ancestor).
std::vector<int> autoSources(const sim::BvhClip& clip, const Character& character, RetargetReport& report,
                             std::vector<std::string>& why) {
  const std::vector<NameRole> cr = clipRoles(clip), jr = characterRoles(character);
  const size_t n = character.joints().size();
  std::vector<int> source(n, -1);
  std::vector<int> used(clip.joints.size(), 0);
  for (size_t j = 0; j < n; ++j) {
    if (jr[j].role == BodyRole::None) continue;
    size_t occurrence = 0;
    for (size_t k = 0; k < j; ++k)
      if (jr[k].role == jr[j].role && jr[k].side == jr[j].side) ++occurrence;
    size_t seen = 0;
    for (size_t c = 0; c < clip.joints.size(); ++c) {
      if (cr[c].role != jr[j].role || cr[c].side != jr[j].side) continue;
      if (seen++ != occurrence) continue;
      const int ancestor = mappedAncestor(character, source, static_cast<int>(j));
      if (ancestor >= 0 && !isAncestor(clip, source[static_cast<size_t>(ancestor)], static_cast<int>(c))) {
        why[c] = describeRole(cr[c].role, cr[c].side) + " by name, but the hierarchy disagrees: '" +
                 clip.joints[static_cast<size_t>(source[static_cast<size_t>(ancestor)])].name +
                 "' (driving " + character.joints()[static_cast<size_t>(ancestor)].name + ") is not above it";
        used[c] = -1;
        break;
      }
      source[j] = static_cast<int>(c);
      used[c] = 1;
      why[c] = describeRole(cr[c].role, cr[c].side) + " (name rule '" + cr[c].key + "'" +
               (cr[c].key == "shoulder" ? std::string(cr[c].role == BodyRole::Clavicle ? ", above an arm joint"
                                                                                       : ", no arm joint below it")
                                        : std::string()) +
               ")";
      break;
    }
  }
  for (size_t c = 0; c < clip.joints.size(); ++c) {
    if (used[c] != 0) continue;
    if (cr[c].role == BodyRole::None)
      why[c] = cr[c].key == "hipjoint" || cr[c].key.empty()
                   ? "a helper joint: no body part, its rotation still reaches the joints below it"
                   : "no name rule for '" + cr[c].key + "'; its rotation still reaches the joints below it";
    else
      why[c] = describeRole(cr[c].role, cr[c].side) + " by name, but the character has no further " +
               describeRole(cr[c].role, cr[c].side) + " joint to drive";
  }
  (void)report;
  return source;
}

// ---- Geometry ---------------------------------------------------------------------------------------------------

glm::dquat channelRotation(const sim::BvhJoint& joint, std::span<const float> values) {
  glm::dquat q{1.0, 0.0, 0.0, 0.0};
  for (size_t k = 0; k < joint.channels.size(); ++k) {
    if (!sim::isRotation(joint.channels[k])) continue;
    glm::dvec3 axis{0.0};
    axis[static_cast<int>(joint.channels[k]) - static_cast<int>(sim::BvhChannel::Xrotation)] = 1.0;
    q = q * glm::angleAxis(glm::radians(static_cast<double>(values[k])), axis);
  }
  return q;
}

glm::dvec3 offsetOf(const sim::BvhJoint& j) { return {j.offset[0], j.offset[1], j.offset[2]}; }

// The shortest rotation taking unit vector a onto unit vector b.
glm::dquat shortestArc(const glm::dvec3& a, const glm::dvec3& b) {
  const double d = glm::dot(a, b);
  if (d < -1.0 + 1e-12) {
    glm::dvec3 axis = glm::cross(glm::dvec3(1, 0, 0), a);
    if (glm::length(axis) < 1e-6) axis = glm::cross(glm::dvec3(0, 1, 0), a);
    return glm::angleAxis(glm::pi<double>(), glm::normalize(axis));
  }
  const glm::dvec3 c = glm::cross(a, b);
  return glm::normalize(glm::dquat(1.0 + d, c.x, c.y, c.z));
}

// Sum of link lengths from clip joint `from` (exclusive) down to `to` (inclusive); 0 when `to` is not below `from`.
double clipChainLength(const sim::BvhClip& clip, int from, int to) {
  if (from < 0 || to < 0 || !isAncestor(clip, from, to)) return 0;
  double length = 0;
  for (int j = to; j != from; j = clip.joints[static_cast<size_t>(j)].parent)
    length += glm::length(offsetOf(clip.joints[static_cast<size_t>(j)]));
  return length;
}

double characterChainLength(const Character& character, int from, int to) {
  double length = 0;
  for (int j = to; j >= 0; j = character.joints()[static_cast<size_t>(j)].parent) {
    if (j == from) return length;
    length += glm::length(character.joints()[static_cast<size_t>(j)].rest.translation);
  }
  return 0;
}

}  // namespace

std::expected<Retargeter, Diagnostics> Retargeter::create(const sim::BvhClip& clip, const Character& character,
                                                          const RetargetOptions& options) {
  const auto fail = [](std::string why) { return std::unexpected(singleError({}, std::move(why))); };
  if (clip.joints.empty()) return fail("the clip has no joints");
  if (options.restFrame >= 0 && static_cast<size_t>(options.restFrame) >= clip.frames.size())
    return fail("rest frame " + std::to_string(options.restFrame) + " is beyond the clip's " +
                std::to_string(clip.frames.size()) + " frames");
  Retargeter r;
  r.clip_ = clip;
  r.clip_.frames.clear();
  r.character_ = &character;
  const size_t n = character.joints().size();
  std::vector<std::string> why(clip.joints.size());

  // 1. Which clip joint drives which character joint.
  if (options.map == RetargetOptions::Map::Auto) {
    r.source_ = autoSources(clip, character, r.report_, why);
  } else {
    r.source_.assign(n, -1);
    std::vector<calibration::JointMatch> matches = options.matches;
    if (options.map == RetargetOptions::Map::Names)
      for (const sim::BvhJoint& j : clip.joints)
        if (character.findJoint(j.name) >= 0) matches.push_back({j.name, j.name, {}});
    for (const calibration::JointMatch& m : matches) {
      const int target = character.findJoint(m.character);
      auto it = std::find_if(clip.joints.begin(), clip.joints.end(),
                             [&](const sim::BvhJoint& j) { return j.name == m.source; });
      if (target < 0 || it == clip.joints.end())
        return fail("joint map: '" + m.source + "' -> '" + m.character + "' names a joint that is not there");
      const auto c = static_cast<size_t>(it - clip.joints.begin());
      r.source_[static_cast<size_t>(target)] = static_cast<int>(c);
      why[c] = options.map == RetargetOptions::Map::Names ? "same name"
                                                          : "joint map line " + std::to_string(m.loc.line);
    }
    for (size_t c = 0; c < clip.joints.size(); ++c)
      if (why[c].empty())
        why[c] = options.map == RetargetOptions::Map::Names ? "the character has no joint of that name"
                                                            : "not in the joint map";
  }
  std::vector<int> target(clip.joints.size(), -1);
  for (size_t j = 0; j < n; ++j)
    if (r.source_[j] >= 0) target[static_cast<size_t>(r.source_[j])] = static_cast<int>(j);
  for (size_t c = 0; c < clip.joints.size(); ++c)
    r.report_.entries.push_back(
        {clip.joints[c].name, target[c] >= 0 ? character.joints()[static_cast<size_t>(target[c])].name : "", why[c]});
  for (size_t j = 0; j < n; ++j)
    if (r.source_[j] < 0) r.report_.characterIdle.push_back(character.joints()[j].name);

  // 2. Rest poses: the clip's world rotations and positions, the character's.
  std::vector<glm::dquat> clipRest(clip.joints.size(), glm::dquat{1.0, 0.0, 0.0, 0.0});
  if (options.restFrame >= 0) r.clipWorldRotations(clip.frames[static_cast<size_t>(options.restFrame)], clipRest);
  r.restWorld_.resize(n);
  std::vector<glm::dvec3> restPosition(n);
  for (size_t j = 0; j < n; ++j) {
    const Joint& joint = character.joints()[j];
    const glm::dquat local(joint.rest.rotation);
    const glm::dvec3 t(joint.rest.translation);
    if (joint.parent < 0) {
      r.restWorld_[j] = local, restPosition[j] = t;
    } else {
      const auto p = static_cast<size_t>(joint.parent);
      r.restWorld_[j] = r.restWorld_[p] * local;
      restPosition[j] = restPosition[p] + r.restWorld_[p] * t;
    }
  }

  // 3. Bones: per mapped joint, its mapped child (same side first) and the rest-pose correction.
  const std::vector<NameRole> roles = characterRoles(character);
  r.bones_.resize(n);
  r.posed_.assign(n, false);
  std::vector<glm::dquat> correction(n, glm::dquat{1.0, 0.0, 0.0, 0.0});  // C_J, inherited by joints without a bone
  for (size_t j = 0; j < n; ++j) {
    const int parent = character.joints()[j].parent;
    if (parent >= 0) correction[j] = correction[static_cast<size_t>(parent)];
    const int s = r.source_[j];
    if (s < 0) continue;
    int child = -1;
    for (size_t k = j + 1; k < n; ++k) {
      if (r.source_[k] < 0 || mappedAncestor(character, r.source_, static_cast<int>(k)) != static_cast<int>(j))
        continue;
      if (!isAncestor(clip, s, r.source_[k]) || r.source_[k] == s) continue;
      // The bone continues the body part: a centre joint's centre child (hips → spine, spine → neck), a side joint's
      // child on that side; a hips with only legs and arms below it has no bone and keeps C = identity.
      if (roles[j].role != BodyRole::None && roles[k].side != roles[j].side) continue;
      if (child < 0) child = static_cast<int>(k);
    }
    Bone bone{s, glm::inverse(clipRest[static_cast<size_t>(s)]) * correction[j]};
    if (child >= 0) {
      // The last link with a length before the child's clip joint.
      int c = r.source_[static_cast<size_t>(child)];
      while (glm::length(offsetOf(clip.joints[static_cast<size_t>(c)])) < 1e-9 &&
             clip.joints[static_cast<size_t>(c)].parent != s)
        c = clip.joints[static_cast<size_t>(c)].parent;
      const int p = clip.joints[static_cast<size_t>(c)].parent;
      const glm::dvec3 clipDir = clipRest[static_cast<size_t>(p)] * offsetOf(clip.joints[static_cast<size_t>(c)]);
      const glm::dvec3 charDir = restPosition[static_cast<size_t>(child)] - restPosition[j];
      if (glm::length(clipDir) > 1e-9 && glm::length(charDir) > 1e-9) {
        correction[j] = shortestArc(glm::normalize(charDir), glm::normalize(clipDir));
        bone = {p, glm::inverse(clipRest[static_cast<size_t>(p)]) * correction[j]};
      }
    }
    r.bones_[j] = bone;
  }
  // Joints between driven ones (and the driven ones) are in the output.
  for (size_t j = 0; j < n; ++j)
    if (r.source_[j] >= 0)
      for (int a = static_cast<int>(j); a >= 0 && !r.posed_[static_cast<size_t>(a)];
           a = character.joints()[static_cast<size_t>(a)].parent)
        r.posed_[static_cast<size_t>(a)] = true;

  // 4. Translation scale: leg length (thigh to foot), else standing height.
  const std::vector<NameRole> jr = roles;
  auto findRole = [&](BodyRole role, BodySide side) {
    for (size_t j = 0; j < n; ++j)
      if (jr[j].role == role && jr[j].side == side && r.source_[j] >= 0) return static_cast<int>(j);
    return -1;
  };
  for (BodySide side : {BodySide::Left, BodySide::Right}) {
    const int thigh = findRole(BodyRole::Thigh, side), foot = findRole(BodyRole::Foot, side);
    if (thigh < 0 || foot < 0) continue;
    const double charLeg = characterChainLength(character, thigh, foot);
    const double clipLeg =
        clipChainLength(clip, r.source_[static_cast<size_t>(thigh)], r.source_[static_cast<size_t>(foot)]);
    if (charLeg > 0 && clipLeg > 0) {
      r.report_.translationScale = charLeg / clipLeg;
      char text[160];
      std::snprintf(text, sizeof text, "%s leg %.4g m (%s to %s) / clip leg %.4g units",
                    side == BodySide::Left ? "left" : "right", charLeg,
                    character.joints()[static_cast<size_t>(thigh)].name.c_str(),
                    character.joints()[static_cast<size_t>(foot)].name.c_str(), clipLeg);
      r.report_.scaleWhy = text;
      break;
    }
  }
  if (r.report_.scaleWhy.empty()) {
    // Standing height: the spread of joint heights at rest.
    double cLo = 0, cHi = 0, kLo = 0, kHi = 0;
    std::vector<glm::dvec3> clipPos(clip.joints.size());
    for (size_t c = 0; c < clip.joints.size(); ++c) {
      const int p = clip.joints[c].parent;
      clipPos[c] = (p >= 0 ? clipPos[static_cast<size_t>(p)] : glm::dvec3(0.0)) + offsetOf(clip.joints[c]);
      cLo = c ? std::min(cLo, clipPos[c].y) : clipPos[c].y, cHi = c ? std::max(cHi, clipPos[c].y) : clipPos[c].y;
    }
    for (size_t j = 0; j < n; ++j)
      kLo = j ? std::min(kLo, restPosition[j].y) : restPosition[j].y,
      kHi = j ? std::max(kHi, restPosition[j].y) : restPosition[j].y;
    if (cHi - cLo > 1e-9 && kHi - kLo > 1e-9) {
      r.report_.translationScale = (kHi - kLo) / (cHi - cLo);
      r.report_.scaleWhy = "no leg mapped: character height / clip height (spread of joint heights at rest)";
    } else {
      r.report_.scaleWhy = "no leg mapped and no height to compare: 1";
    }
  }
  // 5. Translations: a driven joint's own position channels; the character's root also takes the clip root's when
  // its own clip joint has none (3ds-Max Biped: "Bip01" moves, "Bip01 Pelvis" only turns).
  r.translationSource_.assign(n, -1);
  auto hasPositions = [&](int c) {
    return c >= 0 && std::any_of(clip.joints[static_cast<size_t>(c)].channels.begin(),
                                 clip.joints[static_cast<size_t>(c)].channels.end(),
                                 [](sim::BvhChannel ch) { return !sim::isRotation(ch); });
  };
  for (size_t j = 0; j < n; ++j) {
    if (hasPositions(r.source_[j])) r.translationSource_[j] = r.source_[j];
    else if (character.joints()[j].parent < 0 && r.source_[j] >= 0 && hasPositions(0)) r.translationSource_[j] = 0;
  }
  r.reference_.assign(clip.joints.size(), glm::dvec3(0.0));
  if (!clip.frames.empty()) r.setReferenceFrame(clip.frames.front());
  return r;
}

int Retargeter::targetOf(size_t clipJoint) const {
  for (size_t j = 0; j < source_.size(); ++j)
    if (source_[j] == static_cast<int>(clipJoint)) return static_cast<int>(j);
  return -1;
}

void Retargeter::clipWorldRotations(std::span<const float> frame, std::vector<glm::dquat>& out) const {
  out.resize(clip_.joints.size());
  size_t channel = 0;
  for (size_t c = 0; c < clip_.joints.size(); ++c) {
    const sim::BvhJoint& joint = clip_.joints[c];
    const glm::dquat local = channelRotation(joint, frame.subspan(channel, joint.channels.size()));
    channel += joint.channels.size();
    out[c] = joint.parent >= 0 ? out[static_cast<size_t>(joint.parent)] * local : local;
  }
}

glm::dvec3 Retargeter::positionChannels(std::span<const float> frame, size_t clipJoint) const {
  const size_t first = clip_.firstChannel(clipJoint);
  glm::dvec3 p(0.0);
  const sim::BvhJoint& joint = clip_.joints[clipJoint];
  for (size_t k = 0; k < joint.channels.size(); ++k)
    if (!sim::isRotation(joint.channels[k])) p[static_cast<int>(joint.channels[k])] = frame[first + k];
  return p;
}

void Retargeter::setReferenceFrame(std::span<const float> frame) {
  if (frame.size() < clip_.channelCount()) return;
  for (size_t c = 0; c < clip_.joints.size(); ++c) reference_[c] = positionChannels(frame, c);
}

void Retargeter::pose(std::span<const float> frame, std::vector<JointPose>& out) const {
  std::vector<glm::dquat> clipWorld;
  clipWorldRotations(frame, clipWorld);
  const auto& joints = character_->joints();
  std::vector<glm::dquat> world(joints.size());
  out.clear();
  for (size_t j = 0; j < joints.size(); ++j) {
    const Joint& joint = joints[j];
    const glm::dquat parentWorld =
        joint.parent >= 0 ? world[static_cast<size_t>(joint.parent)] : glm::dquat{1.0, 0.0, 0.0, 0.0};
    const Bone& bone = bones_[j];
    world[j] = source_[j] >= 0 ? clipWorld[static_cast<size_t>(bone.source)] * bone.correction * restWorld_[j]
                               : parentWorld * glm::dquat(joint.rest.rotation);
    if (!posed_[j]) continue;
    JointPose p;
    p.joint = joint.name;
    p.rotation = glm::normalize(glm::quat(glm::inverse(parentWorld) * world[j]));
    const int s = translationSource_[j];
    if (s >= 0) {
      const sim::BvhJoint& clipJoint = clip_.joints[static_cast<size_t>(s)];
      const bool moves = std::any_of(clipJoint.channels.begin(), clipJoint.channels.end(),
                                     [](sim::BvhChannel c) { return !sim::isRotation(c); });
      if (moves) {
        const glm::dquat clipParent =
            clipJoint.parent >= 0 ? clipWorld[static_cast<size_t>(clipJoint.parent)] : glm::dquat{1.0, 0.0, 0.0, 0.0};
        const glm::dvec3 delta =
            clipParent * (positionChannels(frame, static_cast<size_t>(s)) - reference_[static_cast<size_t>(s)]);
        p.hasTranslation = true;
        p.translation = joint.rest.translation +
                        glm::vec3(glm::inverse(parentWorld) * (report_.translationScale * delta));
      }
    }
    out.push_back(std::move(p));
  }
}

double sessionChannelValue(uint32_t counts, bool rotation, int bits, double positionUnitsPerCount) {
  if (rotation) return sim::countsToDegrees(counts, bits);
  const auto half = int64_t{1} << (bits - 1);
  return static_cast<double>(static_cast<int64_t>(counts) - half) * positionUnitsPerCount;
}

}  // namespace imps::app
