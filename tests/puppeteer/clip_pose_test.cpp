// SPDX-License-Identifier: MIT
// Tests for ClipDriver / ClipPoseSource (a VRML clip on an implicit character) and the world commands: the bundled
// clips bind to the bundled characters, poses equal hand-computed transforms, squash and stretch change the surface,
// `check` lists clips and props, `render --clip` and `replay CLIP SCENE` fail cleanly on bad input.
#include "clip_pose.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "imps/marching_cubes.h"
#include "imps/scene_reader.h"
#include "imps/vrml_props.h"
#include "imps/vrml_file.h"

#include <algorithm>
#include "subprocess.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
const std::string kSource = IMPS_SOURCE_DIR;
const std::string kBeanito = kSource + "/examples/beanito.wrl";
const std::string kJump = kSource + "/examples/beanito_jump.wrl";
const std::string kFlubber = kSource + "/examples/flubber.wrl";
const std::string kDance = kSource + "/examples/flubber_dance.wrl";

Character characterOf(const std::string& path) {
  auto scene = readSceneFile(path);
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  return std::move(*character);
}

void expectNear(const glm::vec3& a, const glm::vec3& b) {
  EXPECT_NEAR(a.x, b.x, 1e-5f);
  EXPECT_NEAR(a.y, b.y, 1e-5f);
  EXPECT_NEAR(a.z, b.z, 1e-5f);
}

TEST(ClipDriver, BundledClipsDriveEveryJointOfTheirCharacters) {
  for (const auto& [scene, clip] : {std::pair{kBeanito, kJump}, std::pair{kFlubber, kDance}}) {
    const Character character = characterOf(scene);
    auto driver = ClipDriver::load(clip, "", "names", character);
    ASSERT_TRUE(driver.has_value()) << driver.error().str();
    EXPECT_EQ(driver->bound().size(), character.joints().size()) << clip;
    EXPECT_TRUE(driver->unbound().empty()) << clip;
  }
}

TEST(ClipDriver, PoseAtAKeyEqualsTheHandComputedTransform) {
  const Character character = characterOf(kBeanito);
  auto driver = ClipDriver::load(kJump, "JUMP", "names", character);
  ASSERT_TRUE(driver.has_value()) << driver.error().str();
  SkeletonCache skeleton(character);
  // 0.36 s of the 1.2 s cycle is key 0.3: BEAN_BOTTOM at (0, 0.1, 0) turned -0.15 rad about z, BEAN_TOP at (0, 0.8, 0)
  // in its frame.
  driver->apply(0.36, skeleton);
  skeleton.update();
  const int top = character.findJoint("BEAN_TOP");
  const glm::quat turn = glm::angleAxis(-0.15f, glm::vec3(0, 0, 1));
  expectNear(skeleton.world(top).translation, turn * glm::vec3(0, 0.8f, 0) + glm::vec3(0, 0.1f, 0));
  // Looping: one cycle later, the same pose.
  driver->apply(0.36 + 1.2, skeleton);
  skeleton.update();
  expectNear(skeleton.world(top).translation, turn * glm::vec3(0, 0.8f, 0) + glm::vec3(0, 0.1f, 0));
}

// The surface's height (Marching Cubes) with the clip at `seconds`.
float heightAt(const Character& character, const ClipDriver& driver, double seconds) {
  SkeletonCache skeleton(character);
  driver.apply(seconds, skeleton);
  skeleton.update();
  MarchingCubesOptions options;
  options.resolution = 48;
  const MeshBounds b = bounds(polygonize(skeleton.field(), options));
  return b.max.y - b.min.y;
}

TEST(ClipDriver, BeanitoSquashesAndStretches) {
  const Character character = characterOf(kBeanito);
  auto driver = ClipDriver::load(kJump, "", "names", character);
  ASSERT_TRUE(driver.has_value()) << driver.error().str();
  const float rest = heightAt(character, *driver, 0.0);
  const float squash = heightAt(character, *driver, 0.15 * 1.2);   // BEAN_TOP down to 0.4
  const float stretch = heightAt(character, *driver, 0.3 * 1.2);   // BEAN_TOP up to 0.8
  EXPECT_LT(squash, rest - 0.1f);
  EXPECT_GT(stretch, rest + 0.1f);
}

