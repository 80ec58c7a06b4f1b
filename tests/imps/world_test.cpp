// SPDX-License-Identifier: MIT
// Tests for readWorldFile: characters placed by Inlines under Transforms, clips inlined beside them (url fragments),
// props of the world and of inlined files, and the errors with the world's file:line:column.
#include "imps/world.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <glm/gtc/quaternion.hpp>

namespace imps {
namespace {

namespace fs = std::filesystem;
const std::string kExamples = std::string(IMPS_SOURCE_DIR) + "/examples";

// A scratch folder with a world and the files it inlines.
class WorldFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_world_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    write("ball.wrl", "#VRML V2.0 utf8\nDEF ROOT RigidTransform { children [ Metaball { radius 0.3 } ] }\n");
    write(
        "bob.wrl",
        "#VRML V2.0 utf8\nDEF ROOT Transform { translation 0 0.5 0 }\n"
        "DEF UP TimeSensor { cycleInterval 2 loop TRUE }\n"
        "DEF UP_POS PositionInterpolator { key [ 0 1 ] keyValue [ 0 0 0, 0 1 0 ] }\n"
        "ROUTE UP.fraction_changed TO UP_POS.set_fraction\nROUTE UP_POS.value_changed TO ROOT.set_translation\n"
        "DEF DOWN TimeSensor { cycleInterval 1 }\n"
        "DEF DOWN_POS PositionInterpolator { key [ 0 1 ] keyValue [ 0 0 0, 0 -1 0 ] }\n"
        "ROUTE DOWN.fraction_changed TO DOWN_POS.set_fraction\nROUTE DOWN_POS.value_changed TO ROOT.set_translation\n");
    write("table.wrl", "#VRML V2.0 utf8\nShape { geometry Box { size 1 0.1 1 } }\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};

TEST_F(WorldFiles, InlinesPlaceCharactersWithTheirClipsAndProps) {
  const std::string world =
      write("w.wrl",
            "#VRML V2.0 utf8\n"
            "DEF LEFT Transform { translation -2 0 0 children [\n"
            "  Inline { url \"ball.wrl\" }\n"
            "  Inline { url [ \"missing.wrl\" \"bob.wrl#DOWN\" ] }\n"
            "] }\n"
            "DEF RIGHT Transform { translation 2 0 0 rotation 0 1 0 1.5708 children [\n"
            "  Transform { translation 0 1 0 children [ DEF HERO Inline { url \"ball.wrl\" } ] }\n"
            "  Inline { url \"table.wrl\" }\n"
            "] }\n"
            "Shape { geometry Sphere { radius 0.1 } }\n");
  Diagnostics warnings;
  auto w = readWorldFile(world, &warnings);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  ASSERT_EQ(w->characters.size(), 2u) << warnings.str();
  const WorldCharacter& left = w->characters[0];
  const WorldCharacter& hero = w->characters[1];
  EXPECT_EQ(left.name, "LEFT");  // the nearest DEF'd Transform
  EXPECT_EQ(hero.name, "HERO");  // the Inline's own DEF name
  EXPECT_EQ(w->findCharacter("HERO"), 1);
  EXPECT_EQ(w->findCharacter("RIGHT"), -1);
  EXPECT_NEAR(glm::length(left.placement.translation - glm::vec3(-2, 0, 0)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(hero.placement.translation - glm::vec3(2, 1, 0)), 0.0f, 1e-5f);
  const glm::vec3 x = hero.placement.rotation * glm::vec3(1, 0, 0);
  EXPECT_NEAR(x.z, -1.0f, 1e-4f) << "the RIGHT Transform's rotation applies";
  // The second url is used when the first names no file; the fragment picks the TimeSensor.
  ASSERT_TRUE(left.clip.has_value());
  EXPECT_EQ(left.clip->name, "DOWN");
  EXPECT_FALSE(hero.clip.has_value()) << "no clip beside HERO (table.wrl has none)";
  // The world's sphere and the inlined table, placed under RIGHT.
  ASSERT_EQ(w->props.size(), 2u);
  bool tablePlaced = false;
  for (const Prop& p : w->props)
    if (p.geometry == "Box") {
      const MeshBounds b = bounds(p.mesh);
      tablePlaced = b.min.x > 1.0f && b.max.x < 3.0f;
    }
  EXPECT_TRUE(tablePlaced);
}

TEST_F(WorldFiles, TheFirstClipPlaysWithoutAFragment) {
  const std::string world = write("w.wrl", "#VRML V2.0 utf8\nTransform { children [ Inline { url \"ball.wrl\" } "
                                           "Inline { url \"bob.wrl\" } ] }\n");
  auto w = readWorldFile(world);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  ASSERT_EQ(w->characters.size(), 1u);
  EXPECT_EQ(w->characters[0].name, "ball");  // no DEF anywhere: the scene file's stem
  ASSERT_TRUE(w->characters[0].clip.has_value());
  EXPECT_EQ(w->characters[0].clip->name, "UP");
}

// Each error at the world's Inline url, line and column.
TEST_F(WorldFiles, ErrorsPointIntoTheWorld) {
  write("notes.wrl", "just text\n");
  struct Case {
    std::string body, where, what;
  } cases[] = {
      {"Transform { children [\n  Inline { url \"nothere.wrl\" } ] }\n", ":3:16: error:", "no such file"},
      {"Transform { children [\n  Inline { url \"notes.wrl\" } ] }\n", ":3:16: error:", "neither an IMPS character"},
      {"Transform { children [ Inline { url \"ball.wrl\" }\n  Inline { url \"ball.wrl\" } ] }\n", ":3:16: error:",
       "a second character Inline"},
      {"Transform { scale 2 2 2 children [\n  Inline { url \"ball.wrl\" } ] }\n", ":3:16: error:", "scale or mirror"},
      {"Transform { children [ Inline { url \"ball.wrl\" }\n  Inline { url \"bob.wrl#DOWNN\" } ] }\n", ":3:16: error:",
       "did you mean 'DOWN'"},
  };
  for (const Case& c : cases) {
    const std::string world = write("bad.wrl", "#VRML V2.0 utf8\n" + c.body);
    auto w = readWorldFile(world);
    ASSERT_FALSE(w.has_value()) << c.body;
    const std::string text = w.error().str();
    EXPECT_NE(text.find("bad.wrl" + c.where), std::string::npos) << text;
    EXPECT_NE(text.find(c.what), std::string::npos) << text;
  }
  // An inlined character with errors: its own file:line:column, after a note at the Inline.
  write("broken.wrl", "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n");
  auto w = readWorldFile(write("bad.wrl", "#VRML V2.0 utf8\nInline { url \"broken.wrl\" }\n"));
  ASSERT_FALSE(w.has_value());
  EXPECT_NE(w.error().str().find("broken.wrl:3:10: error:"), std::string::npos) << w.error().str();
  EXPECT_NE(w.error().str().find("bad.wrl:2:14: note:"), std::string::npos) << w.error().str();
}

// The world's own clip moves the Transforms it drives: a character's placement and a prop below them follow, the
// rest stays; at 0 s the pose is the file's.
TEST_F(WorldFiles, TheWorldsOwnClipsMovePlacementsAndProps) {
  const std::string world =
      write("w.wrl",
            "#VRML V2.0 utf8\n"
            "DEF CART Transform { translation 1 0 0 children [\n"
            "  DEF RIDER Transform { translation 0 1 0 children [ Inline { url \"ball.wrl\" } ] }\n"
            "  Shape { geometry Box { size 0.1 0.1 0.1 } }\n"
            "] }\n"
            "DEF STILL Transform { children [ Inline { url \"ball.wrl\" } ] }\n"
            "DEF T TimeSensor { cycleInterval 2 loop TRUE }\n"
            "DEF P PositionInterpolator { key [ 0 1 ] keyValue [ 1 0 0, 5 0 0 ] }\n"
            "ROUTE T.fraction_changed TO P.set_fraction\nROUTE P.value_changed TO CART.set_translation\n");
  auto w = readWorldFile(world);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  ASSERT_EQ(w->clips.size(), 1u);
  ASSERT_EQ(w->characters.size(), 2u);
  ASSERT_EQ(w->props.size(), 1u);
  const World::Pose start = w->poseAt(0.0), half = w->poseAt(0.5);
  EXPECT_NEAR(glm::length(start.placements[0].translation - w->characters[0].placement.translation), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(start.placements[0].translation - glm::vec3(1, 1, 0)), 0.0f, 1e-6f);
  // 0.5 s of 2 s: a quarter of the way from x = 1 to x = 5.
  EXPECT_NEAR(glm::length(half.placements[0].translation - glm::vec3(2, 1, 0)), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::length(half.placements[1].translation - w->characters[1].placement.translation), 0.0f, 1e-6f);
  const glm::vec3 before = 0.5f * (bounds(start.props[0]).min + bounds(start.props[0]).max);
  const glm::vec3 after = 0.5f * (bounds(half.props[0]).min + bounds(half.props[0]).max);
  EXPECT_NEAR(glm::length(after - before - glm::vec3(1, 0, 0)), 0.0f, 1e-5f);
}

// A Transform beside a character named after one of its joints carries its children on that joint: the props
// are kept in the joint's frame and, at rest, placed where the character's joint is.
TEST_F(WorldFiles, ATransformNamedAfterAJointCarriesPropsOnIt) {
  const std::string world = write("w.wrl",
                                  "#VRML V2.0 utf8\n"
                                  "DEF HERO Transform { translation 2 0 0 children [\n"
                                  "  Inline { url \"ball.wrl\" }\n"
                                  "  DEF ROOT Transform { translation 9 9 9 children [\n"
                                  "    Transform { translation 0 0.5 0 children [ Shape { geometry Box { } } ] }\n"
                                  "    Inline { url \"table.wrl\" } ] }\n"
                                  "  DEF ELSEWHERE Transform { children [ Shape { geometry Sphere { } } ] }\n"
                                  "] }\n");
  auto w = readWorldFile(world);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  ASSERT_EQ(w->characters.size(), 1u);
  ASSERT_EQ(w->props.size(), 3u);
  int riding = 0;
  for (size_t p = 0; p < w->props.size(); ++p) {
    const glm::vec3 centre = 0.5f * (bounds(w->props[p].mesh).min + bounds(w->props[p].mesh).max);
    if (w->props[p].geometry == "Sphere") {
      EXPECT_EQ(w->propCharacter[p], -1);
      EXPECT_NEAR(glm::length(centre - glm::vec3(2, 0, 0)), 0.0f, 1e-5f);
      continue;
    }
    ++riding;
    EXPECT_EQ(w->propCharacter[p], 0);
    EXPECT_EQ(w->propJoint[p], w->characters[0].character.findJoint("ROOT"));
    // ROOT's own fields (9 9 9) are replaced by the joint: the box sits 0.5 m above the joint at (2, 0, 0).
    const glm::vec3 local = 0.5f * (bounds(w->propLocal[p]).min + bounds(w->propLocal[p]).max);
    EXPECT_NEAR(glm::length(centre - (local + glm::vec3(2, 0, 0))), 0.0f, 1e-5f);
    const bool worldsBox = bounds(w->propLocal[p]).max.y - bounds(w->propLocal[p]).min.y > 1.0f;  // not the table
    if (worldsBox) {
      EXPECT_NEAR(glm::length(local - glm::vec3(0, 0.5f, 0)), 0.0f, 1e-5f);
    }
  }
  EXPECT_EQ(riding, 2) << "the Box and the inlined table ride on ROOT";
}

TEST(World, TheBundledWorldsRead) {
  for (const char* name : {"two_bipeds.wrl", "beanito_and_flubber.wrl"}) {
    Diagnostics warnings;
    auto w = readWorldFile(kExamples + "/" + name, &warnings);
    ASSERT_TRUE(w.has_value()) << w.error().str();
    EXPECT_EQ(w->characters.size(), 2u) << name;
    for (const WorldCharacter& c : w->characters) EXPECT_TRUE(c.clip.has_value()) << name << " " << c.name;
    EXPECT_FALSE(w->props.empty()) << name;
    EXPECT_EQ(warnings.errorCount(), 0);
  }
  EXPECT_TRUE(namesImpsNodes("#VRML V2.0 utf8\nMetaball { }"));
  EXPECT_FALSE(namesImpsNodes("#VRML V2.0 utf8\nDEF MetaballHolder Transform { }"));
}

}  // namespace
}  // namespace imps
