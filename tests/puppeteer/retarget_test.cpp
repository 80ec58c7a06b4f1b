// SPDX-License-Identifier: MIT
// Retargeting clips onto the biped, checked by forward kinematics: for clips in each common naming, with the arms
// down in their rest pose (the biped's is a T-pose), the character's limb bones, hands and feet point where the clip's
// do, frame after frame, and the root moves by the clip's root motion scaled by leg length.
#include "retarget.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "examples.h"
#include "imps/skeleton_cache.h"

namespace imps::app {
namespace {

using sim::BvhChannel;

// The body parts of a test clip; a naming gives each one a name (or "" when that naming has no such joint).
enum Part { Root, Hips, Helper, Spine1, Spine2, Neck, Head, Clav, Upper, Fore, Hand, Thigh, Calf, Foot, Toe, kParts };

struct Naming {
  const char* label;
  // Centre names, then the left side's with '#' for the side word the naming uses.
  std::map<Part, std::string> names;
  std::string left, right;
  bool zyx = false;  // CMU writes Zrotation Yrotation Xrotation
};

std::string sided(std::string name, const std::string& side) {
  const size_t hash = name.find('#');
  return hash == std::string::npos ? name : name.replace(hash, 1, side);
}

const std::vector<Naming>& namings() {
  static const std::vector<Naming> all = {
      {"CMU (MotionBuilder)", {{Hips, "Hips"}, {Helper, "#HipJoint"}, {Spine1, "LowerBack"}, {Spine2, "Spine1"},
        {Neck, "Neck"}, {Head, "Head"}, {Clav, "#Shoulder"}, {Upper, "#Arm"}, {Fore, "#ForeArm"}, {Hand, "#Hand"},
        {Thigh, "#UpLeg"}, {Calf, "#Leg"}, {Foot, "#Foot"}, {Toe, "#ToeBase"}}, "Left", "Right", true},
      {"CMU (3ds Max)", {{Hips, "Hips"}, {Spine1, "Chest"}, {Spine2, "Chest2"}, {Neck, "Neck"}, {Head, "Head"},
        {Clav, "#Collar"}, {Upper, "#Shoulder"}, {Fore, "#Elbow"}, {Hand, "#Wrist"}, {Thigh, "#Hip"},
        {Calf, "#Knee"}, {Foot, "#Ankle"}, {Toe, "#Toe"}}, "Left", "Right"},
      {"Mixamo", {{Hips, "mixamorig:Hips"}, {Spine1, "mixamorig:Spine"}, {Spine2, "mixamorig:Spine1"},
        {Neck, "mixamorig:Neck"}, {Head, "mixamorig:Head"}, {Clav, "mixamorig:#Shoulder"}, {Upper, "mixamorig:#Arm"},
        {Fore, "mixamorig:#ForeArm"}, {Hand, "mixamorig:#Hand"}, {Thigh, "mixamorig:#UpLeg"}, {Calf, "mixamorig:#Leg"},
        {Foot, "mixamorig:#Foot"}, {Toe, "mixamorig:#ToeBase"}}, "Left", "Right"},
      {"Rokoko", {{Hips, "Hips"}, {Spine1, "Spine1"}, {Spine2, "Spine4"}, {Neck, "Neck"}, {Head, "Head"},
        {Clav, "#Shoulder"}, {Upper, "#Arm"}, {Fore, "#ForeArm"}, {Hand, "#Hand"}, {Thigh, "#Thigh"},
        {Calf, "#Shin"}, {Foot, "#Foot"}, {Toe, "#Toe"}}, "Left", "Right"},
      {"Biovision", {{Hips, "Hips"}, {Spine1, "Chest"}, {Neck, "Neck"}, {Head, "Head"}, {Clav, "#Collar"},
        {Upper, "#UpArm"}, {Fore, "#LowArm"}, {Hand, "#Hand"}, {Thigh, "#UpLeg"}, {Calf, "#LowLeg"}, {Foot, "#Foot"}},
       "Left", "Right"},
      {"Bandai-Namco", {{Hips, "Hips"}, {Spine1, "Spine"}, {Spine2, "Chest"}, {Neck, "Neck"}, {Head, "Head"},
        {Clav, "Shoulder_#"}, {Upper, "UpperArm_#"}, {Fore, "LowerArm_#"}, {Hand, "Hand_#"}, {Thigh, "UpperLeg_#"},
        {Calf, "LowerLeg_#"}, {Foot, "Foot_#"}, {Toe, "Toes_#"}}, "L", "R"},
      {"3ds Max Biped", {{Root, "Bip01"}, {Hips, "Bip01 Pelvis"}, {Spine1, "Bip01 Spine"}, {Spine2, "Bip01 Spine1"},
        {Neck, "Bip01 Neck"}, {Head, "Bip01 Head"}, {Clav, "Bip01 # Clavicle"}, {Upper, "Bip01 # UpperArm"},
        {Fore, "Bip01 # Forearm"}, {Hand, "Bip01 # Hand"}, {Thigh, "Bip01 # Thigh"}, {Calf, "Bip01 # Calf"},
        {Foot, "Bip01 # Foot"}, {Toe, "Bip01 # Toe0"}}, "L", "R"},
  };
  return all;
}

// A clip in centimetres whose rest pose has the arms hanging down (the biped's rest is a T-pose), its hands and
// feet shaped like the biped's.
struct TestClip {
  sim::BvhClip clip;
  std::map<std::string, int> index;  // "<part>" for the centre, "<part>L" / "<part>R" for sides
};

TestClip makeClip(const Naming& n) {
  TestClip t;
  auto add = [&](const std::string& key, const std::string& name, int parent, glm::dvec3 offset, bool moves = false) {
    sim::BvhJoint j;
    j.name = name;
    j.parent = parent;
    j.offset = {offset.x, offset.y, offset.z};
    if (moves) j.channels = {BvhChannel::Xposition, BvhChannel::Yposition, BvhChannel::Zposition};
    if (n.zyx)
      j.channels.insert(j.channels.end(), {BvhChannel::Zrotation, BvhChannel::Yrotation, BvhChannel::Xrotation});
    else j.channels.insert(j.channels.end(), {BvhChannel::Zrotation, BvhChannel::Xrotation, BvhChannel::Yrotation});
    t.clip.joints.push_back(j);
    t.index[key] = static_cast<int>(t.clip.joints.size()) - 1;
    return static_cast<int>(t.clip.joints.size()) - 1;
  };
  auto name = [&](Part p) { return n.names.count(p) ? n.names.at(p) : std::string(); };
  int root = -1;
  if (!name(Root).empty()) root = add("root", name(Root), -1, {0, 95, 0}, true);
  const int hips = add("hips", name(Hips), root, root < 0 ? glm::dvec3(0, 95, 0) : glm::dvec3(0), root < 0);
  for (int s = 0; s < 2; ++s) {
    const std::string side = s == 0 ? n.left : n.right, k = s == 0 ? "L" : "R";
    const double x = s == 0 ? 1 : -1;
    int parent = hips;
    if (!name(Helper).empty()) parent = add("helper" + k, sided(name(Helper), s == 0 ? "L" : "R"), hips, {0, 0, 0});
    const int thigh = add("thigh" + k, sided(name(Thigh), side), parent, {x * 9.5, -4, 0});
    const int calf = add("calf" + k, sided(name(Calf), side), thigh, {0, -44, 1});
    const int foot = add("foot" + k, sided(name(Foot), side), calf, {0, -43, -1});
    if (!name(Toe).empty()) {
      add("toe" + k, sided(name(Toe), side), foot, glm::dvec3(0, -2.5, 18) * 0.8);
      t.clip.joints.back().hasEndSite = true, t.clip.joints.back().endSiteOffset = {0, 0, 4};
    } else {
      t.clip.joints[static_cast<size_t>(foot)].hasEndSite = true;
      t.clip.joints[static_cast<size_t>(foot)].endSiteOffset = {0, -2.5, 18};
    }
  }
  int spine = add("spine1", name(Spine1), hips, {0, 6, 0});
  if (!name(Spine2).empty()) spine = add("spine2", name(Spine2), spine, {0, 20, 0});
  const int neck = add("neck", name(Neck), spine, {0, name(Spine2).empty() ? 43 : 23, 0});
  add("head", name(Head), neck, {0, 11, 0});
  t.clip.joints.back().hasEndSite = true, t.clip.joints.back().endSiteOffset = {0, 20, 0};
  for (int s = 0; s < 2; ++s) {
    const std::string side = s == 0 ? n.left : n.right, k = s == 0 ? "L" : "R";
    const double x = s == 0 ? 1 : -1;
    const int clav = add("clav" + k, sided(name(Clav), side), spine, {x * 3.5, name(Spine2).empty() ? 36 : 16, 0});
    const int upper = add("upper" + k, sided(name(Upper), side), clav, {x * 16, 1, 0});
    const int fore = add("fore" + k, sided(name(Fore), side), upper, {0, -29, 0});  // arms down
    add("hand" + k, sided(name(Hand), side), fore, {0, -26, 0});
    t.clip.joints.back().hasEndSite = true, t.clip.joints.back().endSiteOffset = {0, -9, 0.5};
  }
  t.clip.frameTime = 1.0 / 30.0;
  // Frames: every rotation channel within +-50 degrees, the root walking forward and bobbing.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> angle(-50.0f, 50.0f);
  for (int f = 0; f < 12; ++f) {
    std::vector<float> frame;
    for (const sim::BvhJoint& j : t.clip.joints)
      for (BvhChannel c : j.channels) {
        if (c == BvhChannel::Xposition) frame.push_back(2.0f * float(f));
        else if (c == BvhChannel::Yposition) frame.push_back(95.0f + 3.0f * std::sin(float(f)));
        else if (c == BvhChannel::Zposition) frame.push_back(10.0f * float(f));
        else frame.push_back(f == 0 ? 0.0f : angle(rng));
      }
    t.clip.frames.push_back(frame);
  }
  return t;
}

// World positions and rotations of every clip joint in one frame (BVH forward kinematics).
void clipFk(const sim::BvhClip& clip, const std::vector<float>& frame, std::vector<glm::dvec3>& pos,
            std::vector<glm::dquat>& rot) {
  pos.resize(clip.joints.size());
  rot.resize(clip.joints.size());
  size_t ch = 0;
  for (size_t j = 0; j < clip.joints.size(); ++j) {
    const sim::BvhJoint& joint = clip.joints[j];
    glm::dvec3 p(joint.offset[0], joint.offset[1], joint.offset[2]);
    glm::dquat q{1.0, 0.0, 0.0, 0.0};
    for (BvhChannel c : joint.channels) {
      const double v = frame[ch++];
      if (c == BvhChannel::Xposition) p.x = v;
      else if (c == BvhChannel::Yposition) p.y = v;
      else if (c == BvhChannel::Zposition) p.z = v;
      else {
        glm::dvec3 axis(0.0);
        axis[static_cast<int>(c) - static_cast<int>(BvhChannel::Xrotation)] = 1.0;
        q = q * glm::angleAxis(glm::radians(v), axis);
      }
    }
    if (joint.parent >= 0) {
      pos[j] = pos[static_cast<size_t>(joint.parent)] + rot[static_cast<size_t>(joint.parent)] * p;
      rot[j] = rot[static_cast<size_t>(joint.parent)] * q;
    } else {
      pos[j] = p;
      rot[j] = q;
    }
  }
}

double degreesBetween(glm::dvec3 a, glm::dvec3 b) {
  return glm::degrees(std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0, 1.0)));
}

