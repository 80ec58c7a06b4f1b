// SPDX-License-Identifier: MIT
// `puppeteer export` (puppeteer/src/cli_export.cpp) as a user meets it: a BVH clip and a session on the biped as the
// character's skeleton (read back with the BVH reader), a skinned glTF (read back with tinygltf), a numbered surface
// sequence (read back with the PLY reader), the old raw-channel BVH on request, and docs/cli.md's exit codes for
// every failure, with nothing written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "cli_run.h"
#include "examples.h"
#include "imps/mesh.h"
#include "mesh_readers.h"
#include "scratch_dir.h"
#include "sim/bvh.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kScene = sourceFile("examples/simple_biped.wrl");
const std::string kClip = sourceFile("tests/data/bvh/biped_wave.bvh");

// The frame count in "puppeteer: wrote OUT: N frames at …".
size_t framesWritten(const std::string& out) {
  const size_t at = out.find("puppeteer: wrote ");
  if (at == std::string::npos) return 0;
  const size_t colon = out.find(": ", at + 17);
  return colon == std::string::npos ? 0 : std::stoul(out.substr(colon + 2));
}

// The clip on the character's skeleton: the character's joints (root first, moving), one frame per clip frame,
// and the report lists the mapping; it reads back and converts to a session.
TEST(ExportCommand, AClipBecomesTheCharactersSkeleton) {
  const ScratchDir dir("imps_cli_export");
  const std::string out = (dir / "wave.bvh").string();
  const test::ProgramRun run = runPuppeteer({"export", kClip, kScene, "-o", out});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  EXPECT_TRUE(contains(run.out, "L_UpperArm -> L_UpperArm"));
  EXPECT_EQ(run.err.find("frames/s"), std::string::npos) << "quiet when piped (no progress line):\n" << run.err;
  auto clip = sim::readBvh(kClip);
  auto written = sim::readBvh(out);
  ASSERT_TRUE(clip) << clip.error().str();
  ASSERT_TRUE(written) << written.error().str();
  const Character& biped = test::exampleCharacter("simple_biped");
  ASSERT_EQ(written->joints.size(), biped.joints().size());
  for (size_t j = 0; j < biped.joints().size(); ++j) EXPECT_EQ(written->joints[j].name, biped.joints()[j].name);
  const std::vector<sim::BvhChannel> rootChannels = written->joints[0].channels;
  ASSERT_EQ(rootChannels.size(), 6u) << "the root moves";
  EXPECT_EQ(rootChannels[0], sim::BvhChannel::Xposition);
  EXPECT_EQ(written->frames.size(), clip->frames.size());
  EXPECT_EQ(framesWritten(run.out), clip->frames.size());
  EXPECT_NEAR(written->frameTime, clip->frameTime, 1e-6);
  const test::ProgramRun back = runPuppeteer({"convert", out, (dir / "back.session").string()});
  EXPECT_EQ(back.exitCode, kCliOk) << describe(back);
}

