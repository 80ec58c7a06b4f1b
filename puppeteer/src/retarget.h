// SPDX-License-Identifier: MIT
// Retargeting motion clips onto a character: which clip joint drives which character joint (name rules for the
// common skeleton namings plus the hierarchy, the clip's own names, or an explicit joint map), and per frame the
// character's joint rotations with the rest poses matched bone by bone, plus the root's translation scaled by leg
// length. The rules and the math are in docs/calibration.md ("Retargeting clips").
#pragma once

#include <cstdint>
#include <expected>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "calibration/joint_map.h"
#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/skeleton_cache.h"
#include "sim/bvh.h"

namespace imps::app {

// The body parts the name rules know.
enum class BodyRole : uint8_t {
  None,
  Hips,
  Spine,
  Neck,
  Head,
  Clavicle,
  UpperArm,
  Forearm,
  Hand,
  Thigh,
  Calf,
  Foot,
  Toe
};
enum class BodySide : uint8_t { Centre, Left, Right };

// What a joint's name says, before the hierarchy is consulted.
struct NameRole {
  BodyRole role = BodyRole::None;
  BodySide side = BodySide::Centre;
  bool ambiguousShoulder = false;  // "shoulder": a clavicle above an arm joint, else the upper arm (Biovision)
  std::string key;                 // the name without prefix, side and digits, lower case ("upleg", "forearm")
};

// Name rules, for CMU (both releases), Mixamo ("mixamorig:" prefix), Rokoko, Biovision, Bandai-Namco, 3ds-Max Biped
// ("Bip01 …") and this project's own characters: strips a namespace ("mixamorig:") or "Bip01"/"Bip001" prefix,
// splits camelCase, '_', ' ', '.', '-' and digits into words, takes a side from "Left"/"L"/"_L"/"l…" words, and
// looks the rest up ("UpLeg", "Thigh", "UpperLeg" → thigh; "Leg", "Shin", "Calf", "LowerLeg", "Knee" → calf; …).
NameRole roleFromName(std::string_view name);
// "left upper arm", "hips", "none".
std::string describeRole(BodyRole role, BodySide side);

// What the mapping did, for the user: every clip joint once (mapped or not, and why), the character joints nothing
// drives, and the translation scale.
struct RetargetReport {
  struct Entry {
    std::string source;  // clip joint
    std::string target;  // character joint; "" when unmapped
    std::string why;
  };
  std::vector<Entry> entries;               // in clip order
  std::vector<std::string> characterIdle;   // character joints no clip joint drives (they keep their rest rotation)
  double translationScale = 1.0;            // character metres per clip unit
  std::string scaleWhy;
  size_t mapped() const;
  // One line per entry, then the idle joints and the scale.
  std::string str() const;
};

struct RetargetOptions {
  enum class Map { Auto, Names, Explicit };
  Map map = Map::Auto;
  std::vector<calibration::JointMatch> matches;  // Map::Explicit (parseJointMap's result)
  // The clip's rest pose: -1 = its OFFSETs with every rotation zero (the BVH convention); else this frame's pose.
  int restFrame = -1;
};

// Per frame: clip channel values (degrees, clip units) → the character's pose. Immutable once made; pose() may be
// called from any number of threads.
//
// Per mapped character joint J with a mapped child K (its bone J→K; the child on the same side wins): C_J is the
// shortest rotation taking the character's rest bone direction onto the clip's rest direction of the last link
// before K's clip joint c (from c's clip parent p), and the world rotation is Q_p(frame) · Q_p(rest)⁻¹ · C_J · A_J
// (A_J: J's rest world rotation), so the bone points exactly where the clip's link points, with the clip's twist.
// A mapped joint without a mapped child uses its own clip joint and its nearest ancestor's C. Unmapped joints keep
// their rest rotation relative to their parent.
// Translation: a mapped joint whose clip joint has position channels moves from its rest translation by
// s · (p(frame) − p(reference)), turned from the clip parent's world frame into the character parent's, where
// s = translationScale() and the reference is setReferenceFrame()'s (default: the clip's first frame). The
// character's root also takes the clip root's position channels when its own clip joint has none (Bip01 → Pelvis).
class Retargeter {
 public:
  // Errors (one, without a location; the caller names the clip): an explicit match naming a joint neither skeleton
  // has, a rest frame out of range, a clip without joints.
  static std::expected<Retargeter, Diagnostics> create(const sim::BvhClip& clip, const Character& character,
                                                       const RetargetOptions& options = {});

  const RetargetReport& report() const { return report_; }
  double translationScale() const { return report_.translationScale; }
  // The clip frame whose root position is "no translation" (clip.channelCount() values).
  void setReferenceFrame(std::span<const float> frame);
  // One pose entry per character joint that a clip joint drives or that lies between driven joints, in character
  // joint order; `frame` holds clip.channelCount() values.
  void pose(std::span<const float> frame, std::vector<JointPose>& out) const;
  // The character joint driven by clip joint j, or -1.
  int targetOf(size_t clipJoint) const;

 private:
  struct Bone {
    int source = -1;  // clip joint whose world rotation turns the joint
    glm::dquat correction{1.0, 0.0, 0.0, 0.0};  // Q_p(rest)⁻¹ · C_J
  };
  void clipWorldRotations(std::span<const float> frame, std::vector<glm::dquat>& out) const;
  glm::dvec3 positionChannels(std::span<const float> frame, size_t clipJoint) const;

  sim::BvhClip clip_;  // hierarchy only
  const Character* character_ = nullptr;
  std::vector<int> source_;       // per character joint: the clip joint mapped to it, or -1
  std::vector<int> translationSource_;  // per character joint: the clip joint whose position channels move it, or -1
  std::vector<Bone> bones_;       // per character joint
  std::vector<glm::dquat> restWorld_;  // per character joint: A_J
  std::vector<bool> posed_;       // per character joint: in the output pose
  std::vector<glm::dvec3> reference_;  // per clip joint: position channels at the reference frame
  RetargetReport report_;
};

// The clip's values for one frame from raw session channels, for sessions that carry a SKELETON (bvhToSession):
// rotations from sim::countsToDegrees, positions from the skeleton's units per count.
double sessionChannelValue(uint32_t counts, bool rotation, int bits, double positionUnitsPerCount);

}  // namespace imps::app
