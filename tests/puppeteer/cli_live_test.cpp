// SPDX-License-Identifier: MIT
// `puppeteer view`, `replay` and `live` (puppeteer/src/cli_live.cpp) through the real program, headless: everything
// they do before opening a window — the retargeting report, --export-session, every refusal with docs/cli.md's exit
// code — and the exit code when there is no display. The app's frames themselves are tested under Xvfb by
// viewer_app_test.sh and world_app_test.sh (slow).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "scratch_dir.h"
#include "sim/bvh.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kBiped = sourceFile("examples/simple_biped.wrl");
const std::string kWave = sourceFile("examples/simple_biped_wave.session");
const std::string kBvh = sourceFile("tests/data/bvh/biped_wave.bvh");
const std::string kCalibration = sourceFile("examples/simple_biped.calibration.json");

// Without a display the window cannot open: a message saying what to do, exit 3 — after everything that can be
// checked without one.
TEST(LiveCommands, WithoutADisplayTheyExit3SayingWhatToDo) {
  const std::vector<std::vector<std::string>> commands = {
      {"view", kBiped, "--frames", "1"},
      {"replay", kWave, kBiped, "--frames", "1"},
      {"live", kBiped, "--device", "sim:?motion=still", "--calibration", kCalibration, "--frames", "1"},
      {"view", sourceFile("examples/two_bipeds.wrl"), "--frames", "1"},
  };
  for (const std::vector<std::string>& args : commands) {
    const test::ProgramRun run = runPuppeteer(args);
    EXPECT_EQ(run.exitCode, kCliIo) << args[0] << "\n" << describe(run);
    EXPECT_TRUE(contains(run.err, "no display? try xvfb-run -a")) << args[0];
  }
}

// replay --export-session writes the take it plays, before the window opens: a session reads back as itself, a BVH
// clip as the session `convert` makes of it.
TEST(ReplayCommand, ExportSessionWritesTheTakeItPlays) {
  const ScratchDir dir("imps_cli_live");
  const std::string fromSession = (dir / "s.session").string(), fromClip = (dir / "c.session").string();
  test::ProgramRun run = runPuppeteer({"replay", kWave, kBiped, "--frames", "1", "--export-session", fromSession});
  EXPECT_TRUE(contains(run.out, "puppeteer: wrote " + fromSession)) << describe(run);
  auto original = sim::readSession(kWave);
  auto exported = sim::readSession(fromSession);
  ASSERT_TRUE(original) << original.error().str();
  ASSERT_TRUE(exported) << exported.error().str();
  EXPECT_EQ(exported->devices, original->devices);
  ASSERT_EQ(exported->samples.size(), original->samples.size());
  EXPECT_EQ(exported->skeleton, original->skeleton);
  // The scene may come first.
  run = runPuppeteer({"replay", kBiped, kBvh, "--frames", "1", "--export-session", fromClip});
  EXPECT_TRUE(contains(run.out, "replaying")) << describe(run);
  ASSERT_EQ(runPuppeteer({"convert", kBvh, (dir / "converted.session").string()}).exitCode, test::kCliOk);
  auto clipTake = sim::readSession(fromClip);
  auto converted = sim::readSession(dir / "converted.session");
  ASSERT_TRUE(clipTake) << clipTake.error().str();
  ASSERT_TRUE(converted) << converted.error().str();
  EXPECT_EQ(clipTake->samples.size(), converted->samples.size());
  EXPECT_EQ(clipTake->devices, converted->devices);
}

