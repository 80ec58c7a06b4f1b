// SPDX-License-Identifier: MIT
// Keyframed animation clips read from VRML 97 files (imps/vrml_file.h): a TimeSensor's fraction routed to
// interpolators whose values are routed to Transforms' fields becomes a clip, a function of time giving every driven
// Transform's translation, rotation, scale, scale orientation and centre. docs/world-format.md ("Clips").
//
// Based on: ISO/IEC 14772-1:1997 clause 4.6.8 (interpolators), 4.10 (events and ROUTEs) and 6.x (TimeSensor,
// PositionInterpolator, OrientationInterpolator, ScalarInterpolator, Transform); K. Shoemake, "Animating rotation
// with quaternion curves", SIGGRAPH 1985 (slerp).
#pragma once

#include <expected>
#include <map>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "imps/diagnostic.h"
#include "imps/vrml_file.h"

namespace imps {

// Piecewise-linear interpolation over `keys` (ascending fractions; `values` as many): before the first key the
// first value, after the last key the last value, between two keys linear (positions, scalars) or spherical linear
// along the shorter arc (orientations, unit quaternions). Equal neighbouring keys make a step: at the key the later
// value holds. Empty keys give the type's zero (identity rotation). keys.size() must equal values.size() (checked).
glm::vec3 interpolatePosition(std::span<const float> keys, std::span<const glm::vec3> values, float fraction);
glm::quat interpolateOrientation(std::span<const float> keys, std::span<const glm::quat> values, float fraction);
float interpolateScalar(std::span<const float> keys, std::span<const float> values, float fraction);

// A Transform's fields (VRML's transform: x -> T C R SR S SR^-1 C^-1 x).
struct TransformValues {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  glm::quat scaleOrientation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 center{0.0f};
  // The 4x4 matrix of the transform (column vectors).
  glm::mat4 matrix() const;
  // The rigid part as a rotation and translation when the scale is 1: rotation `rotation`, translation
  // translation + center - rotation * center.
  glm::vec3 rigidTranslation() const { return translation + center - rotation * center; }
};

// A Transform node's fields as written (defaults where absent): translation, rotation, scale, scaleOrientation,
// center.
TransformValues transformValuesOf(const VrmlNode& transform);

// Which field of its target a track drives.
enum class ClipProperty { Translation, Rotation, Scale, ScaleOrientation, Center };
// "translation", "rotation", "scale", "scaleOrientation", "center".
const char* clipPropertyName(ClipProperty property);

// One interpolator's keys routed to one Transform field. An interpolator routed to several fields gives one track
// per field (ROUTE fan-out).
struct ClipTrack {
  std::string interpolator;      // its DEF name
  std::string interpolatorType;  // "PositionInterpolator" or "OrientationInterpolator"
  std::string target;            // the DEF name of the Transform (or H-Anim Joint instance) it drives
  ClipProperty property = ClipProperty::Translation;
  std::vector<float> keys;
  std::vector<glm::vec3> positions;  // PositionInterpolator: as many as keys
  std::vector<glm::quat> rotations;  // OrientationInterpolator: as many as keys, unit
  SourceLoc loc;                     // the ROUTE to the target
};

// Everything one TimeSensor drives.
struct Clip {
  std::string name;  // the TimeSensor's DEF name
  SourceLoc loc;
  double cycleInterval = 1.0;  // seconds, > 0
  bool loop = false;
  std::vector<ClipTrack> tracks;
  std::map<std::string, TransformValues, std::less<>> rest;  // every target's fields as the file gives them

  // The driven Transforms' DEF names, sorted.
  std::vector<std::string> targets() const;
  // The TimeSensor's fraction at `seconds` after it started: seconds / cycleInterval wrapped into [0, 1) when
  // looping (`loop` or `forceLoop`), else clamped to [0, 1] (a finished clip holds its last frame).
  double fraction(double seconds, bool forceLoop = false) const;
  // Every target's fields at `fraction`: its rest values with the driven fields replaced by the tracks' values
  // (several tracks on one field: the later ROUTE wins, as the later event would).
  std::map<std::string, TransformValues, std::less<>> sample(double fraction) const;
};

// A ScalarInterpolator's keys routed somewhere a clip cannot play (a Material's transparency): listed, not played.
struct ScalarTrack {
  std::string interpolator, target, field, timeSensor;
  size_t keys = 0;
};

struct Clips {
  std::vector<Clip> clips;           // one per TimeSensor that drives at least one Transform field, in file order
  std::vector<ScalarTrack> scalars;  // ScalarInterpolator routes
};

// Reads the clips of a file by resolving its ROUTEs. A route to an H-Anim Joint instance reaches its PROTO body's
// Transform. Errors (`file:line:column: error: ...` at the ROUTE or field): a route from or to a field the node does
// not have (with "did you mean"), to a plain `field` (not an eventIn or exposedField: a route cannot change it), from
// something that is not an eventOut or exposedField, between fields of different types (an OrientationInterpolator
// to `translation`), an interpolator whose key and keyValue counts differ or whose keys decrease, a cycleInterval
// that is not > 0. Interpolators no TimeSensor drives are reported as warnings. Routes between other nodes (sensors,
// Scripts) are not checked beyond vrml_file.h's checks. Thread-safe.
std::expected<Clips, Diagnostics> readClips(const VrmlFile& file, Diagnostics* warnings = nullptr);

}  // namespace imps
