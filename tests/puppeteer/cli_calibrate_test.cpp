// SPDX-License-Identifier: MIT
// `puppeteer calibrate` (puppeteer/src/cli_calibrate.cpp): in process from recorded sessions (a session → a
// calibration file that reads back with the offsets recorded), and through the real program against the simulated
// armature, with docs/cli.md's exit code and message for every failure.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include <nlohmann/json.hpp>

#include "calibration/calibration.h"
#include "cli.h"
#include "cli_run.h"
#include "examples.h"
#include "scratch_dir.h"
#include "imps/scene_reader.h"
#include "imps/utf8.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

constexpr double kGain12 = 4096 / (2 * std::numbers::pi);
const std::string kSource = IMPS_SOURCE_DIR;

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    path = std::filesystem::temp_directory_path() / ("imps_calibrate_" + std::to_string(::getpid()) + "_" +
                                                     std::to_string(counter()++));
    std::filesystem::create_directories(path);
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  static int& counter() {
    static int n = 0;
    return n;
  }
};

drivers::DeviceInfo device32() {
  drivers::DeviceInfo d;
  d.name = "IMPS Simulated Monkey";
  d.serialNumber = "SIM-1";
  d.channelCount = 32;
  d.bitsPerChannel = 12;
  d.hasDeviceTimestamp = true;
  for (int i = 0; i < 32; ++i) d.channelNames.push_back("enc" + std::to_string(i));
  return d;
}

// Channel mounting: counts at the T-pose (several near the wrap).
double mount(size_t ch) {
  return ch % 5 == 0 ? std::fmod(4094.0 + static_cast<double>(ch % 4), 4096.0)
                     : 300.0 + 111.0 * static_cast<double>(ch);
}

uint32_t countFor(size_t ch, double angle, int sign = 1) {
  double c = std::fmod(std::round(mount(ch) + sign * angle * kGain12), 4096.0);
  if (c < 0) c += 4096;
  return static_cast<uint32_t>(c);
}

// 1 s of T-pose at 1 kHz with ±1 count of wobble, then 1 s with the elbows (channels 16 L_Forearm y, 17 R_Forearm
// y) bent 90 degrees forward: L -90, R +90. `rightElbowSign` -1 simulates an encoder mounted reversed.
void writeSession(const std::filesystem::path& path, int rightElbowSign = 1,
                  const drivers::DeviceInfo& device = device32()) {
  auto w = sim::SessionWriter::create(path, device);
  ASSERT_TRUE(w.has_value()) << w.error().str();
  for (int k = 0; k < 2000; ++k) {
    drivers::Sample s;
    s.sequence = static_cast<uint32_t>(k);
    s.deviceTimeNs = int64_t{k} * 1'000'000;
    s.arrivalTimeNs = 5'000'000'000 + s.deviceTimeNs;
    s.channelCount = 32;
    for (size_t ch = 0; ch < 32; ++ch) {
      double angle = ((k + static_cast<int>(ch)) % 3 - 1) / kGain12;
      if (k >= 1000 && ch == 16) angle = -std::numbers::pi / 2;
      if (k >= 1000 && ch == 17) angle = std::numbers::pi / 2;
      s.counts[ch] = countFor(ch, angle, ch == 17 ? rightElbowSign : 1);
    }
    ASSERT_TRUE(w->append(s).has_value());
  }
  ASSERT_TRUE(w->close().has_value());
}