// A session converted from BVH by an earlier version carries the BVH channel mapping as its "calibration": it is
// not taken for one (the clip is retargeted from its skeleton), with no note; the bundled take has none any more.
TEST(ReplayCommand, ABvhSessionIsRetargetedAndSaysNothingAboutCalibrations) {
  for (const std::string& session : {kWave, sourceFile("tests/data/sessions/legacy_bvh_mapping.session"), kBvh}) {
    const test::ProgramRun run = runPuppeteer({"replay", session, kBiped, "--frames", "1"});
    EXPECT_TRUE(contains(run.out, "replaying")) << session;
    EXPECT_TRUE(contains(run.out, ": clip retargeted")) << session;
    EXPECT_EQ(run.out.find("calibration does not apply"), std::string::npos) << session << "\n" << run.out;
    EXPECT_EQ(run.err.find("calibration"), std::string::npos) << session << "\n" << run.err;
  }
  const test::ProgramRun info = runPuppeteer({"info", "--json", kWave});
  ASSERT_EQ(info.exitCode, test::kCliOk) << info.err;
  EXPECT_TRUE(nlohmann::json::parse(info.out)["calibrations"].empty()) << info.out;
  // The retargeting report names what drives what, before the window.
  const test::ProgramRun run = runPuppeteer({"replay", kBvh, kBiped, "--frames", "1"});
  EXPECT_TRUE(contains(run.out, "L_UpperArm -> L_UpperArm"));
}

// The live app refuses a Marching Cubes grid beyond the cell limit before opening a window, as `mesh` does (it
// used to show an empty window).
TEST(ViewCommand, RefusesAGridBeyondTheCellLimit) {
  const ScratchDir dir("imps_cli_live");
  const std::string scene = (dir / "fine.wrl").string();
  std::ofstream(scene) << "#VRML V2.0 utf8\nMarchingCubes { cellSize 0.0001 sceneGraph RigidTransform { children "
                          "[ Metaball { } ] } }\n";
  const test::ProgramRun run = runPuppeteer({"view", scene, "--frames", "1"});
  EXPECT_EQ(run.exitCode, kCliInvalidInput) << describe(run);
  EXPECT_TRUE(contains(run.err, "more than the limit of"));
}

TEST(ViewCommand, Failures) {
  const ScratchDir dir("imps_cli_live");
  std::ofstream(dir / "bad.wrl") << "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n";
  const std::string world = sourceFile("examples/two_bipeds.wrl"), hat = sourceFile("examples/beanito_hat.wrl");
  test::expectFailures({
      {"missing scene", {"view", (dir / "none.wrl").string()}, kCliInvalidInput, "no such file"},
      {"bad scene", {"view", (dir / "bad.wrl").string()}, kCliInvalidInput, "bad.wrl:3:"},
      {"pose text", {"view", kBiped, "--pose", "bogus"}, kCliUsage, "expected JOINT=AX,AY,AZ,ANGLE"},
      {"point size", {"view", kBiped, "--point-size", "100"}, kCliUsage, "--point-size"},
      {"polygonizer", {"view", kBiped, "--polygonizer", "dual"}, kCliUsage, "--polygonizer"},
      {"prop with overlap",
       {"view", kBiped, "--prop", hat, "--overlap"},
       kCliUsage,
       "--prop cannot be combined with --overlap"},
      {"screenshot without frames",
       {"view", kBiped, "--screenshot", (dir / "x.png").string()},
       kCliUsage,
       "--screenshot needs --frames N"},
      {"screenshot extension",
       {"view", kBiped, "--frames", "1", "--screenshot", (dir / "x.jpg").string()},
       kCliUsage,
       "not '.jpg'"},
      {"screenshot directory",
       {"view", kBiped, "--frames", "1", "--screenshot", (dir / "nodir/x.png").string()},
       kCliIo,
       "does not exist"},
      {"keys", {"view", kBiped, "--keys", "@@@"}, kCliUsage, "--keys"},
      {"world with --pose", {"view", world, "--pose", "Neck=0,0,1,30"}, kCliUsage, "is a world"},
      {"world with --prop", {"view", world, "--prop", hat}, kCliUsage, "is a world"},
      {"drive without a world", {"view", kBiped, "--drive", "A=" + kWave}, kCliUsage, "--drive needs a world file"},
      {"drive no one", {"view", world, "--drive", "NOBODY=rest"}, kCliUsage, "its characters: WALKER, WAVER"},
      {"misspelt option", {"view", kBiped, "--frame", "1"}, kCliUsage, "did you mean '--frames'?"},
  });
  EXPECT_FALSE(fs::exists(dir / "x.png"));
}

