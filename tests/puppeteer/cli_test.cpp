// SPDX-License-Identifier: MIT
// The command line as a user meets it, through the real `puppeteer` program: every command × every kind of failure
// gives the exit code docs/cli.md promises, found before any work is done; misspellings get advice; the streams
// stay in order when piped.
#include <gtest/gtest.h>

#include <poll.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sim/pseudo_terminal.h"
#include "subprocess.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::runProgram;

const std::string kSource = IMPS_SOURCE_DIR;
const std::string kBiped = kSource + "/examples/simple_biped.wrl";
const std::string kRig = kSource + "/examples/simple_biped.rig.json";
const std::string kCalibration = kSource + "/examples/simple_biped.calibration.json";
const std::string kWave = kSource + "/examples/simple_biped_wave.session";
const std::string kBvh = kSource + "/tests/data/bvh/biped_wave.bvh";

// docs/cli.md, "Exit codes".
constexpr int kOk = 0, kInvalidInput = 1, kUsage = 2, kIo = 3;

fs::path puppeteer() { return IMPS_PUPPETEER_BINARY; }

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

struct Failure {
  std::string name;
  std::vector<std::string> args;
  int exitCode;
  std::string stderrHas;  // a phrase the message must contain
};

void expectAll(const std::vector<Failure>& table) {
  for (const Failure& f : table) {
    const test::ProgramRun run = runProgram(puppeteer(), f.args);
    EXPECT_EQ(run.exitCode, f.exitCode) << f.name << "\nstdout: " << run.out << "\nstderr: " << run.err;
    EXPECT_NE(run.err.find(f.stderrHas), std::string::npos)
        << f.name << ": stderr lacks '" << f.stderrHas << "':\n" << run.err;
    // One failure, one cause: a single error line.
    size_t errors = 0;
    for (size_t at = run.err.find("error:"); at != std::string::npos; at = run.err.find("error:", at + 1)) ++errors;
    EXPECT_LE(errors, f.exitCode == kInvalidInput ? 8u : 1u) << f.name << ": more than one cause:\n" << run.err;
  }
}

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

// `stretch` needs a textured character with the joint it bends; its mode is one of three words.
TEST_F(CliTest, StretchRefusesScenesItCannotMeasure) {
  const std::string textured = kSource + "/examples/textured_biped.wrl";
  expectAll({
      {"untextured", {"stretch", kBiped}, kInvalidInput, "no primitive has a texture generator"},
      {"joint", {"stretch", textured, "--joint", "Elbow"}, kInvalidInput, "no joint named 'Elbow'"},
      {"mode", {"stretch", textured, "--mode", "sliding"}, kUsage, "--mode"},
  });
}

// `stretch --pictures` paints the dot and renders the joint at rest, bent and back.
TEST_F(CliTest, StretchPicturesShowTheJointAtRestBentAndBack) {
  const auto run = runProgram(puppeteer(), {"stretch", kSource + "/examples/textured_biped.wrl", "--frames", "2",
                                            "--rest-frames", "0", "--mode", "carried", "--pictures", at("elbow")});
  ASSERT_EQ(run.exitCode, kOk) << run.err;
  EXPECT_NE(run.out.find("carried"), std::string::npos) << run.out;
  for (const char* stage : {"rest", "bent", "back"})
    EXPECT_GT(fs::file_size(at(std::string("elbow_carried_") + stage + ".png")), 1000u) << stage;
  EXPECT_FALSE(fs::exists(at("elbow_projective_rest.png")));
}

TEST_F(CliTest, AnUnknownOptionIsAUsageErrorForEveryCommand) {
  const std::vector<std::vector<std::string>> commands = {
      {"check", kBiped}, {"mesh", kBiped, "-o", at("m.ply")}, {"render", kBiped, "-o", at("r.png")},
      {"bench", kBiped}, {"stretch", kBiped}, {"devices"}, {"sim", "--pty"},
      {"record", "--device", "sim:", "-o", at("t.session")},
      {"calibrate", "--rig", kRig, "--scene", kBiped, "--session", kWave, "-o", at("c.json")},
      {"info", kWave}, {"convert", kBvh, at("c.session")}, {"view", kBiped}, {"replay", kWave, kBiped},
      {"live", kBiped, "--device", "sim:"}};
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
      // The viewer never opens (there is no display here): the name is refused before the first frame.
      {"view", {"view", kBiped, "--frames", "100000", "--screenshot", at("x.jpg")}, kUsage, "not '.jpg'"},
      {"replay", {"replay", kWave, kBiped, "--frames", "100000", "--screenshot", at("x.jpg")}, kUsage, "not '.jpg'"},
      {"live", {"live", kBiped, "--device", "sim:", "--frames", "100000", "--screenshot", at("x")}, kUsage,
       "without an extension"},
  });
  for (const char* name : {"m.txt", "r.jpg", "c.txt", "x.jpg", "x"}) EXPECT_FALSE(fs::exists(at(name))) << name;
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
  EXPECT_NE(run.err.find("did you mean '--calibration'?"), std::string::npos) << run.err;
  // Nothing close: the commands are listed instead.
  run = runProgram(puppeteer(), {"xyzzyplugh"});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_NE(run.err.find("(commands: mesh, check, render"), std::string::npos) << run.err;
}

