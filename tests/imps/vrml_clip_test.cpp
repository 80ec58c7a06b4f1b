// SPDX-License-Identifier: MIT
// Tests for readClips and the interpolators: the maths against hand-computed values, ROUTE resolution and its errors.
#include "imps/vrml_clip.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

namespace imps {
namespace {

std::string worldPath(const std::string& name) { return std::string(IMPS_SOURCE_DIR) + "/tests/data/worlds/" + name; }
const std::string kHeader = "#VRML V2.0 utf8\n";
constexpr float kPi = std::numbers::pi_v<float>;

Clips clipsOf(const std::string& text, Diagnostics* warnings = nullptr) {
  auto file = readVrml(text, "c.wrl");
  EXPECT_TRUE(file.has_value()) << (file ? "" : file.error().str());
  if (!file) return {};
  auto clips = readClips(*file, warnings);
  EXPECT_TRUE(clips.has_value()) << (clips ? "" : clips.error().str());
  return clips ? *clips : Clips{};
}

std::string clipErrors(const std::string& text) {
  auto file = readVrml(text, "c.wrl");
  EXPECT_TRUE(file.has_value()) << (file ? "" : file.error().str());
  if (!file) return {};
  auto clips = readClips(*file);
  EXPECT_FALSE(clips.has_value());
  return clips ? std::string() : clips.error().str();
}

void expectNear(const glm::vec3& a, const glm::vec3& b) {
  EXPECT_NEAR(a.x, b.x, 1e-5f);
  EXPECT_NEAR(a.y, b.y, 1e-5f);
  EXPECT_NEAR(a.z, b.z, 1e-5f);
}

// Same rotation (q and -q are the same).
void expectSameRotation(const glm::quat& a, const glm::quat& b) { EXPECT_NEAR(std::abs(glm::dot(a, b)), 1.0f, 1e-5f); }

TEST(Interpolators, PositionIsLinearBetweenKeys) {
  const std::vector<float> keys = {0.0f, 0.5f, 1.0f};
  const std::vector<glm::vec3> values = {{0, 0, 0}, {2, 4, 0}, {2, 4, 6}};
  expectNear(interpolatePosition(keys, values, 0.25f), {1, 2, 0});
  expectNear(interpolatePosition(keys, values, 0.75f), {2, 4, 3});
  expectNear(interpolatePosition(keys, values, 0.5f), {2, 4, 0});
}

TEST(Interpolators, KeysOutOfRangeHoldTheEndValues) {
  const std::vector<float> keys = {0.2f, 0.8f};
  const std::vector<glm::vec3> values = {{1, 0, 0}, {3, 0, 0}};
  expectNear(interpolatePosition(keys, values, 0.0f), {1, 0, 0});
  expectNear(interpolatePosition(keys, values, -5.0f), {1, 0, 0});
  expectNear(interpolatePosition(keys, values, 1.0f), {3, 0, 0});
  expectNear(interpolatePosition(keys, values, 0.5f), {2, 0, 0});
  EXPECT_EQ(interpolateScalar(std::vector<float>{0.5f}, std::vector<float>{7.0f}, 0.9f), 7.0f);
}

TEST(Interpolators, EqualKeysMakeAStep) {
  const std::vector<float> keys = {0.0f, 0.5f, 0.5f, 1.0f};
  const std::vector<float> values = {0.0f, 1.0f, 5.0f, 6.0f};
  EXPECT_FLOAT_EQ(interpolateScalar(keys, values, 0.25f), 0.5f);
  EXPECT_FLOAT_EQ(interpolateScalar(keys, values, 0.5f), 5.0f);
  EXPECT_FLOAT_EQ(interpolateScalar(keys, values, 0.75f), 5.5f);
}

TEST(Interpolators, OrientationIsSlerp) {
  const std::vector<float> keys = {0.0f, 1.0f};
  const std::vector<glm::quat> values = {glm::angleAxis(0.0f, glm::vec3(0, 0, 1)),
                                         glm::angleAxis(kPi / 2, glm::vec3(0, 0, 1))};
  // Slerp at a quarter: a quarter of the angle about the same axis (a lerp of quaternions would not be).
  expectSameRotation(interpolateOrientation(keys, values, 0.25f), glm::angleAxis(kPi / 8, glm::vec3(0, 0, 1)));
  expectSameRotation(interpolateOrientation(keys, values, 0.5f), glm::angleAxis(kPi / 4, glm::vec3(0, 0, 1)));
}

TEST(Interpolators, OrientationTakesTheShorterArc) {
  const std::vector<float> keys = {0.0f, 1.0f};
  // 350 degrees about x is -10 degrees: halfway is -5 degrees, not 175.
  const std::vector<glm::quat> values = {glm::quat(1, 0, 0, 0), glm::angleAxis(350.0f * kPi / 180, glm::vec3(1, 0, 0))};
  expectSameRotation(interpolateOrientation(keys, values, 0.5f), glm::angleAxis(-5.0f * kPi / 180, glm::vec3(1, 0, 0)));
}

TEST(Clips, MaxExportSampledAtKnownTimes) {
  auto file = readVrmlFile(worldPath("max_quirks.wrl"));
  ASSERT_TRUE(file.has_value());
  auto clips = readClips(*file);
  ASSERT_TRUE(clips.has_value()) << clips.error().str();
  ASSERT_EQ(clips->clips.size(), 1u);
  const Clip& clip = clips->clips[0];
  EXPECT_EQ(clip.name, "Bip01-TIMER");
  EXPECT_EQ(clip.cycleInterval, 2.0);
  EXPECT_TRUE(clip.loop);
  EXPECT_EQ(clip.targets(), (std::vector<std::string>{"Bip01", "Bip01_Schl\xC3\xBCsselbein"}));
  ASSERT_EQ(clip.tracks.size(), 4u);
  // 0.5 s of a 2 s cycle: fraction 0.25. Translation halfway from key 0 to key 0.5: y = (0.9 + 1.5) / 2.
  EXPECT_DOUBLE_EQ(clip.fraction(0.5), 0.25);
  EXPECT_DOUBLE_EQ(clip.fraction(4.5), 0.25);  // looping
  const auto at = clip.sample(clip.fraction(0.5));
  const TransformValues& root = at.at("Bip01");
  expectNear(root.translation, {0, 1.2f, 0});
  expectNear(root.scale, {1.2f, 0.7f, 1.2f});  // exactly at key 0.25
  const TransformValues& bone = at.at("Bip01_Schl\xC3\xBCsselbein");
  expectSameRotation(bone.rotation, glm::angleAxis(kPi / 4, glm::vec3(0, 0, 1)));  // half of 90 degrees
  expectNear(bone.translation, {0.2f, 0.3f, 0});  // not driven: the file's value
  // The root's matrix applied to a point: scale about the origin (scaleOrientation identity), then translate.
  const glm::vec4 p = root.matrix() * glm::vec4(1, 1, 1, 1);
  expectNear(glm::vec3(p), {1.2f, 1.2f + 0.7f, 1.2f});
}

TEST(Clips, ANonLoopingClipHoldsItsLastFrame) {
  const Clips clips = clipsOf(kHeader +
                              "DEF T Transform { } DEF S TimeSensor { cycleInterval 2 }\n"
                              "DEF P PositionInterpolator { key [0 1] keyValue [0 0 0, 4 0 0] }\n"
                              "ROUTE S.fraction_changed TO P.set_fraction ROUTE P.value_changed TO T.set_translation");
  ASSERT_EQ(clips.clips.size(), 1u);
  EXPECT_DOUBLE_EQ(clips.clips[0].fraction(1.0), 0.5);
  EXPECT_DOUBLE_EQ(clips.clips[0].fraction(7.0), 1.0);
  EXPECT_DOUBLE_EQ(clips.clips[0].fraction(7.0, true), 0.5);
  expectNear(clips.clips[0].sample(1.0).at("T").translation, {4, 0, 0});
}

TEST(Clips, RouteFanOutDrivesEveryTarget) {
  const Clips clips = clipsOf(kHeader +
                              "DEF A Transform { } DEF B Transform { translation 0 0 9 } DEF S TimeSensor { }\n"
                              "DEF P PositionInterpolator { key [0 1] keyValue [0 0 0, 2 0 0] }\n"
                              "DEF R OrientationInterpolator { key [0 0.5 1] keyValue [0 1 0 0, 0 1 0 1, 0 1 0 2] }\n"
                              "ROUTE S.fraction_changed TO P.set_fraction ROUTE S.fraction_changed TO R.set_fraction\n"
                              "ROUTE P.value_changed TO A.set_translation ROUTE P.value_changed TO B.translation\n"
                              "ROUTE R.value_changed TO B.set_rotation");
  ASSERT_EQ(clips.clips.size(), 1u);
  const Clip& clip = clips.clips[0];
  EXPECT_EQ(clip.tracks.size(), 3u);
  // Interpolators with 2 and 3 keys in one clip, sampled at 0.25.
  const auto at = clip.sample(0.25);
  expectNear(at.at("A").translation, {0.5f, 0, 0});
  expectNear(at.at("B").translation, {0.5f, 0, 0});
  expectSameRotation(at.at("B").rotation, glm::angleAxis(0.5f, glm::vec3(0, 1, 0)));
  expectSameRotation(at.at("A").rotation, glm::quat(1, 0, 0, 0));
}

TEST(Clips, HAnimRoutesReachTheJointsBodyTransform) {
  auto file = readVrmlFile(worldPath("hanim_humanoid.wrl"));
  ASSERT_TRUE(file.has_value());
  auto clips = readClips(*file);
  ASSERT_TRUE(clips.has_value()) << clips.error().str();
  ASSERT_EQ(clips->clips.size(), 1u);
  const Clip& clip = clips->clips[0];
  EXPECT_EQ(clip.targets(), (std::vector<std::string>{"hanim_l_hip", "hanim_l_knee"}));
  const auto at = clip.sample(0.5);
  expectSameRotation(at.at("hanim_l_knee").rotation, glm::angleAxis(1.0f, glm::vec3(1, 0, 0)));
  expectNear(at.at("hanim_l_knee").center, {0.1f, 0.5f, 0});  // the instance's centre, through IS
}

TEST(Clips, ARouteToAPlainFieldIsRejected) {
  EXPECT_EQ(clipErrors(kHeader + "DEF T Transform { } DEF P PositionInterpolator { }\n"
                                 "ROUTE P.value_changed TO T.bboxCenter"),
            "c.wrl:3:1: error: Transform T.bboxCenter is a plain field, not an eventIn or exposedField: a ROUTE "
            "cannot change it\n");
}

TEST(Clips, RouteErrorsSayWhatIsWrong) {
  const std::string nodes = kHeader + "DEF T Transform { } DEF S TimeSensor { } DEF P PositionInterpolator { }\n"
                                      "DEF R OrientationInterpolator { }\n";
  EXPECT_EQ(clipErrors(nodes + "ROUTE P.value_changed TO T.set_translaton"),
            "c.wrl:4:1: error: Transform T has no eventIn 'set_translaton' (did you mean 'set_translation'?)\n");
  EXPECT_EQ(clipErrors(nodes + "ROUTE R.value_changed TO T.set_translation"),
            "c.wrl:4:1: error: ROUTE from R.value_changed (SFRotation) to T.set_translation (SFVec3f): the types "
            "differ\n");
  EXPECT_EQ(clipErrors(nodes + "ROUTE S.fraction_changd TO P.set_fraction"),
            "c.wrl:4:1: error: TimeSensor S has no eventOut 'fraction_changd' (did you mean 'fraction_changed'?)\n");
  EXPECT_EQ(clipErrors(nodes + "ROUTE S.fraction_changed TO P.value_changed"),
            "c.wrl:4:1: error: PositionInterpolator P.value_changed is an eventOut: a ROUTE cannot end there\n");
}

TEST(Clips, KeyAndKeyValueCountsMustAgree) {
  EXPECT_EQ(clipErrors(kHeader + "DEF T Transform { } DEF S TimeSensor { }\n"
                                 "DEF P PositionInterpolator { key [0 0.5 1] keyValue [0 0 0, 1 1 1] }\n"
                                 "ROUTE S.fraction_changed TO P.set_fraction ROUTE P.value_changed TO T.translation"),
            "c.wrl:3:44: error: PositionInterpolator P: 3 keys but 2 keyValues; they must be as many\n");
  EXPECT_EQ(clipErrors(kHeader + "DEF T Transform { } DEF S TimeSensor { }\n"
                                 "DEF P PositionInterpolator { key [0 1 0.5] keyValue [0 0 0, 1 1 1, 2 2 2] }\n"
                                 "ROUTE S.fraction_changed TO P.set_fraction ROUTE P.value_changed TO T.translation"),
            "c.wrl:3:34: error: PositionInterpolator P: key 2 (0.5) is less than the key before it; keys must "
            "not decrease\n");
  EXPECT_EQ(clipErrors(kHeader + "DEF T Transform { } DEF S TimeSensor { cycleInterval 0 }\n"
                                 "DEF P PositionInterpolator { }\n"
                                 "ROUTE S.fraction_changed TO P.set_fraction ROUTE P.value_changed TO T.translation"),
            "c.wrl:2:40: error: TimeSensor S: cycleInterval must be one number > 0 (seconds)\n");
}

TEST(Clips, AnInterpolatorNoTimeSensorDrivesIsAWarning) {
  Diagnostics warnings;
  const Clips clips = clipsOf(kHeader + "DEF T Transform { } DEF P PositionInterpolator { }\n"
                                        "ROUTE P.value_changed TO T.set_translation",
                              &warnings);
  EXPECT_TRUE(clips.clips.empty());
  EXPECT_EQ(warnings.str(), "c.wrl:2:27: warning: PositionInterpolator P is routed to T.translation but no TimeSensor "
                            "drives it; it is not part of a clip\n");
}

TEST(Clips, ScalarInterpolatorsAreListedNotPlayed) {
  const Clips clips = clipsOf(kHeader +
                              "DEF M Material { } DEF S TimeSensor { }\n"
                              "DEF F ScalarInterpolator { key [0 1] keyValue [0 1] }\n"
                              "ROUTE S.fraction_changed TO F.set_fraction ROUTE F.value_changed TO M.transparency");
  EXPECT_TRUE(clips.clips.empty());
  ASSERT_EQ(clips.scalars.size(), 1u);
  EXPECT_EQ(clips.scalars[0].target, "M");
  EXPECT_EQ(clips.scalars[0].field, "transparency");
  EXPECT_EQ(clips.scalars[0].keys, 2u);
}

}  // namespace
}  // namespace imps
