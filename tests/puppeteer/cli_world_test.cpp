// SPDX-License-Identifier: MIT
// VRML 97 worlds and clips on the command line (puppeteer/src/cli_world.cpp): telling them from IMPS scenes,
// `check WORLD` listing what the world reader reads, and `mesh WORLD` / `render WORLD` through the real program,
// with the exit codes docs/cli.md gives a world's errors.
#include "cli_world.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <tiny_gltf.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "image_file.h"
#include "imps/vrml_clip.h"
#include "imps/vrml_file.h"
#include "imps/world.h"
#include "mesh_readers.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kJump = sourceFile("examples/beanito_jump.wrl");
const std::string kTwoBipeds = sourceFile("examples/two_bipeds.wrl");

void write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// A file naming none of the IMPS-only node types is a world, even one that mentions them only in a comment is not;
// an unreadable file is not (the scene reader says why).
TEST(IsWorldFile, TellsWorldsFromCharacterScenes) {
  const ScratchDir dir("imps_cli_world");
  EXPECT_TRUE(isWorldFile(kJump));
  EXPECT_TRUE(isWorldFile(kTwoBipeds));
  EXPECT_TRUE(isWorldFile(sourceFile("tests/data/worlds/max_quirks.wrl.gz")));
  EXPECT_FALSE(isWorldFile(sourceFile("examples/simple_biped.wrl")));
  write(dir / "comment.wrl", "#VRML V2.0 utf8\n# a Metaball would go here\nTransform { }\n");
  EXPECT_FALSE(isWorldFile((dir / "comment.wrl").string()));
  write(dir / "plain.wrl", "#VRML V2.0 utf8\nTransform { children Shape { geometry Box { } } }\n");
  EXPECT_TRUE(isWorldFile((dir / "plain.wrl").string()));
  write(dir / "plain.txt", "#VRML V2.0 utf8\nTransform { }\n");
  EXPECT_FALSE(isWorldFile((dir / "plain.txt").string())) << "not a VRML extension";
  write(dir / "noheader.wrl", "Transform { }\n");
  EXPECT_FALSE(isWorldFile((dir / "noheader.wrl").string()));
  EXPECT_FALSE(isWorldFile((dir / "missing.wrl").string()));
}

// `check CLIP --json` lists what the library's clip reader reads: every clip, its targets and tracks with their key
// counts.
TEST(CheckWorldCommand, ListsTheClipsTheReaderReads) {
  auto file = readVrmlFile(kJump);
  ASSERT_TRUE(file);
  auto clips = readClips(*file);
  ASSERT_TRUE(clips);
  const test::ProgramRun run = runPuppeteer({"check", "--json", kJump});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  EXPECT_EQ(report["kind"], "world");
  EXPECT_EQ(report["valid"], true);
  ASSERT_EQ(report["clips"].size(), clips->clips.size());
  for (size_t c = 0; c < clips->clips.size(); ++c) {
    const Clip& clip = clips->clips[c];
    const nlohmann::json& listed = report["clips"][c];
    EXPECT_EQ(listed["timeSensor"], clip.name);
    EXPECT_DOUBLE_EQ(listed["duration"].get<double>(), clip.cycleInterval);
    EXPECT_EQ(listed["loop"], clip.loop);
    ASSERT_EQ(listed["tracks"].size(), clip.tracks.size());
    for (size_t t = 0; t < clip.tracks.size(); ++t) {
      EXPECT_EQ(listed["tracks"][t]["interpolator"], clip.tracks[t].interpolator);
      EXPECT_EQ(listed["tracks"][t]["target"], clip.tracks[t].target);
      EXPECT_EQ(listed["tracks"][t]["keys"], clip.tracks[t].keys.size());
    }
  }
  // The text listing says the same in words.
  const test::ProgramRun text = runPuppeteer({"check", kJump});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  EXPECT_TRUE(contains(text.out, "valid VRML 97 world, " + std::to_string(clips->clips.size()) + " clip"));
  for (const Clip& clip : clips->clips) EXPECT_TRUE(contains(text.out, "  " + clip.name + ": TimeSensor"));
}