class EachNaming : public ::testing::TestWithParam<size_t> {};

TEST_P(EachNaming, LimbsHandsAndFeetPointWhereTheClipsDo) {
  const Naming& naming = namings()[GetParam()];
  SCOPED_TRACE(naming.label);
  const TestClip t = makeClip(naming);
  const Character& biped = test::exampleCharacter("simple_biped");
  auto r = Retargeter::create(t.clip, biped);
  ASSERT_TRUE(r.has_value()) << r.error().str();
  const std::string report = r->report().str();
  // Every body part of the biped is driven.
  for (const char* joint : {"Pelvis", "Spine", "Neck", "Head", "L_Clavicle", "L_UpperArm", "L_Forearm", "L_Hand",
                            "R_UpperArm", "R_Forearm", "R_Hand", "L_Thigh", "L_Calf", "L_Foot", "R_Thigh", "R_Calf",
                            "R_Foot"})
    EXPECT_NE(report.find("-> " + std::string(joint) + ":"), std::string::npos) << joint << " not driven:\n" << report;
  // Scale: the biped's leg (0.87 m) over the clip's (87 cm).
  EXPECT_NEAR(r->translationScale(), (std::hypot(0.44, 0.01) * 2) / (std::hypot(44.0, 1.0) * 2), 1e-6) << report;

  SkeletonCache skeleton(biped);
  const int pelvis = biped.findJoint("Pelvis");
  const glm::vec3 pelvisRest = skeleton.world(pelvis).translation;
  std::vector<JointPose> pose;
  std::vector<glm::dvec3> cp, cp0;
  std::vector<glm::dquat> cq, cq0;
  clipFk(t.clip, t.clip.frames[0], cp0, cq0);
  const glm::dvec3 handShape(0.09, 0, 0.005), footShape(0, -0.025, 0.18);  // the biped's hand and foot segments
  double worst = 0;
  for (size_t f = 0; f < t.clip.frames.size(); ++f) {
    r->pose(t.clip.frames[f], pose);
    skeleton.resetPose();
    EXPECT_EQ(skeleton.setPose(pose), 0);
    skeleton.update();
    clipFk(t.clip, t.clip.frames[f], cp, cq);
    auto world = [&](const char* j) { return glm::dvec3(skeleton.world(biped.findJoint(j)).translation); };
    auto clipPos = [&](const std::string& k) { return cp[static_cast<size_t>(t.index.at(k))]; };
    for (const char* s : {"L", "R"}) {
      const std::string side(s), c = s;
      auto bone = [&](const char* from, const char* to, const std::string& cfrom, const std::string& cto) {
        const double d = degreesBetween(world((side + to).c_str()) - world((side + from).c_str()),
                                        clipPos(cto + c) - clipPos(cfrom + c));
        worst = std::max(worst, d);
        EXPECT_LT(d, 3.0) << "frame " << f << " " << side << from << " -> " << side << to;
      };
      bone("_UpperArm", "_Forearm", "upper", "fore");
      bone("_Forearm", "_Hand", "fore", "hand");
      bone("_Thigh", "_Calf", "thigh", "calf");
      bone("_Calf", "_Foot", "calf", "foot");
      // Wrist and ankle: the hand's and the foot's own directions.
      const glm::dquat hand(skeleton.world(biped.findJoint((side + "_Hand").c_str())).rotation);
      const glm::dvec3 clipHand = cq[static_cast<size_t>(t.index.at("hand" + c))] * glm::dvec3(0, -9, 0.5);
      const glm::dvec3 mirroredHand = side == "L" ? handShape : glm::dvec3(-handShape.x, handShape.y, handShape.z);
      const double dh = degreesBetween(hand * mirroredHand, clipHand);
      const glm::dquat foot(skeleton.world(biped.findJoint((side + "_Foot").c_str())).rotation);
      const sim::BvhJoint& clipFoot = t.clip.joints[static_cast<size_t>(t.index.at("foot" + c))];
      const int toe = t.index.count("toe" + c) ? t.index.at("toe" + c) : -1;
      const glm::dvec3 footEnd = toe >= 0 ? glm::dvec3(0, -2.5, 18) * 0.8
                                          : glm::dvec3(clipFoot.endSiteOffset[0], clipFoot.endSiteOffset[1],
                                                       clipFoot.endSiteOffset[2]);
      const double df = degreesBetween(foot * footShape, cq[static_cast<size_t>(t.index.at("foot" + c))] * footEnd);
      worst = std::max({worst, dh, df});
      EXPECT_LT(dh, 5.0) << "frame " << f << " " << side << " wrist";
      EXPECT_LT(df, 5.0) << "frame " << f << " " << side << " ankle";
    }
    // Root motion: the clip's root displacement, scaled.
    const int rootKey = t.index.count("root") ? t.index.at("root") : t.index.at("hips");
    const glm::dvec3 expected =
        r->translationScale() * (cp[static_cast<size_t>(rootKey)] - cp0[static_cast<size_t>(rootKey)]);
    const glm::dvec3 moved = glm::dvec3(skeleton.world(pelvis).translation - pelvisRest);
    EXPECT_LT(glm::length(moved - expected), 1e-4) << "frame " << f;
  }
  std::printf("%s: worst direction error %.2g degrees\n", naming.label, worst);
}

