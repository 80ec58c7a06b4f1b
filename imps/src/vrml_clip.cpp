// SPDX-License-Identifier: MIT
// Clips from VRML 97 ROUTEs: TimeSensor -> interpolators -> Transforms (see vrml_clip.h).
#include "imps/vrml_clip.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <optional>
#include <set>

#include <glm/gtc/matrix_transform.hpp>

#include "imps/check.h"

namespace imps {

namespace {

// ---- The node interfaces routes are checked against (ISO/IEC 14772-1 clause 6) ----

enum class Access { Field, ExposedField, EventIn, EventOut };

struct InterfaceField {
  const char* name;
  Access access;
  const char* type;
};

struct NodeInterface {
  const char* node;
  std::vector<InterfaceField> fields;
};

const std::vector<NodeInterface>& interfaces() {
  static const std::vector<NodeInterface> table = {
      {"Transform",
       {{"addChildren", Access::EventIn, "MFNode"}, {"removeChildren", Access::EventIn, "MFNode"},
        {"center", Access::ExposedField, "SFVec3f"}, {"children", Access::ExposedField, "MFNode"},
        {"rotation", Access::ExposedField, "SFRotation"}, {"scale", Access::ExposedField, "SFVec3f"},
        {"scaleOrientation", Access::ExposedField, "SFRotation"}, {"translation", Access::ExposedField, "SFVec3f"},
        {"bboxCenter", Access::Field, "SFVec3f"}, {"bboxSize", Access::Field, "SFVec3f"}}},
      {"Group",
       {{"addChildren", Access::EventIn, "MFNode"}, {"removeChildren", Access::EventIn, "MFNode"},
        {"children", Access::ExposedField, "MFNode"}, {"bboxCenter", Access::Field, "SFVec3f"},
        {"bboxSize", Access::Field, "SFVec3f"}}},
      {"TimeSensor",
       {{"cycleInterval", Access::ExposedField, "SFTime"}, {"enabled", Access::ExposedField, "SFBool"},
        {"loop", Access::ExposedField, "SFBool"}, {"startTime", Access::ExposedField, "SFTime"},
        {"stopTime", Access::ExposedField, "SFTime"}, {"cycleTime", Access::EventOut, "SFTime"},
        {"fraction_changed", Access::EventOut, "SFFloat"}, {"isActive", Access::EventOut, "SFBool"},
        {"time", Access::EventOut, "SFTime"}}},
      {"PositionInterpolator",
       {{"set_fraction", Access::EventIn, "SFFloat"}, {"key", Access::ExposedField, "MFFloat"},
        {"keyValue", Access::ExposedField, "MFVec3f"}, {"value_changed", Access::EventOut, "SFVec3f"}}},
      {"OrientationInterpolator",
       {{"set_fraction", Access::EventIn, "SFFloat"}, {"key", Access::ExposedField, "MFFloat"},
        {"keyValue", Access::ExposedField, "MFRotation"}, {"value_changed", Access::EventOut, "SFRotation"}}},
      {"ScalarInterpolator",
       {{"set_fraction", Access::EventIn, "SFFloat"}, {"key", Access::ExposedField, "MFFloat"},
        {"keyValue", Access::ExposedField, "MFFloat"}, {"value_changed", Access::EventOut, "SFFloat"}}},
      {"Material",
       {{"ambientIntensity", Access::ExposedField, "SFFloat"}, {"diffuseColor", Access::ExposedField, "SFColor"},
        {"emissiveColor", Access::ExposedField, "SFColor"}, {"shininess", Access::ExposedField, "SFFloat"},
        {"specularColor", Access::ExposedField, "SFColor"}, {"transparency", Access::ExposedField, "SFFloat"}}},
  };
  return table;
}

const NodeInterface* interfaceOf(const std::string& type) {
  for (const NodeInterface& i : interfaces())
    if (type == i.node) return &i;
  return nullptr;
}

// A route's end resolved to a node of a known type and one of its interface fields.
struct RouteEnd {
  const VrmlNode* node = nullptr;  // the built-in node (a PROTO instance's body node)
  std::string defName;             // as the ROUTE names it
  const InterfaceField* field = nullptr;
};

// Finds `written` (`set_x`, `x_changed` or `x`) among the interface's fields usable as a route's source (`out`) or
// destination; reports why not otherwise.
const InterfaceField* findEventField(const NodeInterface& iface, const std::string& written, bool out,
                                     const std::string& defName, const SourceLoc& loc, Diagnostics& d) {
  std::string plain = written;
  if (!out && plain.starts_with("set_")) plain = plain.substr(4);
  if (out && plain.ends_with("_changed")) plain = plain.substr(0, plain.size() - 8);
  for (const InterfaceField& f : iface.fields) {
    const bool exact = written == f.name;
    const bool viaPrefix = plain == f.name && f.access == Access::ExposedField;
    if (!exact && !viaPrefix) continue;
    if (f.access == Access::Field) {
      d.error(loc, std::string(iface.node) + " " + defName + "." + f.name + " is a plain field, not an " +
                       (out ? "eventOut or exposedField" : "eventIn or exposedField") +
                       ": a ROUTE cannot " + (out ? "read" : "change") + " it");
      return nullptr;
    }
    if (out && f.access == Access::EventIn) {
      d.error(loc,
              std::string(iface.node) + " " + defName + "." + f.name + " is an eventIn: a ROUTE cannot start there");
      return nullptr;
    }
    if (!out && f.access == Access::EventOut) {
      d.error(loc,
              std::string(iface.node) + " " + defName + "." + f.name + " is an eventOut: a ROUTE cannot end there");
      return nullptr;
    }
    return &f;
  }
  std::vector<std::string> names;
  for (const InterfaceField& f : iface.fields) {
    names.push_back(f.name);
    if (f.access == Access::ExposedField)
      names.push_back(out ? std::string(f.name) + "_changed" : "set_" + std::string(f.name));
  }
  const std::string guess = closestMatch(written, names);
  d.error(loc, std::string(iface.node) + " " + defName + " has no " + (out ? "eventOut" : "eventIn") + " '" + written +
                   "'" + (guess.empty() ? std::string() : " (did you mean '" + guess + "'?)"));
  return nullptr;
}

// Resolves one end of a route: a built-in node, or an H-Anim-style PROTO instance whose field is linked (IS) to
// a body node's field. Returns false when the end is not a node this module checks (no error), or on an error.
bool resolveEnd(const VrmlFile& file, const std::string& defName, const std::string& field, bool out,
                const SourceLoc& loc, RouteEnd& end, Diagnostics& d, bool& failed) {
  const auto found = file.defs.find(defName);
  if (found == file.defs.end()) return false;  // reported by readVrml
  const VrmlNode* node = found->second.get();
  std::string fieldName = field;
  if (node->protoBody) {
    std::string plain = field;
    if (plain.starts_with("set_")) plain = plain.substr(4);
    if (plain.ends_with("_changed")) plain = plain.substr(0, plain.size() - 8);
    const VrmlIsLink* link = nullptr;
    for (const VrmlIsLink& l : node->isLinks)
      if (l.interfaceField == field || l.interfaceField == plain) link = &l;
    if (link == nullptr) return false;  // the PROTO's own events (not linked to its body): not ours to check
    node = link->bodyNode.get();
    fieldName = link->bodyField;
  }
  const NodeInterface* iface = interfaceOf(node->type);
  if (iface == nullptr) return false;
  end.node = node;
  end.defName = defName;
  end.field = findEventField(*iface, fieldName, out, defName, loc, d);
  if (end.field == nullptr) failed = true;
  return end.field != nullptr;
}

// ---- Reading values ----

glm::vec3 vec3Of(const VrmlField* f, glm::vec3 fallback) {
  if (f == nullptr || f->numbers.size() != 3) return fallback;
  return {static_cast<float>(f->numbers[0]), static_cast<float>(f->numbers[1]), static_cast<float>(f->numbers[2])};
}

glm::quat axisAngle(double x, double y, double z, double angle) {
  const glm::vec3 axis(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  const float length = glm::length(axis);
  if (!(length > 0.0f) || !std::isfinite(length)) return {1.0f, 0.0f, 0.0f, 0.0f};
  return glm::angleAxis(static_cast<float>(angle), axis / length);
}

glm::quat rotationOf(const VrmlField* f) {
  if (f == nullptr || f->numbers.size() != 4) return {1.0f, 0.0f, 0.0f, 0.0f};
  return axisAngle(f->numbers[0], f->numbers[1], f->numbers[2], f->numbers[3]);
}

TransformValues restOf(const VrmlNode& node) {
  TransformValues v;
  v.translation = vec3Of(node.field("translation"), v.translation);
  v.rotation = rotationOf(node.field("rotation"));
  v.scale = vec3Of(node.field("scale"), v.scale);
  v.scaleOrientation = rotationOf(node.field("scaleOrientation"));
  v.center = vec3Of(node.field("center"), v.center);
  return v;
}

// An interpolator's key and keyValue, checked: as many values as keys (of `width` numbers each), keys ascending.
bool readKeys(const VrmlNode& interp, const std::string& defName, size_t width, std::vector<float>& keys,
              std::vector<double>& values, Diagnostics& d) {
  const VrmlField* key = interp.field("key");
  const VrmlField* keyValue = interp.field("keyValue");
  if (key != nullptr) keys.assign(key->numbers.begin(), key->numbers.end());
  if (keyValue != nullptr) values = keyValue->numbers;
  const SourceLoc loc = keyValue != nullptr ? keyValue->loc : key != nullptr ? key->loc : interp.loc;
  if (values.size() % width != 0) {
    d.error(loc, interp.type + " " + defName + ": keyValue has " + std::to_string(values.size()) +
                     " numbers, not a multiple of " + std::to_string(width));
    return false;
  }
  if (values.size() / width != keys.size()) {
    d.error(loc, interp.type + " " + defName + ": " + std::to_string(keys.size()) + " keys but " +
                     std::to_string(values.size() / width) + " keyValues; they must be as many");
    return false;
  }
  for (size_t i = 1; i < keys.size(); ++i) {
    if (keys[i] < keys[i - 1]) {
      char shown[32];
      const auto end = std::to_chars(shown, shown + sizeof shown, keys[i]).ptr;
      d.error(key->valueLoc, interp.type + " " + defName + ": key " + std::to_string(i) + " (" +
                                 std::string(shown, end) + ") is less than the key before it; keys must not decrease");
      return false;
    }
  }
  return true;
}

bool isInterpolator(const std::string& type) {
  return type == "PositionInterpolator" || type == "OrientationInterpolator" || type == "ScalarInterpolator";
}

std::optional<ClipProperty> propertyOf(const std::string& field) {
  if (field == "translation") return ClipProperty::Translation;
  if (field == "rotation") return ClipProperty::Rotation;
  if (field == "scale") return ClipProperty::Scale;
  if (field == "scaleOrientation") return ClipProperty::ScaleOrientation;
  if (field == "center") return ClipProperty::Center;
  return std::nullopt;
}

// The segment of `keys` holding `fraction` and how far along it: (i, t) with the value lerp(v[i], v[i+1], t), or
// (last, 0) past the end / (0, 0) before the start.
std::pair<size_t, float> segment(std::span<const float> keys, float fraction) {
  if (keys.empty() || !(fraction > keys.front())) return {0, 0.0f};
  const auto upper = std::upper_bound(keys.begin(), keys.end(), fraction);
  if (upper == keys.end()) return {keys.size() - 1, 0.0f};
  const size_t i = static_cast<size_t>(upper - keys.begin()) - 1;
  const float span = keys[i + 1] - keys[i];
  return {i, span > 0.0f ? (fraction - keys[i]) / span : 0.0f};
}

}  // namespace

glm::vec3 interpolatePosition(std::span<const float> keys, std::span<const glm::vec3> values, float fraction) {
  IMPS_CHECK_EQ(keys.size(), values.size());
  if (keys.empty()) return glm::vec3(0.0f);
  const auto [i, t] = segment(keys, fraction);
  if (t == 0.0f) return values[i];
  return values[i] + (values[i + 1] - values[i]) * t;
}

glm::quat interpolateOrientation(std::span<const float> keys, std::span<const glm::quat> values, float fraction) {
  IMPS_CHECK_EQ(keys.size(), values.size());
  if (keys.empty()) return {1.0f, 0.0f, 0.0f, 0.0f};
  const auto [i, t] = segment(keys, fraction);
  if (t == 0.0f) return values[i];
  glm::quat b = values[i + 1];
  if (glm::dot(values[i], b) < 0.0f) b = -b;  // the shorter arc
  return glm::normalize(glm::slerp(values[i], b, t));
}

float interpolateScalar(std::span<const float> keys, std::span<const float> values, float fraction) {
  IMPS_CHECK_EQ(keys.size(), values.size());
  if (keys.empty()) return 0.0f;
  const auto [i, t] = segment(keys, fraction);
  if (t == 0.0f) return values[i];
  return values[i] + (values[i + 1] - values[i]) * t;
}

glm::mat4 TransformValues::matrix() const {
  const glm::mat4 identity(1.0f);
  const glm::mat4 so = glm::mat4_cast(scaleOrientation);
  return glm::translate(identity, translation) * glm::translate(identity, center) * glm::mat4_cast(rotation) * so *
         glm::scale(identity, scale) * glm::transpose(so) * glm::translate(identity, -center);
}

const char* clipPropertyName(ClipProperty property) {
  switch (property) {
    case ClipProperty::Translation: return "translation";
    case ClipProperty::Rotation: return "rotation";
    case ClipProperty::Scale: return "scale";
    case ClipProperty::ScaleOrientation: return "scaleOrientation";
    case ClipProperty::Center: return "center";
  }
  return "?";
}

std::vector<std::string> Clip::targets() const {
  std::vector<std::string> names;
  for (const auto& entry : rest) names.push_back(entry.first);
  return names;
}

double Clip::fraction(double seconds, bool forceLoop) const {
  const double cycles = seconds / cycleInterval;
  if (!std::isfinite(cycles) || cycles <= 0.0) return 0.0;
  if (loop || forceLoop) return cycles - std::floor(cycles);
  return std::min(cycles, 1.0);
}

std::map<std::string, TransformValues, std::less<>> Clip::sample(double fraction) const {
  auto values = rest;
  const auto f = static_cast<float>(fraction);
  for (const ClipTrack& track : tracks) {
    TransformValues& v = values[track.target];
    switch (track.property) {
      case ClipProperty::Translation: v.translation = interpolatePosition(track.keys, track.positions, f); break;
      case ClipProperty::Scale: v.scale = interpolatePosition(track.keys, track.positions, f); break;
      case ClipProperty::Center: v.center = interpolatePosition(track.keys, track.positions, f); break;
      case ClipProperty::Rotation: v.rotation = interpolateOrientation(track.keys, track.rotations, f); break;
      case ClipProperty::ScaleOrientation:
        v.scaleOrientation = interpolateOrientation(track.keys, track.rotations, f);
        break;
    }
  }
  return values;
}

std::expected<Clips, Diagnostics> readClips(const VrmlFile& file, Diagnostics* warnings) {
  Diagnostics d;
  Clips result;
  // Pass 1: check every route whose ends this module knows, and collect the two links of a clip chain.
  struct Link {
    RouteEnd from, to;
    SourceLoc loc;
  };
  std::vector<Link> sensorToInterp, interpToTarget;
  bool failed = false;
  for (const VrmlRoute& r : file.routes) {
    Link link{{}, {}, r.loc};
    const bool fromKnown = resolveEnd(file, r.fromNode, r.fromField, true, r.loc, link.from, d, failed);
    const bool toKnown = resolveEnd(file, r.toNode, r.toField, false, r.loc, link.to, d, failed);
    if (!fromKnown || !toKnown) continue;
    if (std::string(link.from.field->type) != link.to.field->type) {
      d.error(r.loc, "ROUTE from " + r.fromNode + "." + r.fromField + " (" + link.from.field->type + ") to " +
                         r.toNode + "." + r.toField + " (" + link.to.field->type + "): the types differ");
      failed = true;
      continue;
    }
    const std::string fromType = link.from.node->type;
    if (fromType == "TimeSensor" && isInterpolator(link.to.node->type) &&
        std::string(link.to.field->name) == "set_fraction")
      sensorToInterp.push_back(link);
    else if (isInterpolator(fromType) && std::string(link.from.field->name) == "value_changed")
      interpToTarget.push_back(link);
  }

  // Pass 2: one clip per TimeSensor, in the order the sensors are first routed.
  std::set<const VrmlNode*> driven;
  for (const Link& s : sensorToInterp) {
    driven.insert(s.to.node);
    auto clip =
        std::find_if(result.clips.begin(), result.clips.end(), [&](const Clip& c) { return c.name == s.from.defName; });
    if (clip == result.clips.end()) {
      Clip c;
      c.name = s.from.defName;
      c.loc = s.from.node->loc;
      const VrmlField* cycle = s.from.node->field("cycleInterval");
      if (cycle != nullptr && (cycle->numbers.size() != 1 || !(cycle->numbers[0] > 0.0))) {
        d.error(cycle->loc, "TimeSensor " + c.name + ": cycleInterval must be one number > 0 (seconds)");
        failed = true;
        continue;
      }
      if (cycle != nullptr) c.cycleInterval = cycle->numbers[0];
      const VrmlField* loop = s.from.node->field("loop");
      c.loop = loop != nullptr && !loop->numbers.empty() && loop->numbers[0] != 0.0;
      result.clips.push_back(std::move(c));
      clip = result.clips.end() - 1;
    }
    const VrmlNode& interp = *s.to.node;
    for (const Link& t : interpToTarget) {
      if (t.from.node != &interp) continue;
      if (interp.type == "ScalarInterpolator" || t.to.node->type != "Transform") {
        const VrmlField* key = interp.field("key");
        result.scalars.push_back({t.from.defName, t.to.defName, t.to.field->name, clip->name,
                                  key != nullptr ? key->numbers.size() : 0});
        continue;
      }
      const auto property = propertyOf(t.to.field->name);
      if (!property) continue;  // children: not animation
      ClipTrack track;
      track.interpolator = t.from.defName;
      track.interpolatorType = interp.type;
      track.target = t.to.defName;
      track.property = *property;
      track.loc = t.loc;
      std::vector<double> values;
      const bool orientation = interp.type == "OrientationInterpolator";
      if (!readKeys(interp, t.from.defName, orientation ? 4 : 3, track.keys, values, d)) {
        failed = true;
        continue;
      }
      for (size_t i = 0; i < track.keys.size(); ++i) {
        if (orientation)
          track.rotations.push_back(axisAngle(values[4 * i], values[4 * i + 1], values[4 * i + 2], values[4 * i + 3]));
        else
          track.positions.emplace_back(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
      }
      clip->rest.emplace(track.target, restOf(*t.to.node));
      clip->tracks.push_back(std::move(track));
    }
  }
  for (const Link& t : interpToTarget) {
    if (driven.contains(t.from.node)) continue;
    driven.insert(t.from.node);
    d.warning(t.from.node->loc, t.from.node->type + " " + t.from.defName + " is routed to " + t.to.defName + "." +
                                    t.to.field->name + " but no TimeSensor drives it; it is not part of a clip");
  }
  std::erase_if(result.clips, [](const Clip& c) { return c.tracks.empty(); });
  if (warnings != nullptr) {
    for (const Diagnostic& diag : d.all())
      if (diag.severity == Severity::Warning) warnings->warning(diag.loc, diag.message);
  }
  if (failed || d.hasErrors()) return std::unexpected(std::move(d));
  return result;
}

TransformValues transformValuesOf(const VrmlNode& transform) { return restOf(transform); }

}  // namespace imps