// --fps resamples and --frames cuts: 2 s of clip at 10 frames per second is 20 frames; frames 5:9 are 5.
TEST(ExportCommand, FramesAreResampledAndCut) {
  const ScratchDir dir("imps_cli_export");
  auto clip = sim::readBvh(kClip);
  ASSERT_TRUE(clip) << clip.error().str();
  const double seconds = double(clip->frames.size()) * clip->frameTime;
  const test::ProgramRun run = runPuppeteer({"export", kClip, kScene, "-o", (dir / "f.bvh").string(), "--fps", "10"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  auto resampled = sim::readBvh(dir / "f.bvh");
  ASSERT_TRUE(resampled) << resampled.error().str();
  EXPECT_NEAR(resampled->frameTime, 0.1, 1e-9);
  EXPECT_NEAR(double(resampled->frames.size()), seconds * 10, 1.0);
  ASSERT_EQ(runPuppeteer({"export", kClip, kScene, "-o", (dir / "c.bvh").string(), "--frames", "5:9"}).exitCode,
            kCliOk);
  auto cut = sim::readBvh(dir / "c.bvh");
  ASSERT_TRUE(cut) << cut.error().str();
  ASSERT_EQ(cut->frames.size(), 5u);
  auto full = sim::readBvh(dir / "f.bvh");
  ASSERT_EQ(runPuppeteer({"export", kClip, kScene, "-o", (dir / "all.bvh").string()}).exitCode, kCliOk);
  auto all = sim::readBvh(dir / "all.bvh");
  ASSERT_TRUE(all) << all.error().str();
  for (size_t f = 0; f < 5; ++f) EXPECT_EQ(cut->frames[f], all->frames[5 + f]) << f;
}

// A skinned, animated glTF: one skin over the character's joints, one animation of the frames written, a mesh.
TEST(ExportCommand, ASkinnedGltfReadsBack) {
  const ScratchDir dir("imps_cli_export");
  const std::string out = (dir / "wave.glb").string();
  const test::ProgramRun run = runPuppeteer({"export", kClip, kScene, "-o", out, "--fps", "10", "--cell", "0.05"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  tinygltf::Model model;
  std::string error, warning;
  ASSERT_TRUE(test::loadGlbModel(out, &model, &error, &warning)) << error;
  const Character& biped = test::exampleCharacter("simple_biped");
  ASSERT_EQ(model.skins.size(), 1u);
  EXPECT_EQ(model.skins[0].joints.size(), biped.joints().size());
  ASSERT_EQ(model.animations.size(), 1u);
  ASSERT_FALSE(model.animations[0].samplers.empty());
  const tinygltf::Accessor& times = model.accessors[size_t(model.animations[0].samplers[0].input)];
  EXPECT_EQ(times.count, framesWritten(run.out));
  Mesh mesh;
  ASSERT_TRUE(test::readGlb(out, &mesh, &error)) << error;
  EXPECT_GT(mesh.triangleCount(), 100u);
  EXPECT_TRUE(analyzeTopology(mesh).closedManifold());
}

// A surface sequence: one numbered PLY per frame kept, in a folder created for it, each a closed mesh.
TEST(ExportCommand, ASurfaceSequenceIsNumberedFiles) {
  const ScratchDir dir("imps_cli_export");
  const test::ProgramRun run = runPuppeteer(
      {"export", kClip, kScene, "-o", (dir / "seq/s_###.ply").string(), "--frames", "0:2", "--cell", "0.06"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  for (const char* name : {"s_000.ply", "s_001.ply", "s_002.ply"}) {
    Mesh mesh;
    std::string error;
    ASSERT_TRUE(test::readPly((dir / "seq" / name).string(), &mesh, &error)) << name << ": " << error;
    EXPECT_GT(mesh.triangleCount(), 50u) << name;
    EXPECT_TRUE(analyzeTopology(mesh).closedManifold()) << name;
  }
  EXPECT_FALSE(fs::exists(dir / "seq/s_003.ply"));
}

// A session made from a clip exports like the clip; --raw-channels writes the old raw-channel BVH and says so.
TEST(ExportCommand, ASessionExportsAsTheCharacterOrAsRawChannels) {
  const ScratchDir dir("imps_cli_export");
  const std::string session = (dir / "wave.session").string();
  ASSERT_EQ(runPuppeteer({"convert", kClip, session}).exitCode, kCliOk);
  const test::ProgramRun run = runPuppeteer({"export", session, kScene, "-o", (dir / "s.bvh").string()});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  auto fromSession = sim::readBvh(dir / "s.bvh");
  ASSERT_TRUE(fromSession) << fromSession.error().str();
  EXPECT_EQ(fromSession->joints.size(), test::exampleCharacter("simple_biped").joints().size());
  const test::ProgramRun raw =
      runPuppeteer({"export", session, kScene, "-o", (dir / "raw.bvh").string(), "--raw-channels"});
  ASSERT_EQ(raw.exitCode, kCliOk) << describe(raw);
  EXPECT_TRUE(contains(raw.out, "raw channels"));
  auto rawClip = sim::readBvh(dir / "raw.bvh");
  ASSERT_TRUE(rawClip) << rawClip.error().str();
  auto clip = sim::readBvh(kClip);
  EXPECT_EQ(rawClip->joints.size(), clip->joints.size()) << "the clip's own joints, not the character's";
}

TEST(ExportCommand, Failures) {
  const ScratchDir dir("imps_cli_export");
  std::ofstream(dir / "map.json") << "{\"version\": 1, \"joints\": {\n  \"L_UpperArn\": \"L_UpperArm\"\n}}\n";
  std::ofstream(dir / "bad.wrl") << "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n";
  std::ofstream(dir / "garbage.session") << "not a session\n";
  std::ofstream(dir / "keep.bvh") << "precious";
  const std::string out = (dir / "y.bvh").string();
  test::expectFailures({
      {"missing input", {"export", (dir / "none.bvh").string(), kScene, "-o", out}, kCliInvalidInput, "no such file"},
      {"missing scene", {"export", kClip, (dir / "none.wrl").string(), "-o", out}, kCliInvalidInput, "no such file"},
      {"missing calibration",
       {"export", kClip, kScene, "-o", out, "--calibration", (dir / "none.json").string()},
       kCliInvalidInput,
       "no such file"},
      {"bad scene", {"export", kClip, (dir / "bad.wrl").string(), "-o", out}, kCliInvalidInput, "bad.wrl:3:"},
      {"garbage session",
       {"export", (dir / "garbage.session").string(), kScene, "-o", out},
       kCliInvalidInput,
       "garbage.session"},
      {"joint map errors",
       {"export", kClip, kScene, "-o", out, "--map", (dir / "map.json").string()},
       kCliInvalidInput,
       "map.json:2:3: error: unknown clip joint 'L_UpperArn'; did you mean 'L_UpperArm'?"},
      {"missing joint map",
       {"export", kClip, kScene, "-o", out, "--map", (dir / "none.json").string()},
       kCliInvalidInput,
       "no such file"},
      {"unknown output kind",
       {"export", kClip, kScene, "-o", (dir / "x.txt").string()},
       kCliUsage,
       "OUT must end in .bvh"},
      {"frames outside the take", {"export", kClip, kScene, "-o", out, "--frames", "5:100000"}, kCliUsage, "--frames"},
      {"frame range text", {"export", kClip, kScene, "-o", out, "--frames", "five"}, kCliUsage, "--frames"},
      {"fps 0", {"export", kClip, kScene, "-o", out, "--fps", "0"}, kCliUsage, "expected a number > 0, got '0'"},
      {"cell", {"export", kClip, kScene, "-o", out, "--cell", "5"}, kCliUsage, "--cell"},
      {"polygonizer", {"export", kClip, kScene, "-o", out, "--polygonizer", "dual"}, kCliUsage, "--polygonizer"},
      {"raw channels of a clip", {"export", kClip, kScene, "-o", out, "--raw-channels"}, kCliUsage, "--raw-channels"},
      {"missing directory", {"export", kClip, kScene, "-o", (dir / "nodir/w.bvh").string()}, kCliIo, "does not exist"},
      {"missing directory for glb",
       {"export", kClip, kScene, "-o", (dir / "nodir/w.glb").string()},
       kCliIo,
       "does not exist"},
      {"bad scene over an existing file",
       {"export", kClip, (dir / "bad.wrl").string(), "-o", (dir / "keep.bvh").string()},
       kCliInvalidInput,
       "bad.wrl:3:"},
      {"misspelt option", {"export", kClip, kScene, "-o", out, "--fpss", "10"}, kCliUsage, "did you mean '--fps'?"},
  });
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir / "nodir"));
  EXPECT_EQ(fileBytes(dir / "keep.bvh"), "precious");
  // The range error is short (CLI11's own printed the double range's 309-digit bounds).
  EXPECT_LT(runPuppeteer({"export", kClip, kScene, "-o", out, "--fps", "0"}).err.size(), 200u);
}

}  // namespace
}  // namespace imps::app
