// SPDX-License-Identifier: MIT
// `--map auto|names|FILE.json`: the keywords choose the retargeting rules, a joint map file is read and checked
// against the clip's and the character's joints (errors printed, nothing returned), and the report names how many
// clip joints drive the character.
#include "map_option.h"

#include <gtest/gtest.h>

#include <string>

#include "examples.h"
#include "scratch_dir.h"
#include "sim/bvh.h"

namespace imps::app {
namespace {

sim::BvhClip waveClip() {
  auto clip = sim::readBvh(std::string(IMPS_SOURCE_DIR) + "/tests/data/bvh/biped_wave.bvh");
  EXPECT_TRUE(clip.has_value());
  return clip ? *clip : sim::BvhClip{};
}

TEST(MapOption, KeywordsChooseTheRules) {
  const sim::BvhClip clip = waveClip();
  const Character& biped = test::exampleCharacter("simple_biped");
  const auto automatic = retargetOptionsFor("auto", clip, biped);
  ASSERT_TRUE(automatic.has_value());
  EXPECT_EQ(automatic->map, RetargetOptions::Map::Auto);
  EXPECT_TRUE(automatic->matches.empty());
  const auto names = retargetOptionsFor("names", clip, biped);
  ASSERT_TRUE(names.has_value());
  EXPECT_EQ(names->map, RetargetOptions::Map::Names);
}

TEST(MapOption, AJointMapFileIsReadAndChecked) {
  const sim::BvhClip clip = waveClip();
  const Character& biped = test::exampleCharacter("simple_biped");
  ScratchDir dir("map_option");
  writeBytes(dir / "map.json", R"({"version": 1, "joints": {"L_UpperArm": "R_UpperArm", "Pelvis": "Pelvis"}})");
  const auto file = retargetOptionsFor((dir / "map.json").string(), clip, biped);
  ASSERT_TRUE(file.has_value());
  EXPECT_EQ(file->map, RetargetOptions::Map::Explicit);
  ASSERT_EQ(file->matches.size(), 2u);
  bool crossed = false;
  for (const auto& m : file->matches) crossed |= m.source == "L_UpperArm" && m.character == "R_UpperArm";
  EXPECT_TRUE(crossed) << "the file's pairs are used as written";

  // A character joint the scene does not have: the diagnostics go to stderr with the file's position.
  writeBytes(dir / "bad.json", R"({"version": 1, "joints": {"L_UpperArm": "NoSuchJoint"}})");
  testing::internal::CaptureStderr();
  EXPECT_FALSE(retargetOptionsFor((dir / "bad.json").string(), clip, biped).has_value());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("bad.json:1:"), std::string::npos) << err;
  EXPECT_NE(err.find("NoSuchJoint"), std::string::npos) << err;

  // A missing file is an error too, not the automatic rules.
  testing::internal::CaptureStderr();
  EXPECT_FALSE(retargetOptionsFor((dir / "missing.json").string(), clip, biped).has_value());
  EXPECT_NE(testing::internal::GetCapturedStderr().find("missing.json"), std::string::npos);
}

TEST(MapOption, TheReportCountsTheDrivingJoints) {
  RetargetReport report;
  report.entries = {
      {"Pelvis", "Pelvis", "same name"}, {"L_UpperArm", "L_UpperArm", "same name"}, {"Tail", "", "no match"}};
  testing::internal::CaptureStdout();
  printRetargetReport("wave.bvh", "names", report);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(out.rfind("puppeteer: retargeting wave.bvh (--map names): 2 of 3 clip joints drive the character\n", 0), 0u)
      << out;
  EXPECT_NE(out.find(report.str()), std::string::npos) << "the report's lines follow";
}

}  // namespace
}  // namespace imps::app