int runCalibrate(std::vector<std::string> args) {
  CLI::App app("puppeteer");
  Commands commands;
  addCalibrationCommands(app, commands);
  args.insert(args.begin(), "calibrate");
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

const Character& biped() {
  static const Character c = [] {
    auto scene = readSceneFile(kSource + "/examples/simple_biped.wrl");
    EXPECT_TRUE(scene.has_value());
    auto ch = Character::fromScene(*scene);
    EXPECT_TRUE(ch.has_value());
    return std::move(*ch);
  }();
  return c;
}

TEST(CalibrateCommand, FromASessionWritesOffsetsAndPassesTheCheckPose) {
  TempDir dir;
  const auto session = dir.path / "take.session", out = dir.path / "biped.calibration.json";
  writeSession(session);
  const int rc = runCalibrate({"--rig", kSource + "/examples/simple_biped.rig.json", "--scene",
                               kSource + "/examples/simple_biped.wrl", "--session", session.string(), "-o",
                               out.string(), "--window-ms", "500", "--check-pose",
                               kSource + "/examples/simple_biped.check_pose.json"});
  ASSERT_EQ(rc, kExitOk);
  const drivers::DeviceInfo dev = device32();
  auto cal = calibration::Calibration::readFile(out, &biped(), &dev);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  ASSERT_EQ(cal->rigMap().channels.size(), 32u);
  for (size_t i = 0; i < 32; ++i) {
    const auto& c = cal->rigMap().channels[i];
    EXPECT_LE(std::abs(calibration::countDelta(*c.offset, mount(static_cast<size_t>(c.channel)), 4096,
                                               calibration::EncoderKind::Absolute)),
              0.5)
        << i;
  }
  EXPECT_EQ(cal->rigMap().device, "IMPS Simulated Monkey");
  EXPECT_NE(cal->rigMap().info.find("\"window_ms\""), std::string::npos);
  // The recorded bent-elbow sample reads as 90 degrees through the new calibration.
  auto read = sim::readSession(session);
  ASSERT_TRUE(read.has_value());
  const auto& last = read->samples.back();
  EXPECT_NEAR(cal->angle(16, last.counts[16]), -std::numbers::pi / 2, 1.5 / kGain12);
  EXPECT_NEAR(cal->angle(17, last.counts[17]), std::numbers::pi / 2, 1.5 / kGain12);
}

TEST(CalibrateCommand, ADeviceNameThatIsNotUtf8IsWrittenAsValidJson) {
  // A device's name and serial are whatever bytes it sent; the calibration file is JSON, which must be UTF-8.
  TempDir dir;
  const auto session = dir.path / "take.session", out = dir.path / "biped.calibration.json";
  drivers::DeviceInfo dev = device32();
  dev.name = "Monkey \xFF\xFE";
  dev.serialNumber = "SN-\xC3";
  writeSession(session, 1, dev);
  const int rc = runCalibrate({"--rig", kSource + "/examples/simple_biped.rig.json", "--scene",
                               kSource + "/examples/simple_biped.wrl", "--session", session.string(), "-o",
                               out.string(), "--window-ms", "500"});
  ASSERT_EQ(rc, kExitOk);
  std::ifstream in(out, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(firstInvalidUtf8(text), text.size()) << text;
  auto cal = calibration::Calibration::readFile(out, &biped(), &dev);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  EXPECT_EQ(cal->rigMap().device, "Monkey \uFFFD\uFFFD");
  EXPECT_NE(cal->rigMap().info.find("\"serial\":\"SN-\uFFFD\""), std::string::npos) << cal->rigMap().info;
}

TEST(CalibrateCommand, AReversedChannelFailsTheCheckPoseAndWritesNothing) {
  TempDir dir;
  const auto session = dir.path / "take.session", out = dir.path / "biped.calibration.json";
  writeSession(session, -1);
  testing::internal::CaptureStderr();
  const int rc = runCalibrate({"--rig", kSource + "/examples/simple_biped.rig.json", "--scene",
                               kSource + "/examples/simple_biped.wrl", "--session", session.string(), "-o",
                               out.string(), "--check-pose", kSource + "/examples/simple_biped.check_pose.json"});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(rc, kExitInvalidInput);
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_NE(err.find("channel 17 'enc17' (R_Forearm y) reads -90.0 deg for a target of 90.0 deg: looks reversed; "
                     "set \"sign\": -1"),
            std::string::npos)
      << err;
}

TEST(CalibrateCommand, RigMapErrorsAreReportedWithLocations) {
  TempDir dir;
  const auto session = dir.path / "take.session", rig = dir.path / "bad.rig.json";
  writeSession(session);
  {
    std::ofstream f(rig);
    f << "{\"version\": 1, \"bits\": 12, \"joints\": [\n"
         "  {\"joint\": \"L_Elbow\", \"channels\": [{\"channel\": 40, \"axis\": \"y\", \"sign\": 1}]}\n"
         "]}\n";
  }
  testing::internal::CaptureStderr();
  const int rc = runCalibrate({"--rig", rig.string(), "--scene", kSource + "/examples/simple_biped.wrl", "--session",
                               session.string(), "-o", (dir.path / "x.json").string()});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(rc, kExitInvalidInput);
  EXPECT_NE(err.find(rig.string() + ":2:49: error: channel 40 is out of range: device 'IMPS Simulated Monkey' has 32 "
                                    "channels (0..31)"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find(rig.string() + ":2:13: error: unknown joint 'L_Elbow'"), std::string::npos) << err;
}

TEST(CalibrateCommand, NeedsExactlyOneSource) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(runCalibrate({"--rig", "r", "--scene", "s", "-o", "o"}), kExitUsage);
  testing::internal::GetCapturedStderr();
}

}  // namespace
}  // namespace imps::app

