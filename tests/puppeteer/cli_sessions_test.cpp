// SPDX-License-Identifier: MIT
// `puppeteer info` and `convert` (puppeteer/src/cli_sessions.cpp): in process on sessions whose timestamps are whatever
// a file may hold (the extremes of int64), and through the real program: round trips that read back with the BVH and
// session readers, and every failure's exit code and message (docs/cli.md).
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli.h"
#include "cli_run.h"
#include "scratch_dir.h"
#include "sim/bvh.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

struct TempDir {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("imps_session_commands_" + std::to_string(::getpid()) + "_" +
                                ::testing::UnitTest::GetInstance()->current_test_info()->name());
  TempDir() { std::filesystem::create_directories(path); }
  ~TempDir() { std::filesystem::remove_all(path); }
};

int runSessionCommand(std::vector<std::string> args) {
  CLI::App app("puppeteer");
  Commands commands;
  addSessionCommands(app, commands);
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments reversed from a vector
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  for (const Command& c : commands)
    if (c.app->parsed()) return c.run();
  return -1;
}

// A one-channel session whose samples arrive at `times`.
void writeSession(const std::filesystem::path& path, const std::vector<int64_t>& times) {
  drivers::DeviceInfo d;
  d.name = "extreme";
  d.channelCount = 1;
  d.bitsPerChannel = 12;
  auto w = sim::SessionWriter::create(path, d);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  uint32_t sequence = 0;
  for (int64_t t : times) {
    drivers::Sample s;
    s.channelCount = 1;
    s.sequence = sequence++;
    s.arrivalTimeNs = s.deviceTimeNs = t;
    ASSERT_TRUE(w->append(s).has_value());
  }
  ASSERT_TRUE(w->close().has_value());
}

TEST(InfoCommand, TheDurationOfExtremeTimestampsIsTheirRealSpan) {
  // From the earliest to the latest representable time: 2^64 ns, about 18446744073.7 s. The difference used to
  // overflow int64 and print "over -0.000 s".
  TempDir dir;
  const auto path = dir.path / "extreme.session";
  writeSession(path, {std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::max()});
  testing::internal::CaptureStdout();
  const int rc = runSessionCommand({"info", path.string()});
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, kExitOk);
  EXPECT_NE(out.find("2 samples over 18446744073.710 s"), std::string::npos) << out;
}

TEST(ConvertCommand, ExtremeTimestampsGiveTheDefaultFrameTimeNotAWrappedOne) {
  // Every spacing overflows int64: none is measurable, so the clip gets the default 1/60 s (it was a wrapped,
  // meaningless frame time).
  TempDir dir;
  const auto session = dir.path / "extreme.session", bvh = dir.path / "extreme.bvh";
  const int64_t lo = -9'000'000'000'000'000'000, hi = 9'000'000'000'000'000'000;
  writeSession(session, {lo, hi, lo, hi, lo});
  testing::internal::CaptureStdout();
  const int rc = runSessionCommand({"convert", session.string(), bvh.string()});
  testing::internal::GetCapturedStdout();
  ASSERT_EQ(rc, kExitOk);
  auto clip = sim::readBvh(bvh);
  ASSERT_TRUE(clip.has_value()) << clip.error().str();
  EXPECT_NEAR(clip->frameTime, 1.0 / 60.0, 1e-9);
}

// ---- Through the program

using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kClipPath = sourceFile("tests/data/bvh/biped_wave.bvh");

// BVH -> session -> BVH reproduces the clip: the same joints and frames, every rotation within half an encoder
// count (16 bits: 360 / 2^17 degrees), the root translation within half a position count; the reports count what
// was written; info describes the take.
TEST(ConvertCommand, ABvhClipRoundTripsThroughASession) {
  const ScratchDir dir("imps_cli_sessions");
  const std::string session = (dir / "wave.session").string(), bvh = (dir / "wave.bvh").string();
  const test::ProgramRun there = runPuppeteer({"convert", "--json", kClipPath, session});
  ASSERT_EQ(there.exitCode, kCliOk) << describe(there);
  const test::ProgramRun back = runPuppeteer({"convert", "--json", session, bvh});
  ASSERT_EQ(back.exitCode, kCliOk) << describe(back);
  auto original = sim::readBvh(kClipPath);
  auto copy = sim::readBvh(bvh);
  ASSERT_TRUE(original) << original.error().str();
  ASSERT_TRUE(copy) << copy.error().str();
  auto take = sim::readSession(session);
  ASSERT_TRUE(take) << take.error().str();
  const nlohmann::json report = nlohmann::json::parse(there.out);
  EXPECT_EQ(report["frames"], original->frames.size());
  EXPECT_EQ(report["samples"], take->samples.size());
  EXPECT_EQ(report["bits"], 16);
  EXPECT_EQ(nlohmann::json::parse(back.out)["frames"], original->frames.size());
  EXPECT_NEAR(copy->frameTime, original->frameTime, 1e-6);
  ASSERT_EQ(copy->joints.size(), original->joints.size());
  for (size_t j = 0; j < original->joints.size(); ++j) {
    EXPECT_EQ(copy->joints[j].name, original->joints[j].name);
    EXPECT_EQ(copy->joints[j].channels, original->joints[j].channels) << original->joints[j].name;
  }
  ASSERT_EQ(copy->frames.size(), original->frames.size());
  ASSERT_TRUE(take->skeleton.has_value());
  const double halfCount = 360.0 / 65536 / 2 + 1e-5, halfPosition = take->skeleton->positionUnitsPerCount / 2 + 1e-5;
  for (size_t f = 0; f < original->frames.size(); ++f)
    for (size_t j = 0; j < original->joints.size(); ++j)
      for (size_t c = 0; c < original->joints[j].channels.size(); ++c) {
        const size_t k = original->firstChannel(j) + c;
        EXPECT_NEAR(copy->frames[f][k], original->frames[f][k],
                    sim::isRotation(original->joints[j].channels[c]) ? halfCount : halfPosition)
            << "frame " << f << " joint " << original->joints[j].name << " channel " << c;
      }
  // info: the take's samples, whole.
  const test::ProgramRun info = runPuppeteer({"info", session});
  ASSERT_EQ(info.exitCode, kCliOk) << describe(info);
  EXPECT_TRUE(contains(info.out, std::to_string(take->samples.size()) + " samples from 1 device"));
  EXPECT_TRUE(contains(info.out, "closed cleanly"));
  // --bits sets the counts per turn.
  const test::ProgramRun coarse = runPuppeteer({"convert", "--json", "--bits", "12", kClipPath,
                                                (dir / "coarse.session").string()});
  ASSERT_EQ(coarse.exitCode, kCliOk) << describe(coarse);
  auto coarseTake = sim::readSession(dir / "coarse.session");
  ASSERT_TRUE(coarseTake) << coarseTake.error().str();
  EXPECT_EQ(coarseTake->devices[0].bitsPerChannel, 12);
}

