// SPDX-License-Identifier: MIT
// `puppeteer calibrate --session` end to end (a recorded session → a calibration file), and calibrations stored in
// sessions (SessionWriter → readSession → the calibration in force for a sample).
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "calibration/calibration.h"
#include "cli.h"
#include "imps/scene_reader.h"
#include "imps/utf8.h"
#include "session_calibration.h"
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
double mount(size_t ch) { return ch % 5 == 0 ? std::fmod(4094.0 + static_cast<double>(ch % 4), 4096.0) : 300.0 + 111.0 * static_cast<double>(ch); }

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

TEST(SessionCalibration, ReplayFindsTheCalibrationItWasCapturedWith) {
  TempDir dir;
  const auto path = dir.path / "take.session";
  const drivers::DeviceInfo dev = device32();
  auto first = calibration::Calibration::readFile(kSource + "/examples/simple_biped.calibration.json", &biped(), &dev);
  ASSERT_TRUE(first.has_value()) << first.error().str();
  calibration::RigMap shifted = first->rigMap();
  for (auto& c : shifted.channels) c.offset = *c.offset + 100;
  auto second = calibration::Calibration::create(shifted, &biped(), &dev);
  ASSERT_TRUE(second.has_value());
  {
    auto w = sim::SessionWriter::create(path, dev);
    ASSERT_TRUE(w.has_value());
    drivers::Sample s;
    s.channelCount = 32;
    ASSERT_TRUE(appendCalibration(*w, *first).has_value());
    for (int k = 0; k < 10; ++k) ASSERT_TRUE(w->append(s).has_value());
    ASSERT_TRUE(appendCalibration(*w, *second).has_value());  // re-calibrated mid-take
    for (int k = 0; k < 10; ++k) ASSERT_TRUE(w->append(s).has_value());
    ASSERT_TRUE(w->close().has_value());
  }
  auto session = sim::readSession(path);
  ASSERT_TRUE(session.has_value()) << session.error().str();
  ASSERT_EQ(session->calibrations.size(), 2u);
  auto at5 = calibrationForSample(*session, 5, &biped(), path.string());
  auto at15 = calibrationForSample(*session, 15, &biped(), path.string());
  ASSERT_TRUE(at5.has_value() && at5->has_value()) << (at5 ? "none" : at5.error().str());
  ASSERT_TRUE(at15.has_value() && at15->has_value());
  EXPECT_EQ((*at5)->toJson(), first->toJson());
  EXPECT_EQ((*at15)->toJson(), second->toJson());
  // A session without calibrations has none to offer.
  sim::Session empty;
  auto none = calibrationForSample(empty, 0);
  ASSERT_TRUE(none.has_value());
  EXPECT_FALSE(none->has_value());
  // A damaged blob is reported against the session.
  session->calibrations[1].json = "{\"version\": 1, \"bits\": 12, \"joints\": [}";
  auto bad = calibrationForSample(*session, 15, &biped(), "take.session");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().str(), "take.session calibration #1:1:39: error: expected a value, found '}'\n");
}

// Sessions converted from BVH by earlier versions carry the clip's channel mapping as a CALIBRATION blob: it is
// not a calibration (channels map by name), so none is in force — no error to report.
TEST(SessionCalibration, OldBvhChannelMappingIsNoCalibration) {
  auto old = sim::readSession(kSource + "/tests/data/sessions/legacy_bvh_mapping.session");
  ASSERT_TRUE(old.has_value()) << old.error().str();
  ASSERT_EQ(old->calibrations.size(), 1u);
  EXPECT_TRUE(isBvhChannelMapping(old->calibrations[0].json));
  auto found = calibrationForSample(*old, 0, &biped(), "legacy_bvh_mapping.session");
  ASSERT_TRUE(found.has_value()) << found.error().str();
  EXPECT_FALSE(found->has_value());
  EXPECT_FALSE(isBvhChannelMapping("{\"version\": 1, \"bits\": 12, \"info\": {\"source\":\"bvh\"}, \"joints\": []}"));
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

}  // namespace
}  // namespace imps::app