namespace imps::app {
namespace {

TEST(CalibrateCommand, LiveDeviceThatKeepsMovingIsRejectedAsNoisy) {
  // The simulated armature's generated motion swings every channel: no window of it is a held pose. stdin is not
  // --no-wait: the "press Enter" prompts do not wait.
  TempDir dir;
  const auto out = dir.path / "x.json";
  testing::internal::CaptureStderr();
  const int rc = runCalibrate({"--rig", kSource + "/examples/simple_biped.rig.json", "--scene",
                               kSource + "/examples/simple_biped.wrl", "--device", "sim:?channels=32&bits=12",
                               "-o", out.string(), "--window-ms", "300", "--no-wait"});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(rc, kExitInvalidInput) << err;
  EXPECT_NE(err.find("the calibration-pose window was rejected"), std::string::npos) << err;
  EXPECT_NE(err.find("is too noisy"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(out));
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

const std::string kRig = sourceFile("examples/simple_biped.rig.json");
const std::string kBiped = sourceFile("examples/simple_biped.wrl");

// The documented walkthrough works with what ships: the simulator holding the calibration pose. The file it writes
// reads back as a calibration of the character, with the summary's channels; its offsets are the still pose's counts.
TEST(CalibrateCommand, SucceedsWithTheBundledPieces) {
  const ScratchDir dir("imps_cli_calibrate");
  const std::string out = (dir / "still.calibration.json").string();
  const test::ProgramRun run = runPuppeteer(
      {"calibrate", "--json", "--rig", kRig, "--scene", kBiped, "--device", "sim:?motion=still&noise=1", "--no-wait",
       "-o", out});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  EXPECT_TRUE(contains(run.err, "Hold the armature in the calibration pose")) << "the walkthrough goes to stderr";
  auto cal = calibration::Calibration::readFile(out, &test::exampleCharacter("simple_biped"), nullptr);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  EXPECT_EQ(cal->rigMap().channels.size(), summary["channels"].get<size_t>());
  EXPECT_EQ(cal->rigMap().device, "IMPS Simulated Monkey");
  for (const auto& c : cal->rigMap().channels) EXPECT_TRUE(c.offset.has_value()) << c.channel;
  EXPECT_LT(summary["noiseMaxDeg"].get<double>(), 0.5);
  // The bundled calibration was made the same way: both read the still pose alike.
  auto bundled = calibration::Calibration::readFile(sourceFile("examples/simple_biped.calibration.json"),
                                                    &test::exampleCharacter("simple_biped"), nullptr);
  ASSERT_TRUE(bundled.has_value()) << bundled.error().str();
  ASSERT_EQ(bundled->rigMap().channels.size(), cal->rigMap().channels.size());
  for (size_t i = 0; i < cal->rigMap().channels.size(); ++i)
    EXPECT_NEAR(bundled->angle(i, *cal->rigMap().channels[i].offset), 0.0, 0.01) << "channel " << i;
}

// A 12-bit rig map on a line-protocol device: calibrate and live agree. Without bits=12 both refuse it (naming
// the key to add); with it calibrate succeeds.
TEST(CalibrateCommand, CalibrateAndLiveAgreeOnALineDevicesBits) {
  const ScratchDir dir("imps_cli_calibrate");
  test::ProgramRun run = runPuppeteer({"calibrate", "--rig", kRig, "--scene", kBiped, "--device",
                                       "sim:?protocol=lines&motion=still&bits=12", "--no-wait", "-o",
                                       (dir / "lines.calibration.json").string()});
  EXPECT_EQ(run.exitCode, kCliOk) << describe(run);
  EXPECT_TRUE(std::filesystem::exists(dir / "lines.calibration.json"));
  run = runPuppeteer({"live", kBiped, "--device", "sim:?protocol=lines&motion=still", "--calibration",
                      sourceFile("examples/simple_biped.calibration.json"), "--frames", "1"});
  EXPECT_EQ(run.exitCode, kCliInvalidInput) << describe(run);
  EXPECT_TRUE(contains(run.err, "add bits=12 to the device spec"));
  run = runPuppeteer({"calibrate", "--rig", kRig, "--scene", kBiped, "--device",
                      "sim:?protocol=lines&motion=still&bits=16", "--no-wait", "-o", (dir / "l16.json").string()});
  EXPECT_EQ(run.exitCode, kCliInvalidInput) << describe(run);
  EXPECT_TRUE(contains(run.err, "12-bit encoders"));
}

// A recorded take of the simulator's moving armature: the window is too noisy, the channels are named, nothing is
// written.
TEST(CalibrateCommand, AMovingTakeIsRejectedAsNoisy) {
  const ScratchDir dir("imps_cli_calibrate");
  const std::string take = (dir / "take.session").string(), out = (dir / "cal.json").string();
  ASSERT_EQ(runPuppeteer({"record", "--device", "sim:?rate=200&channels=32", "-o", take, "--seconds", "0.5"}).exitCode,
            kCliOk);
  const test::ProgramRun run = runPuppeteer({"calibrate", "--rig", kRig, "--scene", kBiped, "--session", take, "-o",
                                             out});
  EXPECT_EQ(run.exitCode, kCliInvalidInput) << describe(run);
  EXPECT_TRUE(contains(run.err, "is too noisy"));
  EXPECT_TRUE(contains(run.err, "Nothing was written"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(CalibrateCommand, Failures) {
  const ScratchDir dir("imps_cli_calibrate");
  const std::string wave = sourceFile("examples/simple_biped_wave.session");
  const std::string out = (dir / "c.json").string();
  std::ofstream(dir / "bad.rig.json") << "{\n  \"version\": 1,\n  \"joints\": [ { \"joint\": \"L_Elbo\" } ]\n}\n";
  std::ofstream(dir / "garbage.session") << "not a session\n";
  std::ofstream(dir / "keep.json") << "precious";
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"calibrate", "--rig", kRig, "--scene", kBiped};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  const std::vector<std::string> still = {"--device", "sim:?motion=still", "--no-wait"};
  test::expectFailures({
      {"missing rig", {"calibrate", "--rig", (dir / "none.json").string(), "--scene", kBiped, "--session", wave, "-o",
                       out}, kCliInvalidInput, "no such file"},
      {"missing scene", {"calibrate", "--rig", kRig, "--scene", (dir / "none.wrl").string(), "--session", wave, "-o",
                         out}, kCliInvalidInput, "no such file"},
      {"missing session", with({"--session", (dir / "none.session").string(), "-o", out}), kCliInvalidInput,
       "no such file"},
      {"missing check pose", with({"--session", wave, "-o", out, "--check-pose", (dir / "none.json").string()}),
       kCliInvalidInput, "no such file"},
      {"bad rig map", {"calibrate", "--rig", (dir / "bad.rig.json").string(), "--scene", kBiped, "--session", wave,
                       "-o", out}, kCliInvalidInput, "bad.rig.json:"},
      {"endless rig map", {"calibrate", "--rig", "/dev/zero", "--scene", kBiped, "--session", wave, "-o", out},
       kCliInvalidInput, "/dev/zero: error: cannot read rig map: larger than the 16 MiB limit"},
      {"garbage session", with({"--session", (dir / "garbage.session").string(), "-o", out}), kCliInvalidInput,
       "garbage.session"},
      {"no source", with({"-o", out}), kCliUsage, "give exactly one of --session SESSION or --device SPEC"},
      {"two sources", with({"--session", wave, "--device", "sim:", "-o", out}), kCliUsage, "exactly one of"},
      {"window 0", with({"--session", wave, "-o", out, "--window-ms", "0"}), kCliUsage, "--window-ms"},
      {"noise -1", with({"--session", wave, "-o", out, "--max-noise-deg", "-1"}), kCliUsage, "--max-noise-deg"},
      {"bad spec", with({"--device", "nope", "-o", out}), kCliUsage, "spec:1:1: error"},
      {"an OSC stream", with({"--device", "osc.udp://:9000", "-o", out}), kCliUsage, "OSC pose stream"},
      {"missing directory", with({"--session", wave, "-o", (dir / "nodir/c.json").string()}), kCliIo,
       "does not exist"},
      {"no output", with(still), kCliUsage, "--output"},
      {"misspelt option", with({"--session", wave, "-o", out, "--window-m", "300"}), kCliUsage,
       "did you mean '--window-ms'?"},
      {"rejected over an existing file",
       {"calibrate", "--rig", (dir / "bad.rig.json").string(), "--scene", kBiped, "--session", wave, "-o",
        (dir / "keep.json").string()},
       kCliInvalidInput, "bad.rig.json"},
  });
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(fileBytes(dir / "keep.json"), "precious");
}

}  // namespace
}  // namespace imps::app
