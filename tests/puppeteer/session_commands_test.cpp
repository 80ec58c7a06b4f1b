// SPDX-License-Identifier: MIT
// `puppeteer info` and `convert` on sessions whose timestamps are whatever a file may hold (the extremes of int64).
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "cli.h"
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

}  // namespace
}  // namespace imps::app