TEST_F(CliTest, ARangeErrorIsReadable) {
  const test::ProgramRun run = runProgram(puppeteer(), {"mesh", kBiped, "-o", at("m.ply"), "--cell", "0"});
  EXPECT_EQ(run.exitCode, kUsage);
  EXPECT_LT(run.err.size(), 200u) << run.err;  // was "Value 0 not in range 2.2250738585072014e-308 to 1797…"
}

// ---- Out of the box

// The documented calibration walkthrough works with what ships: the simulator holding the calibration pose.
TEST_F(CliTest, CalibrateSucceedsWithTheBundledPieces) {
  const test::ProgramRun run =
      runProgram(puppeteer(), {"calibrate", "--rig", kRig, "--scene", kBiped, "--device", "sim:?motion=still&noise=1",
                               "--no-wait", "-o", at("still.calibration.json")});
  EXPECT_EQ(run.exitCode, kOk) << run.out << run.err;
  EXPECT_TRUE(fs::exists(at("still.calibration.json")));
  // The calibration it wrote drives the character: replay of a take recorded with it maps by that calibration.
  const test::ProgramRun info = runProgram(puppeteer(), {"info", "--json", kWave});
  EXPECT_EQ(info.exitCode, kOk) << info.err;
}

// A 12-bit rig map on a line-protocol device: calibrate and live agree. Without bits=12 both refuse it (naming
// the key to add); with it calibrate succeeds.
TEST_F(CliTest, CalibrateAndLiveAgreeOnALineDevicesBits) {
  test::ProgramRun run = runProgram(puppeteer(), {"calibrate", "--rig", kRig, "--scene", kBiped, "--device",
                                                  "sim:?protocol=lines&motion=still&bits=12", "--no-wait", "-o",
                                                  at("lines.calibration.json")});
  EXPECT_EQ(run.exitCode, kOk) << run.out << run.err;
  EXPECT_TRUE(fs::exists(at("lines.calibration.json")));
  run = runProgram(puppeteer(), {"live", kBiped, "--device", "sim:?protocol=lines&motion=still", "--calibration",
                                 kCalibration, "--frames", "1"});
  EXPECT_EQ(run.exitCode, kInvalidInput) << run.out << run.err;
  EXPECT_NE(run.err.find("add bits=12 to the device spec"), std::string::npos) << run.err;
  run = runProgram(puppeteer(), {"calibrate", "--rig", kRig, "--scene", kBiped, "--device",
                                 "sim:?protocol=lines&motion=still&bits=16", "--no-wait", "-o", at("l16.json")});
  EXPECT_EQ(run.exitCode, kInvalidInput) << run.out << run.err;
  EXPECT_NE(run.err.find("12-bit encoders"), std::string::npos) << run.err;
}

// A session converted from BVH by an earlier version carries the BVH channel mapping as its "calibration": it is
// not taken for one (the clip is retargeted from its skeleton), with no note; the bundled take has none any more.
TEST_F(CliTest, ReplayOfABvhSessionSaysNothingAboutCalibrations) {
  for (const std::string& session : {kWave, kSource + "/tests/data/sessions/legacy_bvh_mapping.session", kBvh}) {
    const test::ProgramRun run = runProgram(puppeteer(), {"replay", session, kBiped, "--frames", "1"});
    EXPECT_NE(run.out.find("replaying"), std::string::npos) << session << "\n" << run.out << run.err;
    EXPECT_NE(run.out.find(": clip retargeted"), std::string::npos) << session << "\n" << run.out;
    EXPECT_EQ(run.out.find("calibration does not apply"), std::string::npos) << session << "\n" << run.out;
    EXPECT_EQ(run.err.find("calibration"), std::string::npos) << session << "\n" << run.err;
  }
  const test::ProgramRun info = runProgram(puppeteer(), {"info", "--json", kWave});
  ASSERT_EQ(info.exitCode, kOk) << info.err;
  EXPECT_TRUE(nlohmann::json::parse(info.out)["calibrations"].empty()) << info.out;
}

