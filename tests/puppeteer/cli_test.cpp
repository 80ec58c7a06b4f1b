// SPDX-License-Identifier: MIT
// The command line's shared checks (puppeteer/src/cli.cpp) as a user meets them, through the real `puppeteer`
// program: every command × every kind of failure gives the exit code docs/cli.md promises, found before any work is
// done; misspellings get advice; every reporting command prints JSON; the streams stay in order when piped. Each
// command group's own outputs and failures are tested in cli_<group>_test.cpp.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::runProgram;

const std::string kSource = IMPS_SOURCE_DIR;
const std::string kBiped = kSource + "/examples/simple_biped.wrl";
const std::string kRig = kSource + "/examples/simple_biped.rig.json";
const std::string kWave = kSource + "/examples/simple_biped_wave.session";
const std::string kBvh = kSource + "/tests/data/bvh/biped_wave.bvh";

constexpr int kOk = test::kCliOk, kInvalidInput = test::kCliInvalidInput, kUsage = test::kCliUsage,
              kIo = test::kCliIo;

fs::path puppeteer() { return test::puppeteerProgram(); }

// A scratch directory with one bad file of each kind.
class CliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("imps_cli_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    write("bad.wrl", "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n");
    write("notex.wrl", "#VRML V2.0 utf8\nMetaball {\n  texture ImageTexture { url \"gone.png\" }\n}\n");
    write("garbage.session", "this is not a session file\n");
    write("garbage.bvh", "HIERARCHY\nROOT {\n");
    write("bad.rig.json", "{\n  \"version\": 1,\n  \"joints\": [ { \"joint\": \"L_Elbo\" } ]\n}\n");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / name) << text; }
  static std::string at(const std::string& name) { return (dir_ / name).string(); }

  static fs::path dir_;
};
fs::path CliTest::dir_;

using Failure = test::CliFailure;
void expectAll(const std::vector<Failure>& table) { test::expectFailures(table); }

TEST_F(CliTest, AMissingInputFileIsAnInputErrorForEveryCommand) {
  const std::string none = at("none");
  expectAll({
      {"check", {"check", none + ".wrl"}, kInvalidInput, "no such file"},
      {"mesh", {"mesh", none + ".wrl", "-o", at("m.ply")}, kInvalidInput, "no such file"},
      {"render", {"render", none + ".wrl", "-o", at("r.png")}, kInvalidInput, "no such file"},
      {"bench", {"bench", none + ".wrl"}, kInvalidInput, "no such file"},
      {"stretch", {"stretch", none + ".wrl"}, kInvalidInput, "no such file"},
      {"calibrate --rig", {"calibrate", "--rig", none + ".json", "--scene", kBiped, "--session", kWave, "-o",
                           at("c.json")}, kInvalidInput, "no such file"},
      {"calibrate --scene", {"calibrate", "--rig", kRig, "--scene", none + ".wrl", "--session", kWave, "-o",
                             at("c.json")}, kInvalidInput, "no such file"},
      {"calibrate --session", {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", none + ".session", "-o",
                               at("c.json")}, kInvalidInput, "no such file"},
      {"info", {"info", none + ".session"}, kInvalidInput, "no such file"},
      {"convert", {"convert", none + ".bvh", at("c.session")}, kInvalidInput, "no such file"},
      {"view", {"view", none + ".wrl"}, kInvalidInput, "no such file"},
      {"replay session", {"replay", none + ".session", kBiped}, kInvalidInput, "no such file"},
      {"replay scene", {"replay", kWave, none + ".wrl"}, kInvalidInput, "no such file"},
      {"live scene", {"live", none + ".wrl", "--device", "sim:"}, kInvalidInput, "no such file"},
      {"live --calibration", {"live", kBiped, "--device", "sim:", "--calibration", none + ".json"}, kInvalidInput,
       "no such file"},
      {"record --calibration", {"record", "--device", "sim:", "--calibration", none + ".json", "-o", at("t.session")},
       kInvalidInput, "no such file"},
      {"record sim:SESSION", {"record", "--device", "sim:" + none + ".session", "-o", at("t.session")},
       kInvalidInput, none + ".session"},
      {"sim sim:SESSION", {"sim", "--device", "sim:" + none + ".session", "--pty"}, kInvalidInput,
       none + ".session"},
      {"export input", {"export", none + ".bvh", kBiped, "-o", at("e.bvh")}, kInvalidInput, "no such file"},
      {"export scene", {"export", kBvh, none + ".wrl", "-o", at("e.bvh")}, kInvalidInput, "no such file"},
  });
  EXPECT_FALSE(fs::exists(at("t.session")));
}