TEST(ReplayCommand, Failures) {
  const ScratchDir dir("imps_cli_live");
  std::ofstream(dir / "garbage.session") << "not a session\n";
  std::ofstream(dir / "existing.session") << "precious";
  test::expectFailures({
      {"missing session", {"replay", (dir / "none.session").string(), kBiped}, kCliInvalidInput, "no such file"},
      {"missing scene", {"replay", kWave, (dir / "none.wrl").string()}, kCliInvalidInput, "no such file"},
      {"garbage session", {"replay", (dir / "garbage.session").string(), kBiped}, kCliInvalidInput, "garbage.session"},
      {"missing calibration",
       {"replay", kWave, kBiped, "--calibration", (dir / "none.json").string()},
       kCliInvalidInput,
       "no such file"},
      {"clip driving no joint",
       {"replay", sourceFile("examples/beanito_jump.wrl"), kBiped, "--frames", "1"},
       kCliInvalidInput,
       "drives no joint"},
      {"osc-out", {"replay", kWave, kBiped, "--osc-out", "bogus"}, kCliUsage, "expected osc.udp://HOST:PORT"},
      {"speed", {"replay", kWave, kBiped, "--speed", "-1"}, kCliUsage, "--speed"},
      {"rig alone",
       {"replay", kWave, kBiped, "--rig", sourceFile("examples/simple_biped.rig.json")},
       kCliUsage,
       "--rig"},
      {"export-session directory",
       {"replay", kWave, kBiped, "--export-session", (dir / "nodir/x.session").string()},
       kCliIo,
       "does not exist"},
      {"one argument", {"replay", kWave}, kCliUsage, "scene"},
  });
}

TEST(LiveCommand, Failures) {
  const ScratchDir dir("imps_cli_live");
  std::ofstream(dir / "existing.session") << "precious";
  test::expectFailures({
      {"missing scene", {"live", (dir / "none.wrl").string(), "--device", "sim:"}, kCliInvalidInput, "no such file"},
      {"no device", {"live", kBiped}, kCliUsage, "--device"},
      {"bad spec", {"live", kBiped, "--device", "nope"}, kCliUsage, "spec:1:1: error"},
      {"a world", {"live", sourceFile("examples/two_bipeds.wrl"), "--device", "sim:"}, kCliUsage, "--drive NAME=sim:"},
      {"record over a file",
       {"live", kBiped, "--device", "sim:", "--record", (dir / "existing.session").string()},
       kCliIo,
       "recordings never overwrite a file"},
      {"record directory",
       {"live", kBiped, "--device", "sim:", "--record", (dir / "nodir/t.session").string()},
       kCliIo,
       "does not exist"},
      {"record-dir",
       {"live", kBiped, "--device", "sim:", "--record-dir", (dir / "nodir").string()},
       kCliIo,
       "no such directory"},
      {"record an OSC stream",
       {"live", kBiped, "--device", "osc.udp://:9999", "--record", (dir / "o.session").string()},
       kCliUsage,
       "not recorded"},
      {"window", {"live", kBiped, "--device", "sim:", "--window-ms", "0"}, kCliUsage, "must be positive"},
      {"osc-out", {"live", kBiped, "--device", "sim:", "--osc-out", "osc.udp://nohost"}, kCliUsage, "osc:1:"},
      {"misspelt option",
       {"live", kBiped, "--device=sim:", "--calibraton=x.json"},
       kCliUsage,
       "did you mean '--calibration'?"},
  });
  EXPECT_EQ(fileBytes(dir / "existing.session"), "precious");
}

}  // namespace
}  // namespace imps::app