INSTANTIATE_TEST_SUITE_P(Namings, EachNaming, ::testing::Range<size_t>(0, 7));

// The clip's rest pose (frame 0: every angle 0, arms down) shows the biped with its arms down: the rest-pose
// correction makes it look like the clip, not like its own T-pose.
TEST(Retarget, ArmsDownClipRestPoseLowersTheBipedsArms) {
  const TestClip t = makeClip(namings()[0]);
  const Character& biped = test::exampleCharacter("simple_biped");
  auto r = Retargeter::create(t.clip, biped);
  ASSERT_TRUE(r.has_value()) << r.error().str();
  std::vector<JointPose> pose;
  r->pose(t.clip.frames[0], pose);
  SkeletonCache skeleton(biped);
  skeleton.setPose(pose);
  skeleton.update();
  const glm::vec3 arm = skeleton.world(biped.findJoint("L_Forearm")).translation -
                        skeleton.world(biped.findJoint("L_UpperArm")).translation;
  EXPECT_LT(glm::normalize(arm).y, -0.99f);
}

TEST(Retarget, NameRules) {
  EXPECT_EQ(describeRole(roleFromName("mixamorig:LeftUpLeg").role, roleFromName("mixamorig:LeftUpLeg").side),
            "left thigh");
  EXPECT_EQ(roleFromName("RightLeg").role, BodyRole::Calf);
  EXPECT_EQ(roleFromName("RightLeg").side, BodySide::Right);
  EXPECT_EQ(roleFromName("Bip01 R Forearm").role, BodyRole::Forearm);
  EXPECT_EQ(roleFromName("Bip01 R Forearm").side, BodySide::Right);
  EXPECT_EQ(roleFromName("Bip01").role, BodyRole::None);
  EXPECT_EQ(roleFromName("LHipJoint").role, BodyRole::None);
  EXPECT_EQ(roleFromName("LeftHip").role, BodyRole::Thigh);
  EXPECT_EQ(roleFromName("UpperArm_L").side, BodySide::Left);
  EXPECT_EQ(roleFromName("lhumerus").role, BodyRole::UpperArm);
  EXPECT_EQ(roleFromName("lhumerus").side, BodySide::Left);
  EXPECT_EQ(roleFromName("LeftHandIndex1").role, BodyRole::None);
  EXPECT_EQ(roleFromName("L_Calf").role, BodyRole::Calf);
}