TEST_F(CliTest, AnInputFileWithErrorsIsAnInputErrorForEveryCommand) {
  expectAll({
      {"check", {"check", at("bad.wrl")}, kInvalidInput, "bad.wrl:3:"},
      {"mesh", {"mesh", at("bad.wrl"), "-o", at("m.ply")}, kInvalidInput, "bad.wrl:3:"},
      {"render", {"render", at("bad.wrl"), "-o", at("r.png")}, kInvalidInput, "bad.wrl:3:"},
      {"bench", {"bench", at("bad.wrl")}, kInvalidInput, "bad.wrl:3:"},
      {"calibrate", {"calibrate", "--rig", at("bad.rig.json"), "--scene", kBiped, "--session", kWave, "-o",
                     at("c.json")}, kInvalidInput, "bad.rig.json:"},
      {"info", {"info", at("garbage.session")}, kInvalidInput, "garbage.session"},
      {"convert", {"convert", at("garbage.bvh"), at("c.session")}, kInvalidInput, "garbage.bvh"},
      {"view", {"view", at("bad.wrl")}, kInvalidInput, "bad.wrl:3:"},
      {"replay", {"replay", at("garbage.session"), kBiped}, kInvalidInput, "garbage.session"},
      {"live", {"live", at("bad.wrl"), "--device", "sim:"}, kInvalidInput, "bad.wrl:3:"},
      {"record", {"record", "--device", "sim:" + at("garbage.session"), "-o", at("t.session")}, kInvalidInput,
       "garbage.session"},
      {"sim", {"sim", "--device", "sim:" + at("garbage.session"), "--pty"}, kInvalidInput, "garbage.session"},
  });
  EXPECT_FALSE(fs::exists(at("m.ply")));
  EXPECT_FALSE(fs::exists(at("c.json")));
}

// docs/scene-format.md, *Texturing*: a missing image is an input error at its url, for the commands that draw.
TEST_F(CliTest, AMissingTextureImageIsAnInputError) {
  const std::string message = "notex.wrl:3:30: error: cannot read texture 'gone.png' (" + at("gone.png") +
                              "): No such file or directory";
  expectAll({
      {"render", {"render", at("notex.wrl"), "-o", at("r.png")}, kInvalidInput, message},
      {"view", {"view", at("notex.wrl")}, kInvalidInput, message},
  });
  EXPECT_FALSE(fs::exists(at("r.png")));
  // A textured example renders.
  const auto run = runProgram(puppeteer(), {"render", kSource + "/examples/textured_blobs.wrl", "--width", "64",
                                            "--height", "64", "-o", at("blobs.png")});
  EXPECT_EQ(run.exitCode, kOk) << run.err;
  EXPECT_TRUE(fs::exists(at("blobs.png")));
}