TEST(ClipDriver, AJointMapRenamesTargets) {
  const Character character = characterOf(kBeanito);
  const fs::path map = fs::temp_directory_path() / ("clip_map_" + std::to_string(::getpid()) + ".json");
  std::ofstream(map) << R"({"version": 1, "joints": {"BEAN_TOP": "BEAN_BOTTOM"}})";
  auto driver = ClipDriver::load(kJump, "", map.string(), character);
  fs::remove(map);
  ASSERT_TRUE(driver.has_value()) << driver.error().str();
  ASSERT_EQ(driver->bound().size(), 1u);
  EXPECT_EQ(driver->bound()[0].first, "BEAN_TOP");
  EXPECT_EQ(driver->bound()[0].second, character.findJoint("BEAN_BOTTOM"));
  EXPECT_EQ(driver->unbound(), std::vector<std::string>{"BEAN_BOTTOM"});
}

TEST(ClipDriver, ErrorsNameTheProblem) {
  const Character beanito = characterOf(kBeanito);
  auto wrongCharacter = ClipDriver::load(kDance, "", "names", beanito);
  ASSERT_FALSE(wrongCharacter.has_value());
  EXPECT_NE(wrongCharacter.error().str().find("clip DANCE drives no joint of the character"), std::string::npos);
  auto noSuchClip = ClipDriver::load(kJump, "WALK", "names", beanito);
  ASSERT_FALSE(noSuchClip.has_value());
  EXPECT_NE(noSuchClip.error().str().find("no clip named 'WALK' (the clips: JUMP)"), std::string::npos);
  auto noClips = ClipDriver::load(kSource + "/tests/data/worlds/blender_quirks.wrl", "", "names", beanito);
  ASSERT_FALSE(noClips.has_value());
  EXPECT_NE(noClips.error().str().find("error: no clip"), std::string::npos);
}

TEST(ClipPoseSource, FixedStepsAdvanceOneFrameEach) {
  const Character character = characterOf(kBeanito);
  ClipDriver driver(*ClipDriver::load(kJump, "", "names", character));
  ClipPoseSource source(driver, 1.0, 0.06, "jump");  // 0.06 s a frame: frame 3 is key 0.15
  SkeletonCache skeleton(character);
  for (int i = 0; i < 3; ++i) source.frameDone();
  ASSERT_TRUE(source.poll(skeleton, nullptr));
  skeleton.update();
  expectNear(skeleton.local(character.findJoint("BEAN_TOP")).translation, {0, 0.4f, 0});
}

TEST(ClipDriver, AHatOnAJointFollowsItThroughTheJump) {
  const Character character = characterOf(kBeanito);
  auto driver = ClipDriver::load(kJump, "", "names", character);
  ASSERT_TRUE(driver.has_value()) << driver.error().str();
  auto hatFile = readVrmlFile(kSource + "/examples/beanito_hat.wrl");
  ASSERT_TRUE(hatFile.has_value());
  const std::vector<Prop> hat = readProps(*hatFile);
  ASSERT_EQ(hat.size(), 3u);  // brim, crown, band
  const int top = character.findJoint("BEAN_TOP");
  auto hatBottomAt = [&](double seconds) {
    SkeletonCache skeleton(character);
    driver->apply(seconds, skeleton);
    skeleton.update();
    return bounds(transformed(hat[0].mesh, skeleton.world(top))).min.y - skeleton.world(top).translation.y;
  };
  // At the apex (key 0.55) the brim is as far above BEAN_TOP as at rest, give or take the tilt: it moved with it.
  EXPECT_NEAR(hatBottomAt(0.0), hatBottomAt(0.55 * 1.2), 0.06f);
  SkeletonCache apex(character);
  driver->apply(0.55 * 1.2, apex);
  apex.update();
  // The clip's keys at 0.55: BEAN_BOTTOM at y 0.55 turned 0.25 rad about z, BEAN_TOP 0.62 above it.
  EXPECT_NEAR(apex.world(top).translation.y, 0.55f + 0.62f * std::cos(0.25f), 1e-5f);
}

TEST(Grab, AGrabbedPropStaysPutThenFollowsTheHandThenStaysWhereDropped) {
  const Grab grab{0, 1.0, 2.0};
  // A hand that moves along x and turns about z as time goes on.
  auto hand = [](double t) { return Rigid{glm::angleAxis(float(t), glm::vec3(0, 0, 1)), {float(t), 0, 0}}; };
  const glm::vec3 p(0.3f, 0.2f, 0.1f);  // a point of the prop, in the file's frame
  expectNear(grabbedMotion(grab, 0.5, hand).apply(p), p);  // before the pick: not moved
  for (double t : {1.0, 1.3, 1.99}) {
    // While held, the point keeps its place in the hand's frame at the pick.
    expectNear(hand(t).inverse().apply(grabbedMotion(grab, t, hand).apply(p)), hand(1.0).inverse().apply(p));
  }
  // After the drop it stays where the hand left it.
  expectNear(grabbedMotion(grab, 5.0, hand).apply(p), grabbedMotion(grab, 2.0, hand).apply(p));
}