// ---- The command line, consistent

// replay takes SESSION SCENE; the other order (view and live take the scene first) works too.
TEST_F(CliTest, ReplayAcceptsTheSceneFirst) {
  const test::ProgramRun run = runProgram(
      puppeteer(), {"replay", kBiped, kBvh, "--frames", "1", "--export-session", at("swapped.session")});
  EXPECT_NE(run.out.find("replaying"), std::string::npos) << run.out << run.err;
  EXPECT_TRUE(fs::exists(at("swapped.session")));
}

// record --calibration stores the calibration in force with the take; a missing directory is one cause.
TEST_F(CliTest, RecordStoresTheCalibrationGiven) {
  test::ProgramRun run = runProgram(puppeteer(), {"record", "--device", "sim:?rate=200", "--calibration",
                                                  kCalibration, "-o", at("cal.session"), "--seconds", "0.3"});
  ASSERT_EQ(run.exitCode, kOk) << run.out << run.err;
  run = runProgram(puppeteer(), {"info", "--json", at("cal.session")});
  ASSERT_EQ(run.exitCode, kOk) << run.err;
  const auto info = nlohmann::json::parse(run.out);
  ASSERT_EQ(info["calibrations"].size(), 1u) << run.out;
  EXPECT_EQ(info["calibrations"][0]["firstSample"], 0);
  run = runProgram(puppeteer(), {"record", "--device", "sim:", "-o", at("nodir/take.session"), "--seconds", "1"});
  EXPECT_EQ(run.exitCode, kIo);
  EXPECT_EQ(run.err.find("never started streaming"), std::string::npos) << run.err;
}

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

// Progress: a status line on a terminal, erased before the report; nothing when stderr is a pipe.
TEST_F(CliTest, LongWorkShowsProgressOnATerminalOnly) {
  const std::vector<std::string> args = {"mesh", kBiped, "--res", "48", "-o", at("progress.ply")};
  const test::ProgramRun piped = runProgram(puppeteer(), args);
  ASSERT_EQ(piped.exitCode, kOk) << piped.err;
  EXPECT_EQ(piped.err, "");
  auto pty = sim::PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  test::ProgramOptions onTerminal;
  onTerminal.stderrPath = pty->slavePath();
  const test::ProgramRun shown = runProgram(puppeteer(), args, onTerminal);
  ASSERT_EQ(shown.exitCode, kOk);
  std::string terminal;
  char buffer[4096];
  for (pollfd ready{pty->master(), POLLIN, 0}; ::poll(&ready, 1, 200) > 0;) {
    const ssize_t n = ::read(pty->master(), buffer, sizeof buffer);
    if (n <= 0) break;
    terminal.append(buffer, size_t(n));
  }
  ASSERT_GE(terminal.size(), 4u);
  EXPECT_NE(terminal.find("puppeteer mesh: polygonizing"), std::string::npos) << terminal;
  EXPECT_NE(terminal.find("puppeteer mesh: writing"), std::string::npos) << terminal;
  EXPECT_EQ(terminal.substr(terminal.size() - 4), "\r\033[K") << "the line is erased at the end";
}

// record's live counter line is redrawn with \r on a terminal only: into a pipe or a log it writes one line per
// change of state, and the summary carries the counters.
TEST_F(CliTest, RecordIsQuietOfRedrawnLinesWhenPiped) {
  const test::ProgramRun run =
      runProgram(puppeteer(), {"record", "--device", "sim:?rate=200", "-o", at("quiet.session"), "--seconds", "0.3"});
  ASSERT_EQ(run.exitCode, kOk) << run.err;
  EXPECT_EQ(run.err.find('\r'), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("puppeteer record: streaming\n"), std::string::npos) << run.err;
}

// The live app refuses a Marching Cubes grid beyond the cell limit before opening a window, as `mesh` does (it
// used to show an empty window).
TEST_F(CliTest, ViewRefusesAGridBeyondTheCellLimit) {
  const std::string scene = at("fine.wrl");
  {
    std::ofstream out(scene);
    out << "#VRML V2.0 utf8\nMarchingCubes { cellSize 0.0001 sceneGraph RigidTransform { children [ Metaball { } ] } }\n";
  }
  const test::ProgramRun run = runProgram(puppeteer(), {"view", scene, "--frames", "1"});
  EXPECT_EQ(run.exitCode, 1) << run.err;
  EXPECT_NE(run.err.find("more than the limit of"), std::string::npos) << run.err;
}

