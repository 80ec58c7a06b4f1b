// SPDX-License-Identifier: MIT
// Joint map files (clip joint → character joint): parsing and every error with its file:line:column.
#include "calibration/joint_map.h"

#include <gtest/gtest.h>

#include "examples.h"

namespace imps::calibration {
namespace {

const std::vector<std::string> kClip = {"Hips", "LeftArm", "LeftForeArm", "RightArm"};

std::string errors(const std::string& json) {
  auto r = parseJointMap(json, "map.json", kClip, &test::exampleCharacter("simple_biped"));
  EXPECT_FALSE(r.has_value()) << json;
  return r ? "" : r.error().str();
}

TEST(JointMap, ParsesPairsInFileOrder) {
  auto r = parseJointMap("{\"version\": 1, \"joints\": {\n  \"LeftArm\": \"L_UpperArm\",\n  \"Hips\": \"Pelvis\"\n}}\n",
                         "map.json", kClip, &test::exampleCharacter("simple_biped"));
  ASSERT_TRUE(r.has_value()) << r.error().str();
  ASSERT_EQ(r->size(), 2u);
  EXPECT_EQ((*r)[0].source, "LeftArm");
  EXPECT_EQ((*r)[0].character, "L_UpperArm");
  EXPECT_EQ((*r)[0].loc.line, 2);
  EXPECT_EQ((*r)[1].character, "Pelvis");
}

TEST(JointMap, EveryProblemHasALocation) {
  EXPECT_EQ(errors("{\"version\": 1, \"joints\": {\n  \"LeftArn\": \"L_UpperArm\",\n  \"LeftForeArm\": \"L_Forarm\",\n"
                   "  \"RightArm\": \"L_UpperArm\",\n  \"Hips\": 3\n}}\n"),
            "map.json:2:3: error: unknown clip joint 'LeftArn'; did you mean 'LeftArm'?\n"
            "map.json:3:18: error: unknown character joint 'L_Forarm'; did you mean 'L_Forearm'?\n"
            "map.json:5:11: error: the character joint for 'Hips' must be a string, not a number\n");
  EXPECT_EQ(
      errors("{\"version\": 1, \"joints\": {\"LeftArm\": \"L_UpperArm\",\n \"RightArm\": \"L_UpperArm\"}}"),
      "map.json:2:14: error: character joint 'L_UpperArm' is already driven by 'LeftArm' (line 1): one clip joint "
      "per joint\n");
  EXPECT_EQ(errors("{\"version\": 2, \"joints\": {}}"),
            "map.json:1:13: error: file format version 2 is newer than this program reads (1); update puppeteer\n");
  EXPECT_EQ(errors("{\"version\": 1, \"joint\": {}}"),
            "map.json:1:16: error: unknown field 'joint' in the joint map; did you mean 'joints'?\n"
            "map.json:1:1: error: missing field 'joints' in the joint map\n");
  EXPECT_EQ(errors("{\"version\": 1, \"joints\": {},}"),
            "map.json:1:29: error: expected a key after ',' (JSON has no trailing commas)\n");
  EXPECT_FALSE(readJointMapFile("/nonexistent/map.json").has_value());
}

// An endless or huge file is refused at the reader's limit, saying how to raise it, instead of growing memory.
TEST(JointMap, FileReadsAreBounded) {
  auto zero = readJointMapFile("/dev/zero");
  ASSERT_FALSE(zero.has_value());
  EXPECT_NE(zero.error().str().find("/dev/zero: error: cannot read joint map: larger than the 16 MiB limit"),
            std::string::npos)
      << zero.error().str();
  EXPECT_NE(zero.error().str().find("IMPS_MAX_INPUT_MIB"), std::string::npos) << zero.error().str();
  auto missing = readJointMapFile("/nonexistent/map.json");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().str(), "/nonexistent/map.json: error: cannot read joint map: no such file\n");
}

}  // namespace
}  // namespace imps::calibration