// `check WORLD` lists the characters its Inlines place, as the world reader places them.
TEST(CheckWorldCommand, ListsTheCharactersAndProps) {
  auto world = readWorldFile(kTwoBipeds);
  ASSERT_TRUE(world);
  const test::ProgramRun run = runPuppeteer({"check", "--json", kTwoBipeds});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  ASSERT_EQ(report["characters"].size(), world->characters.size());
  for (size_t i = 0; i < world->characters.size(); ++i) {
    const WorldCharacter& c = world->characters[i];
    EXPECT_EQ(report["characters"][i]["name"], c.name);
    EXPECT_EQ(report["characters"][i]["joints"], c.character.joints().size());
    EXPECT_FLOAT_EQ(report["characters"][i]["translation"][0].get<float>(), c.placement.translation.x);
  }
  EXPECT_FALSE(report["props"].empty());
  const test::ProgramRun text = runPuppeteer({"check", kTwoBipeds});
  EXPECT_TRUE(contains(text.out, "characters (" + std::to_string(world->characters.size()) + "):"));
}

// A world's errors are input errors at the world's file:line:column; a warning (an unknown node) goes to stderr and
// the check still passes.
TEST(CheckWorldCommand, ErrorsHaveTheWorldsLocations) {
  const ScratchDir dir("imps_cli_world");
  write(dir / "route.wrl",
        "#VRML V2.0 utf8\nDEF T Transform { }\nDEF P PositionInterpolator { key [0 1] "
        "keyValue [0 0 0 1 1 1] }\nROUTE P.value_changed TO T.bboxSize\n");
  write(dir / "inline.wrl", "#VRML V2.0 utf8\nDEF A Transform { children [ Inline { url \"gone.wrl\" } ] }\n");
  write(dir / "unknown.wrl", "#VRML V2.0 utf8\nFrobnicator { }\nTransform { }\n");
  write(dir / "broken.wrl", "#VRML V2.0 utf8\nTransform { children [ \n");
  test::expectFailures({
      {"a ROUTE to a plain field", {"check", (dir / "route.wrl").string()}, kCliInvalidInput, "route.wrl:4:"},
      {"an Inline naming no file", {"check", (dir / "inline.wrl").string()}, kCliInvalidInput, "inline.wrl:2:"},
      {"unclosed", {"check", (dir / "broken.wrl").string()}, kCliInvalidInput, "broken.wrl:"},
  });
  const test::ProgramRun warned = runPuppeteer({"check", (dir / "unknown.wrl").string()});
  EXPECT_EQ(warned.exitCode, kCliOk) << describe(warned);
  EXPECT_TRUE(contains(warned.err, "warning:"));
  EXPECT_TRUE(contains(warned.err, "Frobnicator"));
}

// `mesh WORLD`: one object per character and prop — glTF root nodes named after them, OBJ `o` lines — and PLY
// merged (the report says so); the triangles read back are the ones reported.
TEST(MeshWorldCommand, EveryCharacterAndPropIsAnObject) {
  const ScratchDir dir("imps_cli_world");
  const std::string glb = (dir / "world.glb").string();
  const test::ProgramRun run = runPuppeteer({"mesh", kTwoBipeds, "--res", "16", "--json", "-o", glb});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  auto world = readWorldFile(kTwoBipeds);
  ASSERT_TRUE(world);
  ASSERT_GE(report["objects"].size(), world->characters.size());
  tinygltf::Model model;
  std::string error, warning;
  ASSERT_TRUE(test::loadGlbModel(glb, &model, &error, &warning)) << error;
  ASSERT_EQ(model.scenes.size(), 1u);
  ASSERT_EQ(model.scenes[0].nodes.size(), report["objects"].size());
  for (size_t i = 0; i < report["objects"].size(); ++i)
    EXPECT_EQ(model.nodes[size_t(model.scenes[0].nodes[i])].name, report["objects"][i]["name"].get<std::string>());
  for (const WorldCharacter& c : world->characters) {
    bool named = false;
    for (const nlohmann::json& o : report["objects"]) named = named || o["name"] == c.name;
    EXPECT_TRUE(named) << c.name;
  }

  const std::string obj = (dir / "world.obj").string();
  ASSERT_EQ(runPuppeteer({"mesh", kTwoBipeds, "--res", "16", "-o", obj}).exitCode, kCliOk);
  EXPECT_EQ(test::occurrences(fileBytes(obj), "\no "), report["objects"].size());
  Mesh mesh;
  ASSERT_TRUE(test::readObj(obj, &mesh, &error)) << error;
  EXPECT_EQ(mesh.triangleCount(), report["triangles"].get<size_t>());

  const std::string ply = (dir / "world.ply").string();
  const test::ProgramRun merged = runPuppeteer({"mesh", kTwoBipeds, "--res", "16", "-o", ply});
  ASSERT_EQ(merged.exitCode, kCliOk) << describe(merged);
  EXPECT_TRUE(contains(merged.out, "merged: PLY has no objects"));
  ASSERT_TRUE(test::readPly(ply, &mesh, &error)) << error;
  EXPECT_EQ(mesh.triangleCount(), report["triangles"].get<size_t>());
}