// ---- The particle tesselator's report (issue 15)

// bench checks every render's mesh: on a fast swing, on the project's own small clip (retargeted as replay does) and
// on a recorded session, each render closed and manifold, reported as JSON and one CSV line per render.
TEST_F(CliTest, BenchChecksEveryRenderOfASwingAClipAndASession) {
  const std::vector<std::string> coarse = {"--desired-radius", "0.0432", "--json"};  // ~900 particles
  struct Case {
    std::string motion;
    int renders;
  } cases[] = {{"swing:720", 12}, {kBvh, 4}, {kWave, 4}};
  for (const Case& c : cases) {
    std::vector<std::string> args = {"bench", kBiped, "--motion", c.motion, "--hz", "60", "--renders",
                                     std::to_string(c.renders), "--csv", at("bench.csv")};
    args.insert(args.end(), coarse.begin(), coarse.end());
    const test::ProgramRun run = runProgram(puppeteer(), args);
    ASSERT_EQ(run.exitCode, kOk) << c.motion << ": " << run.err;
    const nlohmann::json report = nlohmann::json::parse(run.out);
    const nlohmann::json& scene = report["scenes"][0];
    for (const char* key : {"renders", "renders_with_holes", "max_boundary_edges", "renders_with_nonmanifold",
                            "max_nonmanifold_edges", "max_nonmanifold_vertices", "renders_with_folds",
                            "fissions_per_update_settled", "worst_f_minus_iso", "renders_with_fallback"})
      EXPECT_TRUE(scene.contains(key)) << c.motion << ": " << key;
    EXPECT_EQ(scene["renders"], c.renders) << c.motion;
    EXPECT_EQ(scene["renders_with_holes"], 0) << c.motion;
    EXPECT_EQ(scene["renders_with_nonmanifold"], 0) << c.motion;
    std::ifstream csv(at("bench.csv"));
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line.rfind("scene,render,seconds,particles,triangles,boundary_edges,", 0), 0u) << line;
    int rows = 0;
    while (std::getline(csv, line)) ++rows;
    EXPECT_EQ(rows, c.renders) << c.motion;
  }
  struct Bad {
    std::vector<std::string> args;
    int code;
    std::string says;
  } bad[] = {
      {{"--motion", at("missing.bvh")}, kInvalidInput, "no such file"},
      {{"--motion", at("garbage.bvh")}, kInvalidInput, "garbage.bvh"},
      {{"--motion", "swing:fast"}, kUsage, "swing:fast"},
      {{"--motion", "wobble"}, kUsage, "--motion"},
      {{"--csv", at("report.txt")}, kUsage, "--csv"},
      {{"--csv", at("nodir/report.csv")}, kIo, "nodir"},
      {{"--hz", "0"}, kUsage, "--hz"},
  };
  for (const Bad& b : bad) {
    std::vector<std::string> args = {"bench", kBiped, "--renders", "1"};
    args.insert(args.end(), b.args.begin(), b.args.end());
    const test::ProgramRun run = runProgram(puppeteer(), args);
    EXPECT_EQ(run.exitCode, b.code) << b.args[1] << ": " << run.err;
    EXPECT_NE(run.err.find(b.says), std::string::npos) << run.err;
  }
}