TEST_F(CliTest, AnUnknownOptionIsAUsageErrorForEveryCommand) {
  const std::vector<std::vector<std::string>> commands = {
      {"check", kBiped}, {"mesh", kBiped, "-o", at("m.ply")}, {"render", kBiped, "-o", at("r.png")},
      {"bench", kBiped}, {"stretch", kBiped}, {"devices"}, {"sim", "--pty"},
      {"record", "--device", "sim:", "-o", at("t.session")},
      {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", kWave, "-o", at("c.json")},
      {"info", kWave}, {"convert", kBvh, at("c.session")}, {"view", kBiped}, {"replay", kWave, kBiped},
      {"live", kBiped, "--device", "sim:"}, {"export", kBvh, kBiped, "-o", at("e.bvh")}};
  std::vector<Failure> table;
  for (std::vector<std::string> args : commands) {
    const std::string name = args.front();
    args.push_back("--frobnicate");
    table.push_back({name, args, kUsage, "unknown option '--frobnicate' for " + name});
  }
  expectAll(table);
}

TEST_F(CliTest, ABadValueIsAUsageError) {
  expectAll({
      {"mesh --cell 0", {"mesh", kBiped, "-o", at("m.ply"), "--cell", "0"}, kUsage, "expected a number > 0, got '0'"},
      {"mesh --res 0", {"mesh", kBiped, "-o", at("m.ply"), "--res", "0"}, kUsage, "--res"},
      {"render --width 1", {"render", kBiped, "-o", at("r.png"), "--width", "1"}, kUsage, "--width"},
      {"bench --motion", {"bench", kBiped, "--motion", "wobble"}, kUsage, "--motion"},
      {"sim without --pty", {"sim"}, kUsage, "--pty"},
      {"record --device", {"record", "--device", "nope", "-o", at("t.session")}, kUsage, "spec:1:1: error"},
      {"calibrate --window-ms", {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", kWave, "-o",
                                 at("c.json"), "--window-ms", "0"}, kUsage, "--window-ms"},
      {"convert bvh to bvh", {"convert", kBvh, at("c.bvh")}, kUsage, "cannot convert"},
      {"view --frames", {"view", kBiped, "--frames", "-1"}, kUsage, "expected a number >= 0, got '-1'"},
      {"replay --rig alone", {"replay", kWave, kBiped, "--rig", kRig}, kUsage, "--rig"},
      {"live --device", {"live", kBiped, "--device", "nope"}, kUsage, "spec:1:1: error"},
  });
}

TEST_F(CliTest, AWrongOutputExtensionIsAUsageErrorFoundBeforeAnyWork) {
  expectAll({
      {"mesh", {"mesh", kBiped, "-o", at("m.txt")}, kUsage, "expected a .obj, .ply or .glb file, not '.txt'"},
      {"render", {"render", kBiped, "-o", at("r.jpg")}, kUsage, "expected a .png file, not '.jpg'"},
      {"convert", {"convert", kBvh, at("c.txt")}, kUsage, "'.txt'"},
      {"export", {"export", kBvh, kBiped, "-o", at("e.txt")}, kUsage, "OUT must end in"},
      {"bench --csv", {"bench", kBiped, "--csv", at("b.txt")}, kUsage, "--csv"},
      // The viewer never opens (there is no display here): the name is refused before the first frame.
      {"view", {"view", kBiped, "--frames", "100000", "--screenshot", at("x.jpg")}, kUsage, "not '.jpg'"},
      {"replay", {"replay", kWave, kBiped, "--frames", "100000", "--screenshot", at("x.jpg")}, kUsage, "not '.jpg'"},
      {"live", {"live", kBiped, "--device", "sim:", "--frames", "100000", "--screenshot", at("x")}, kUsage,
       "without an extension"},
  });
  for (const char* name : {"m.txt", "r.jpg", "c.txt", "e.txt", "b.txt", "x.jpg", "x"})
    EXPECT_FALSE(fs::exists(at(name))) << name;
}

TEST_F(CliTest, AnOutputInAMissingDirectoryIsAnOutputErrorFoundBeforeAnyWork) {
  const std::string nodir = at("nodir") + "/";
  expectAll({
      {"mesh", {"mesh", kBiped, "-o", nodir + "m.ply"}, kIo, "does not exist"},
      {"render", {"render", kBiped, "-o", nodir + "r.png"}, kIo, "does not exist"},
      {"convert", {"convert", kBvh, nodir + "c.session"}, kIo, "does not exist"},
      {"calibrate", {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", kWave, "-o", nodir + "c.json"}, kIo,
       "does not exist"},
      {"record", {"record", "--device", "sim:", "-o", nodir + "t.session", "--seconds", "5"}, kIo, "does not exist"},
      {"sim", {"sim", "--pty", "--link", nodir + "arm"}, kIo, "does not exist"},
      {"export", {"export", kBvh, kBiped, "-o", nodir + "e.bvh"}, kIo, "does not exist"},
      {"bench --csv", {"bench", kBiped, "--csv", nodir + "b.csv"}, kIo, "nodir"},
      {"stretch --pictures", {"stretch", kSource + "/examples/textured_biped.wrl", "--pictures", nodir + "p"}, kIo,
       "does not exist"},
      {"view", {"view", kBiped, "--frames", "100000", "--screenshot", nodir + "x.png"}, kIo, "does not exist"},
      {"replay", {"replay", kWave, kBiped, "--export-session", nodir + "x.session"}, kIo, "does not exist"},
      {"live --record", {"live", kBiped, "--device", "sim:", "--record", nodir + "t.session"}, kIo, "does not exist"},
      {"live --record-dir", {"live", kBiped, "--device", "sim:", "--record-dir", nodir}, kIo, "no such directory"},
  });
}

TEST_F(CliTest, MisspeltCommandsAndOptionsGetASuggestion) {
  test::ProgramRun run = runProgram(puppeteer(), {"rendr", kBiped, "-o", at("r.png")});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_NE(run.err.find("unknown command 'rendr'; did you mean 'render'?"), std::string::npos) << run.err;
  run = runProgram(puppeteer(), {"mesh", kBiped, "-o", at("m.ply"), "--cel", "0.1"});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_NE(run.err.find("unknown option '--cel' for mesh; did you mean '--cell'?"), std::string::npos) << run.err;
  run = runProgram(puppeteer(), {"live", kBiped, "--device=sim:", "--calibraton=x.json"});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_NE(run.err.find("did you mean '--calibration'?"), std::string::npos) << run.err;
  // Nothing close: the commands are listed instead.
  run = runProgram(puppeteer(), {"xyzzyplugh"});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_NE(run.err.find("(commands: mesh, check, render"), std::string::npos) << run.err;
}

// Range errors are short: CLI11's own checks printed a double range's 309-digit bounds ("Value 0 not in range
// 2.2250738585072014e-308 to 1797…").
TEST_F(CliTest, ARangeErrorIsReadable) {
  const std::vector<std::vector<std::string>> commands = {
      {"mesh", kBiped, "-o", at("m.ply"), "--cell", "0"},
      {"mesh", kBiped, "-o", at("m.ply"), "--max-cells", "0"},
      {"mesh", kBiped, "-o", at("m.ply"), "--max-particles", "0"},
      {"render", kBiped, "-o", at("r.png"), "--max-cells", "0"},
      {"export", kBvh, kBiped, "-o", at("e.bvh"), "--fps", "0"},
      {"bench", kBiped, "--desired-radius", "0"},
      {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", kWave, "-o", at("c.json"), "--max-noise-deg", "0"},
  };
  for (const std::vector<std::string>& args : commands) {
    const test::ProgramRun run = runProgram(puppeteer(), args);
    EXPECT_EQ(run.exitCode, kUsage) << args[0] << " " << args[args.size() - 2] << ": " << run.err;
    EXPECT_LT(run.err.size(), 200u) << run.err;
  }
}

// ---- The command line, consistent

// Every reporting command has --json: one document on stdout that a script can read.
TEST_F(CliTest, ReportingCommandsPrintJson) {
  struct Case {
    std::vector<std::string> args;
    std::string key;  // a field the report must have
  } cases[] = {
      {{"check", "--json", kBiped}, "blendSets"},
      {{"mesh", "--json", kBiped, "--res", "24", "--check", "-o", at("j.ply")}, "topology"},
      {{"mesh", "--json", kBiped, "--polygonizer", "particles", "--updates", "3", "-o", at("jp.ply")}, "particles"},
      {{"render", "--json", kBiped, "--res", "16", "--width", "32", "--height", "32", "-o", at("j.png")}, "triangles"},
      {{"bench", "--json", kBiped, "--updates", "1"}, "scenes"},
      {{"stretch", "--json", kSource + "/examples/textured_biped.wrl", "--frames", "2", "--rest-frames", "0",
        "--mode", "carried"},
       "modes"},
      {{"devices", "--json"}, "serialPorts"},
      {{"info", "--json", kWave}, "devices"},
      {{"convert", "--json", kBvh, at("j.session")}, "samples"},
      {{"record", "--json", "--device", "sim:?rate=200", "-o", at("j.take.session"), "--seconds", "0.3"}, "samples"},
      {{"calibrate", "--json", "--rig", kRig, "--scene", kBiped, "--device", "sim:?motion=still", "--no-wait", "-o",
        at("j.calibration.json")}, "channels"},
      {{"check", "--json", kSource + "/examples/beanito_jump.wrl"}, "clips"},
      {{"mesh", "--json", kSource + "/examples/two_bipeds.wrl", "--res", "12", "-o", at("jw.glb")}, "objects"},
  };
  for (const Case& c : cases) {
    const test::ProgramRun run = runProgram(puppeteer(), c.args);
    EXPECT_EQ(run.exitCode, kOk) << c.args.front() << ": " << run.err;
    nlohmann::json report;
    ASSERT_NO_THROW(report = nlohmann::json::parse(run.out)) << c.args.front() << ":\n" << run.out;
    EXPECT_TRUE(report.contains(c.key)) << c.args.front() << ":\n" << run.out;
  }
}

// stdout and stderr into one pipe (`cmd 2>&1 | less`) keep the order things were printed in: the replay's report
// line comes before the error that follows it (here: no display to open a window on).
TEST_F(CliTest, StdoutAndStderrStayInOrderWhenPiped) {
  test::ProgramOptions merged;
  merged.mergeOutput = true;
  const test::ProgramRun run = runProgram(puppeteer(), {"replay", kWave, kBiped, "--frames", "1"}, merged);
  ASSERT_NE(run.exitCode, kOk) << run.out;
  const size_t report = run.out.find("replaying"), error = run.out.find("error");
  ASSERT_NE(report, std::string::npos) << run.out;
  ASSERT_NE(error, std::string::npos) << run.out;
  EXPECT_LT(report, error) << run.out;
}

}  // namespace
}  // namespace imps::app