// A session cut off mid-record is read up to its last whole record, and info says so (exit 0).
TEST(InfoCommand, ATruncatedSessionIsReadUpToItsLastWholeRecord) {
  const ScratchDir dir("imps_cli_sessions");
  const std::string whole = sourceFile("examples/simple_biped_wave.session");
  const std::string bytes = fileBytes(whole);
  writeBytes(dir / "cut.session", bytes.substr(0, bytes.size() / 2));
  const test::ProgramRun run = runPuppeteer({"info", "--json", (dir / "cut.session").string()});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  EXPECT_EQ(report["closedCleanly"], false);
  const nlohmann::json full = nlohmann::json::parse(runPuppeteer({"info", "--json", whole}).out);
  EXPECT_EQ(full["closedCleanly"], true);
  EXPECT_GT(report["samples"].get<size_t>(), 0u);
  EXPECT_LT(report["samples"].get<size_t>(), full["samples"].get<size_t>());
  const test::ProgramRun text = runPuppeteer({"info", (dir / "cut.session").string()});
  EXPECT_TRUE(contains(text.out, "not closed cleanly"));
}

TEST(InfoCommand, Failures) {
  const ScratchDir dir("imps_cli_sessions");
  writeBytes(dir / "garbage.session", "this is not a session file\n");
  test::expectFailures({
      {"missing", {"info", (dir / "none.session").string()}, kCliInvalidInput, "no such file"},
      {"garbage", {"info", (dir / "garbage.session").string()}, kCliInvalidInput, "garbage.session"},
      {"endless", {"info", "/dev/zero"}, kCliInvalidInput, "/dev/zero: error: not a session file: bad magic"},
      {"a directory", {"info", dir.path().string()}, kCliInvalidInput, "is a directory"},
      {"no session", {"info"}, kCliUsage, "session"},
      {"misspelt option", {"info", "--jsn", sourceFile("examples/simple_biped_wave.session")}, kCliUsage,
       "did you mean '--json'?"},
  });
}

TEST(ConvertCommand, Failures) {
  const ScratchDir dir("imps_cli_sessions");
  writeBytes(dir / "garbage.bvh", "HIERARCHY\nROOT {\n");
  writeBytes(dir / "garbage.session", "this is not a session file\n");
  writeBytes(dir / "existing.session", "precious");
  std::filesystem::create_symlink("/dev/zero", dir / "endless.bvh");
  const std::string out = (dir / "c.session").string();
  test::expectFailures({
      {"missing", {"convert", (dir / "none.bvh").string(), out}, kCliInvalidInput, "no such file"},
      {"garbage BVH", {"convert", (dir / "garbage.bvh").string(), out}, kCliInvalidInput, "garbage.bvh:"},
      {"garbage session", {"convert", (dir / "garbage.session").string(), (dir / "c.bvh").string()},
       kCliInvalidInput, "garbage.session"},
      {"endless BVH", {"convert", (dir / "endless.bvh").string(), out}, kCliInvalidInput,
       "endless.bvh: error: cannot read BVH file: larger than the 256 MiB limit"},
      {"a 1e308 frame time", {"convert", sourceFile("tests/fuzz/seeds/bvh_session/error_frame_time_1e308.bvh"), out},
       kCliInvalidInput, "error_frame_time_1e308.bvh:9:13: error: frame time 1e308 s is longer than the 3600 s"},
      {"BVH to BVH", {"convert", kClipPath, (dir / "c.bvh").string()}, kCliUsage, "cannot convert"},
      {"unknown format", {"convert", kClipPath, (dir / "c.txt").string()}, kCliUsage, "'.txt'"},
      {"bits", {"convert", kClipPath, out, "--bits", "40"}, kCliUsage, "--bits"},
      {"missing directory", {"convert", kClipPath, (dir / "nodir/c.session").string()}, kCliIo, "does not exist"},
      {"never overwrites", {"convert", kClipPath, (dir / "existing.session").string()}, kCliIo,
       "convert never overwrites a file"},
      {"one argument", {"convert", kClipPath}, kCliUsage, "output"},
  });
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(fileBytes(dir / "existing.session"), "precious");
}

}  // namespace
}  // namespace imps::app