// The bundled ball touches the tip of Flubber's left hand at the pick time its comment gives (1.0 s into the dance),
// so a grab there carries it in the hand instead of at a distance; half a second earlier the hand is elsewhere.
TEST(Grab, TheBundledBallIsInFlubbersHandAtThePickTime) {
  const Character flubber = characterOf(kFlubber);
  auto driver = ClipDriver::load(kDance, "", "names", flubber);
  ASSERT_TRUE(driver.has_value()) << driver.error().str();
  auto file = readVrmlFile(kSource + "/examples/flubber_ball.wrl");
  ASSERT_TRUE(file.has_value());
  const auto props = readProps(*file);
  ASSERT_EQ(props.size(), 1u);
  const MeshBounds b = bounds(props[0].mesh);
  const glm::vec3 ball = 0.5f * (b.min + b.max);
  const float ballRadius = 0.5f * (b.max.y - b.min.y);
  const int arm = flubber.findJoint("L_ARM_JOINT");
  ASSERT_GE(arm, 0);
  const Primitive& hand = flubber.primitives()[size_t(
      std::find_if(flubber.primitives().begin(), flubber.primitives().end(),
                   [&](const CharacterPrimitive& p) { return p.joint == arm; }) -
      flubber.primitives().begin())].local;
  auto tipAt = [&](double seconds) {
    SkeletonCache skeleton(flubber);
    driver->apply(seconds, skeleton);
    skeleton.update();
    return skeleton.world(arm).apply(hand.p2);
  };
  const float touching = ballRadius + hand.r2;
  EXPECT_LT(glm::length(tipAt(1.0) - ball), touching + 0.03f) << "in the hand at the pick";
  EXPECT_GT(glm::length(tipAt(0.5) - ball), touching + 0.1f) << "the hand is elsewhere before";
}

TEST(Grab, SpecsAreChecked) {
  const Character flubber = characterOf(kFlubber);
  auto ok = parseGrab("ball.wrl@L_ARM_JOINT@0.5:1.5", flubber);
  ASSERT_TRUE(ok.has_value()) << ok.error().str();
  EXPECT_EQ(ok->first, "ball.wrl");
  EXPECT_EQ(ok->second.joint, flubber.findJoint("L_ARM_JOINT"));
  EXPECT_EQ(ok->second.pickSeconds, 0.5);
  EXPECT_EQ(ok->second.dropSeconds, 1.5);
  EXPECT_NE(parseGrab("ball.wrl@L_ARM_JOINT", flubber).error().str().find("expected FILE.wrl@JOINT@PICK:DROP"),
            std::string::npos);
  EXPECT_NE(parseGrab("ball.wrl@HAND@0:1", flubber).error().str().find("no joint 'HAND'"), std::string::npos);
  EXPECT_NE(parseGrab("ball.wrl@L_ARM_JOINT@2:1", flubber).error().str().find("0 <= PICK <= DROP"), std::string::npos);
  EXPECT_NE(parseGrab("ball.wrl@L_ARM_JOINT@x:1", flubber).error().str().find("must be numbers"), std::string::npos);
}

// ---- The commands, run as a user would ----

fs::path puppeteer() { return IMPS_PUPPETEER_BINARY; }