// mesh --polygonizer particles always checks its mesh: a scene where the particles miss a small blob that Marching
// Cubes finds (twelve metaballs, a desiredRadius of 0.3 m against radii of 0.15-0.35 m) exits 4 and says so; the mesh
// is written all the same. The same scene without its Tesselator3MP node gets a desiredRadius from its smallest
// metaball (issue 15) and meshes closed with every component, exit 0.
TEST_F(CliTest, ParticleMeshMissingPartOfTheSurfaceExits4) {
  const std::string balls = "ExponentialBlend {\n  variance 0.25\n  children [\n"
                       "    Metaball { center 0.939 -1.308 0.851 radius 0.267 }\n"
                       "    Metaball { center 0.146 -1.031 -0.394 radius 0.176 }\n"
                       "    Metaball { center 1.202 -0.405 0.604 radius 0.250 }\n"
                       "    Metaball { center -0.659 -0.226 1.153 radius 0.262 }\n"
                       "    Metaball { center 0.598 1.372 0.434 radius 0.230 }\n"
                       "    Metaball { center -1.395 -0.707 -1.069 radius 0.155 }\n"
                       "    Metaball { center 1.166 0.646 -1.215 radius 0.313 }\n"
                       "    Metaball { center -0.913 1.281 -0.251 radius 0.189 }\n"
                       "    Metaball { center 0.302 0.066 1.391 radius 0.337 }\n"
                       "    Metaball { center -1.275 0.467 0.285 radius 0.214 }\n"
                       "    Metaball { center 0.016 0.553 -0.792 radius 0.158 }\n"
                       "    Metaball { center -0.388 -1.448 0.955 radius 0.296 }\n  ]\n}\n";
  write("blobs12.wrl", "#VRML V2.0 utf8\nTesselator3MP {\n  desiredRadius 0.3\n  sceneGraph " + balls + "}\n");
  const test::ProgramRun run =
      runProgram(puppeteer(), {"mesh", at("blobs12.wrl"), "--polygonizer", "particles", "-o", at("blobs12.ply")});
  EXPECT_EQ(run.exitCode, 4) << run.err;
  EXPECT_NE(run.err.find("Marching Cubes finds"), std::string::npos) << run.err;
  EXPECT_TRUE(std::filesystem::exists(at("blobs12.ply")));
  write("blobs12_default.wrl", "#VRML V2.0 utf8\n" + balls);
  const test::ProgramRun fine = runProgram(
      puppeteer(), {"mesh", at("blobs12_default.wrl"), "--polygonizer", "particles", "-o", at("blobs12_default.ply")});
  EXPECT_EQ(fine.exitCode, kOk) << fine.out << fine.err;
  EXPECT_NE(fine.out.find("from the scene's feature size"), std::string::npos) << fine.out;
  EXPECT_NE(fine.out.find("closed 2-manifold"), std::string::npos) << fine.out;
  EXPECT_NE(fine.out.find("12 components (Marching Cubes at"), std::string::npos) << fine.out;
  const test::ProgramRun biped = runProgram(puppeteer(), {"mesh", kBiped, "--polygonizer", "particles", "--updates",
                                                          "3", "-o", at("biped.ply")});
  EXPECT_EQ(biped.exitCode, kOk) << biped.err;
  EXPECT_NE(biped.out.find("closed 2-manifold"), std::string::npos) << biped.out;
}

// ---- Noise

// Particle runs with more threads than the machine has cores used to print oneTBB's "The number of workers is
// currently limited to …" warning.
TEST_F(CliTest, ParticleRunsPrintNoThreadingWarnings) {
  for (const char* threads : {"2", "3", "8"}) {
    const test::ProgramRun run = runProgram(puppeteer(), {"mesh", kBiped, "--polygonizer", "particles", "--updates",
                                                          "2", "--threads", threads, "-o", at("t.ply")});
    EXPECT_EQ(run.exitCode, kOk) << run.err;
    EXPECT_EQ(run.err.find("TBB"), std::string::npos) << threads << " threads:\n" << run.err;
    EXPECT_EQ(run.err.find("limited to"), std::string::npos) << threads << " threads:\n" << run.err;
  }
}

// Each scene warning is printed once — also when the scene has errors too — and "1 set" is singular.
TEST_F(CliTest, CheckPrintsEachWarningOnceInGoodGrammar) {
  const std::string lineSeg = "LineSeg {\n  point1 0 0 0  point2 0.1 0 0  radius1 0.5  radius2 0.1\n}\n";
  write("contained.wrl", "#VRML V2.0 utf8\n" + lineSeg);
  write("contained_bad.wrl", "#VRML V2.0 utf8\n" + lineSeg + "Metaball { radius -2 }\n");
  for (const char* name : {"contained.wrl", "contained_bad.wrl"}) {
    const test::ProgramRun run = runProgram(puppeteer(), {"check", at(name)});
    EXPECT_EQ(run.exitCode, std::string(name) == "contained.wrl" ? kOk : kInvalidInput) << run.err;
    const size_t first = run.err.find("warning:");
    ASSERT_NE(first, std::string::npos) << run.err;
    EXPECT_EQ(run.err.find("warning:", first + 1), std::string::npos) << name << " printed it twice:\n" << run.err;
  }
  const test::ProgramRun run = runProgram(puppeteer(), {"check", at("contained.wrl")});
  EXPECT_NE(run.out.find("(1 set:"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace imps::app