// Unmapped clip joints are reported with the reason; a joint whose name says "left forearm" but sits under the
// right arm is refused by the hierarchy.
TEST(Retarget, ReportsWhatDidNotMapAndWhy) {
  TestClip t = makeClip(namings()[0]);
  const Character& biped = test::exampleCharacter("simple_biped");
  t.clip.joints[static_cast<size_t>(t.index.at("foreR"))].name = "LeftForeArm";  // the right forearm, misnamed
  t.clip.joints[static_cast<size_t>(t.index.at("foreL"))].name = "LeftForeArmX";
  auto r = Retargeter::create(t.clip, biped);
  ASSERT_TRUE(r.has_value()) << r.error().str();
  const std::string report = r->report().str();
  EXPECT_NE(report.find("LHipJoint (unmapped): a helper joint"), std::string::npos) << report;
  EXPECT_NE(report.find("LeftForeArm (unmapped): left forearm by name, but the hierarchy disagrees"), std::string::npos)
      << report;
  EXPECT_NE(report.find("LeftForeArmX (unmapped): no name rule for 'forearmx'"), std::string::npos) << report;
  EXPECT_NE(report.find("L_Forearm"), std::string::npos) << "listed as idle";
}

TEST(Retarget, ExplicitMapsAndBadRestFrames) {
  const TestClip t = makeClip(namings()[4]);
  const Character& biped = test::exampleCharacter("simple_biped");
  RetargetOptions o;
  o.map = RetargetOptions::Map::Explicit;
  o.matches = {{"LeftUpArm", "L_UpperArm", {}}, {"LeftLowArm", "L_Forearm", {}}};
  auto r = Retargeter::create(t.clip, biped, o);
  ASSERT_TRUE(r.has_value()) << r.error().str();
  EXPECT_EQ(r->report().mapped(), 2u);
  o.matches = {{"LeftUpArm", "NoSuchJoint", {}}};
  EXPECT_FALSE(Retargeter::create(t.clip, biped, o).has_value());
  RetargetOptions late;
  late.restFrame = 1000;
  EXPECT_FALSE(Retargeter::create(t.clip, biped, late).has_value());
}

}  // namespace
}  // namespace imps::app