// `render WORLD --at T` poses the characters by their clips: two times, two pictures.
TEST(RenderWorldCommand, PosesTheCharactersAtTheTimeAsked) {
  const ScratchDir dir("imps_cli_world");
  std::optional<test::ImageFile> images[2];
  const char* times[2] = {"0", "0.5"};
  for (int i = 0; i < 2; ++i) {
    const std::string png = (dir / ("t" + std::to_string(i) + ".png")).string();
    const test::ProgramRun run = runPuppeteer(
        {"render", kTwoBipeds, "--at", times[i], "--res", "16", "--width", "64", "--height", "48", "-o", png});
    ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
    images[i] = test::readImageFile(png);
    ASSERT_TRUE(images[i]) << png;
    EXPECT_EQ(images[i]->width, 64);
  }
  EXPECT_NE(images[0]->pixels, images[1]->pixels);
}

// --drive: a name the world does not place (with advice), no '=', a character driven twice are usage errors; a
// source render cannot sample is an input error; options for one character are usage errors with a world.
TEST(RenderWorldCommand, DriveAndOptionErrors) {
  const ScratchDir dir("imps_cli_world");
  const std::string png = (dir / "w.png").string(), walk = sourceFile("examples/simple_biped_moves.wrl");
  const std::vector<std::string> base = {"render", kTwoBipeds, "--res", "12", "--width",
                                         "32",     "--height", "32",    "-o", png};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  test::expectFailures({
      {"misspelt character", with({"--drive", "WALKR=" + walk}), kCliUsage, "did you mean 'WALKER'?"},
      {"unknown character", with({"--drive", "NOBODY=" + walk}), kCliUsage, "its characters: WALKER, WAVER"},
      {"no =", with({"--drive", "WALKER"}), kCliUsage, "expected NAME=SOURCE"},
      {"driven twice", with({"--drive", "WALKER=" + walk, "--drive", "WALKER=" + walk}), kCliUsage, "already driven"},
      {"a session", with({"--drive", "WAVER=" + sourceFile("examples/simple_biped_wave.session")}), kCliInvalidInput,
       "render samples VRML clips only"},
      {"a TimeSensor it lacks", with({"--drive", "WAVER=" + walk + "#NOPE"}), kCliInvalidInput, "NOPE"},
      {"--clip", with({"--clip", kJump}), kCliUsage, "is a world"},
      {"--prop", with({"--prop", sourceFile("examples/beanito_hat.wrl")}), kCliUsage, "is a world"},
      {"mesh --check", {"mesh", kTwoBipeds, "--check", "-o", (dir / "w.glb").string()}, kCliUsage, "is a world"},
      {"mesh particles",
       {"mesh", kTwoBipeds, "--polygonizer", "particles", "-o", (dir / "w.glb").string()},
       kCliUsage,
       "is a world"},
  });
  EXPECT_FALSE(fs::exists(png));
  // A driven character moves: WAVER walking is another picture than WAVER waving.
  ASSERT_EQ(runPuppeteer(with({"--at", "0.4"})).exitCode, kCliOk);
  const std::optional<test::ImageFile> waving = test::readImageFile(png);
  ASSERT_EQ(runPuppeteer(with({"--at", "0.4", "--drive", "WAVER=" + walk + "#WALK"})).exitCode, kCliOk);
  const std::optional<test::ImageFile> walking = test::readImageFile(png);
  ASSERT_TRUE(waving && walking);
  EXPECT_NE(waving->pixels, walking->pixels);
}

}  // namespace
}  // namespace imps::app