TEST(WorldCommands, CheckListsClipsAndProps) {
  const auto run = test::runProgram(puppeteer(), {"check", kSource + "/tests/data/worlds/max_quirks.wrl.gz"});
  EXPECT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("valid VRML 97 world, 1 clip, 1 prop"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("Bip01-TIMER: TimeSensor, 2 s, loop, targets Bip01 Bip01_Schl\xC3\xBCsselbein"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("-> Bip01.scaleOrientation, 2 keys"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("Bip01/Bip01_Schl\xC3\xBCsselbein/Box01 IndexedFaceSet   8 points, 12 faces"),
            std::string::npos)
      << run.out;
  const auto json = test::runProgram(puppeteer(), {"check", kJump, "--json"});
  EXPECT_EQ(json.exitCode, 0);
  EXPECT_NE(json.out.find("\"timeSensor\": \"JUMP\""), std::string::npos) << json.out;
}

TEST(WorldCommands, AnImpsSceneIsNeverTakenForAWorld) {
  const fs::path scene = fs::temp_directory_path() / ("not_world_" + std::to_string(::getpid()) + ".wrl");
  std::ofstream(scene) << "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n";
  const auto run = test::runProgram(puppeteer(), {"check", scene.string()});
  fs::remove(scene);
  EXPECT_EQ(run.exitCode, 1);
  EXPECT_EQ(run.out.find("VRML 97 world"), std::string::npos) << run.out;
  EXPECT_NE(run.err.find(":3:10: error:"), std::string::npos) << run.err;  // the scene reader's radius error
}

TEST(WorldCommands, BadWorldsAreInputErrors) {
  const fs::path bad = fs::temp_directory_path() / ("bad_world_" + std::to_string(::getpid()) + ".wrl");
  std::ofstream(bad) << "#VRML V2.0 utf8\nDEF T Transform { }\nDEF P PositionInterpolator { }\n"
                        "ROUTE P.value_changed TO T.bboxSize\n";
  const auto check = test::runProgram(puppeteer(), {"check", bad.string()});
  const auto render =
      test::runProgram(puppeteer(), {"render", kBeanito, "--clip", bad.string(), "-o", "/tmp/never.png"});
  const auto replay = test::runProgram(puppeteer(), {"replay", bad.string(), kBeanito, "--frames", "1"});
  fs::remove(bad);
  for (const auto& run : {check, render, replay}) {
    EXPECT_EQ(run.exitCode, 1) << run.out << run.err;
    EXPECT_NE(run.err.find(":4:1: error: Transform T.bboxSize is a plain field"), std::string::npos) << run.err;
  }
  EXPECT_FALSE(fs::exists("/tmp/never.png"));
}

TEST(WorldCommands, RenderPosesTheCharacterFromTheClip) {
  const fs::path out = fs::temp_directory_path() / ("clip_render_" + std::to_string(::getpid()) + ".png");
  const auto run = test::runProgram(
      puppeteer(), {"render", kBeanito, "--clip", kJump, "--at", "0.18", "--res", "24", "--width", "64", "--height",
                    "64", "-o", out.string(), "--json"});
  EXPECT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(fs::exists(out));
  fs::remove(out);
  const auto withHat = test::runProgram(puppeteer(), {"render", kBeanito, "--prop",
                                                      kSource + "/examples/beanito_hat.wrl@BEAN_TOP", "--res", "24",
                                                      "--width", "64", "--height", "64", "-o", out.string()});
  EXPECT_EQ(withHat.exitCode, 0) << withHat.err;
  fs::remove(out);
  const auto noJoint = test::runProgram(puppeteer(), {"render", kBeanito, "--prop",
                                                      kSource + "/examples/beanito_hat.wrl@HEAD", "-o", out.string()});
  EXPECT_EQ(noJoint.exitCode, 1);
  EXPECT_NE(noJoint.err.find("the scene has no joint 'HEAD'"), std::string::npos) << noJoint.err;
  EXPECT_FALSE(fs::exists(out));
  const auto grab = test::runProgram(puppeteer(), {"render", kFlubber, "--clip", kDance, "--at", "1.2", "--grab",
                                                   kSource + "/examples/flubber_ball.wrl@L_ARM_JOINT@0.5:1.5",
                                                   "--res", "24", "--width", "64", "--height", "64", "-o",
                                                   out.string()});
  EXPECT_EQ(grab.exitCode, 0) << grab.err;
  fs::remove(out);
  const auto badGrab = test::runProgram(puppeteer(), {"render", kFlubber, "--clip", kDance, "--grab",
                                                      kSource + "/examples/flubber_ball.wrl@L_ARM_JOINT@3:1", "-o",
                                                      out.string()});
  EXPECT_EQ(badGrab.exitCode, 1);
  EXPECT_NE(badGrab.err.find("expected 0 <= PICK <= DROP"), std::string::npos) << badGrab.err;
  const auto wrong = test::runProgram(puppeteer(), {"render", kBeanito, "--clip", kDance, "-o", out.string()});
  EXPECT_EQ(wrong.exitCode, 1);
  EXPECT_NE(wrong.err.find("drives no joint"), std::string::npos) << wrong.err;
}

}  // namespace
}  // namespace imps::app
