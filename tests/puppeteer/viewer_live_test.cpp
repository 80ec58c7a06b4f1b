// SPDX-License-Identifier: MIT
// The live pose source's recording (key o) and re-calibration (key k) against a simulated armature through the real
// driver stack (in-process transport, device session, pose mailbox), without a window: a recording holds the
// device, the calibration in force and every sample the simulator sent, bit for bit; a still armature calibrates
// (offsets = its counts, saved atomically, applied, recorded); a noisy one is rejected and nothing is written.
#include "viewer_live.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <numbers>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "calibration_flow.h"
#include "cli.h"
#include "drivers/device_spec.h"
#include "drivers/serial_transport.h"
#include "eventually.h"
#include "examples.h"
#include "imps/skeleton_cache.h"
#include "sim/pseudo_terminal.h"
#include "sim/session_file.h"
#include "sim/simulated_armature.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("imps_live_test_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

// A 32-channel, 12-bit session for the simulator to play (the example calibration's device): `moving` samples of
// pseudo-random counts, or one still pose repeated.
fs::path writeSourceSession(const fs::path& dir, bool moving, size_t samples = 700) {
  sim::Session session;
  session.devices.push_back(sim::ArmatureOptions::defaultInfo(32, 12));
  std::mt19937 rng(7);
  for (size_t i = 0; i < samples; ++i) {
    drivers::Sample s;
    s.channelCount = 32;
    s.sequence = uint32_t(i);
    s.deviceTimeNs = int64_t(i) * 1'000'000;
    for (int c = 0; c < 32; ++c) s.counts[c] = moving ? rng() % 4096 : uint32_t(1500 + 37 * c);
    session.samples.push_back(s);
    session.sampleDevice.push_back(0);
  }
  const fs::path path = dir / (moving ? "moving.session" : "still.session");
  auto saved = sim::saveSession(path, session);
  EXPECT_TRUE(saved) << saved.error().str();
  return path;
}

const fs::path kCalibration = fs::path(IMPS_SOURCE_DIR) / "examples/simple_biped.calibration.json";

struct Rig {
  imps::SteadyClock clock;
  std::unique_ptr<LivePoseSource> source;
  SkeletonCache skeleton;

  Rig(const std::string& specText, std::optional<SampleMapper> mapper, LiveSourceOptions live)
      : skeleton(test::exampleCharacter("simple_biped")) {
    auto spec = drivers::parseDeviceSpec(specText);
    EXPECT_TRUE(spec) << spec.error().str();
    auto options = sim::armatureOptionsFromSpec(*spec);
    EXPECT_TRUE(options) << options.error().str();
    source = std::make_unique<LivePoseSource>(sim::simulatedOpener(*options, clock), drivers::sessionOptionsFor(*spec),
                                              test::exampleCharacter("simple_biped"), specText, std::move(mapper),
                                              std::move(live));
  }
  // Runs the "frame loop" for `ms` milliseconds (or until `until` says stop), polling every 5 ms.
  template <class Until>
  void run(int ms, Until until) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < end && !until()) {
      int64_t arrival = 0;
      if (source->poll(skeleton, &arrival)) skeleton.update();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  void run(int ms) {
    run(ms, [] { return false; });
  }
};

std::optional<SampleMapper> exampleCalibration() {
  auto c = calibration::Calibration::readFile(kCalibration, &test::exampleCharacter("simple_biped"));
  EXPECT_TRUE(c) << c.error().str();
  return SampleMapper(std::move(*c), "simple_biped.calibration.json");
}

TEST(LiveRecording, RecordsEverySampleBitExactWithDeviceAndCalibration) {
  TempDir dir;
  const fs::path source = writeSourceSession(dir.path, true);
  auto sent = sim::readSession(source);
  ASSERT_TRUE(sent) << sent.error().str();
  LiveSourceOptions live;
  live.recordPath = (dir.path / "take.session").string();
  Rig rig("sim:" + source.string() + "?rate=1000", exampleCalibration(), live);
  EXPECT_TRUE(rig.source->recording());
  rig.run(600);
  const std::string message = rig.source->finish();
  EXPECT_NE(message.find("recorded"), std::string::npos) << message;
  EXPECT_NE(message.find("take.session"), std::string::npos) << message;

  auto take = sim::readSession(live.recordPath);
  ASSERT_TRUE(take) << take.error().str();
  EXPECT_TRUE(take->recovery.closedCleanly);
  ASSERT_EQ(take->devices.size(), 1u);
  EXPECT_EQ(take->devices[0].channelCount, 32);
  EXPECT_EQ(take->devices[0].bitsPerChannel, 12);
  // The calibration in force, from the first sample on, exactly the file's.
  ASSERT_EQ(take->calibrations.size(), 1u);
  EXPECT_EQ(take->calibrations[0].firstSample, 0u);
  auto recorded = calibration::Calibration::parse(take->calibrations[0].json, "recorded");
  ASSERT_TRUE(recorded) << recorded.error().str();
  EXPECT_EQ(recorded->toJson(), rig.source->calibration()->toJson());
  // Every sample the simulator sent (~1 kHz for 0.6 s), in order, bit for bit: sample k of the stream is the
  // source session's sample k (mod its length), and no sequence number is missing.
  ASSERT_GT(take->samples.size(), 200u);
  const size_t n = sent->samples.size();
  for (size_t i = 0; i < take->samples.size(); ++i) {
    const drivers::Sample& got = take->samples[i];
    const drivers::Sample& want = sent->samples[got.sequence % n];
    ASSERT_EQ(got.channelCount, 32);
    for (int c = 0; c < 32; ++c) ASSERT_EQ(got.counts[c], want.counts[c]) << "sample " << i << " channel " << c;
    if (i > 0) {
      ASSERT_EQ(got.sequence, take->samples[i - 1].sequence + 1) << "a sample is missing before " << i;
    }
  }
}

TEST(LiveRecording, KeyStartsAndStopsATakeInTheRecordDirectory) {
  TempDir dir;
  const fs::path source = writeSourceSession(dir.path, true);
  LiveSourceOptions live;
  live.recordDir = dir.path.string();
  Rig rig("sim:" + source.string() + "?rate=1000", std::nullopt, live);
  rig.run(100);
  EXPECT_FALSE(rig.source->recording());
  const std::string started = rig.source->toggleRecording();
  EXPECT_NE(started.find("recording to"), std::string::npos) << started;
  EXPECT_NE(started.find("take-"), std::string::npos) << started;
  rig.run(300);
  HudInfo info;
  rig.source->describe(info);
  EXPECT_TRUE(info.recording);
  EXPECT_GT(info.recordSamples, 0u);
  EXPECT_GT(info.recordSeconds, 0.0);
  const std::string stopped = rig.source->toggleRecording();
  EXPECT_NE(stopped.find("recorded"), std::string::npos) << stopped;
  EXPECT_FALSE(rig.source->recording());
  size_t takes = 0;
  for (const auto& e : fs::directory_iterator(dir.path)) {
    if (e.path().filename().string().rfind("take-", 0) != 0) continue;
    ++takes;
    EXPECT_EQ(e.path().extension(), ".session");
    auto take = sim::readSession(e.path());
    ASSERT_TRUE(take) << take.error().str();
    EXPECT_TRUE(take->recovery.closedCleanly);
    EXPECT_GT(take->samples.size(), 100u);
    EXPECT_TRUE(take->calibrations.empty());  // mapped by channel names: no calibration in force
  }
  EXPECT_EQ(takes, 1u);
}

TEST(LiveCalibration, StillArmatureCalibratesSavesAppliesAndRecords) {
  TempDir dir;
  const fs::path source = writeSourceSession(dir.path, false);
  LiveSourceOptions live;
  live.recordPath = (dir.path / "take.session").string();
  live.calibrationPath = kCalibration.string();
  live.calibrationOut = (dir.path / "new.calibration.json").string();
  live.calibrate.delayMs = 0;
  live.calibrate.windowMs = 150;
  Rig rig("sim:" + source.string() + "?rate=1000", exampleCalibration(), live);
  rig.run(3000, [&] { return rig.source->recording() && rig.skeleton.generation() > 2; });
  const std::string started = rig.source->recalibrate();
  EXPECT_NE(started.find("averaging"), std::string::npos) << started;
  std::string message;
  rig.run(5000, [&] { return !(message = rig.source->takeMessage()).empty(); });
  ASSERT_NE(message.find("calibrated 32 channels"), std::string::npos) << message;
  EXPECT_NE(message.find("new.calibration.json"), std::string::npos) << message;
  // Saved: offsets are the still pose's counts; and in force.
  auto saved = calibration::Calibration::readFile(live.calibrationOut, &test::exampleCharacter("simple_biped"));
  ASSERT_TRUE(saved) << saved.error().str();
  for (const calibration::ChannelMap& ch : saved->rigMap().channels) {
    ASSERT_TRUE(ch.offset.has_value());
    EXPECT_NEAR(*ch.offset, 1500 + 37 * ch.channel, 1e-6) << "channel " << ch.channel;
  }
  EXPECT_NE(saved->rigMap().info.find("\"window_ms\""), std::string::npos);
  ASSERT_NE(rig.source->calibration(), nullptr);
  EXPECT_EQ(rig.source->calibration()->toJson(), saved->toJson());
  // The take records both calibrations, the new one from the samples after the re-calibration.
  rig.source->finish();
  auto take = sim::readSession(live.recordPath);
  ASSERT_TRUE(take) << take.error().str();
  ASSERT_EQ(take->calibrations.size(), 2u);
  EXPECT_GT(take->calibrations[1].firstSample, 0u);
  EXPECT_EQ(take->calibrations[1].json, saved->toJson());
}

TEST(LiveCalibration, NoisyWindowIsRejectedAndNothingIsWritten) {
  TempDir dir;
  const fs::path source = writeSourceSession(dir.path, false);
  LiveSourceOptions live;
  live.calibrationPath = kCalibration.string();
  live.calibrationOut = (dir.path / "new.calibration.json").string();
  live.calibrate.delayMs = 0;
  live.calibrate.windowMs = 150;
  // ±60 counts of 4096 is about ±5 degrees: far above the 0.5 degree limit.
  Rig rig("sim:" + source.string() + "?rate=1000&noise=60", exampleCalibration(), live);
  rig.run(3000, [&] { return rig.skeleton.generation() > 2; });
  rig.source->recalibrate();
  std::string message;
  rig.run(5000, [&] { return !(message = rig.source->takeMessage()).empty(); });
  EXPECT_NE(message.find("calibration rejected"), std::string::npos) << message;
  EXPECT_NE(message.find("press k again"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(live.calibrationOut));
  // The calibration in force is unchanged.
  auto original = calibration::Calibration::readFile(kCalibration, &test::exampleCharacter("simple_biped"));
  ASSERT_TRUE(original);
  EXPECT_EQ(rig.source->calibration()->toJson(), original->toJson());
}

// Issue 14 item 1, the app's recorder: a DIY line-protocol device on a pseudo-terminal changes from 4 to 6 channels
// mid-take. Every line is recorded: the 6-channel samples under a second device declared as the same armature's
// new layout, not skipped as "from a different device". The link's counters are stored with the take.
TEST(LiveRecording, LayoutChangeMidTakeIsRecordedNotDropped) {
  TempDir dir;
  auto pty = sim::PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  LiveSourceOptions live;
  live.recordPath = (dir.path / "take.session").string();
  drivers::DeviceSessionOptions options;
  options.protocol = drivers::WireProtocol::Lines;
  const Character& character = test::exampleCharacter("simple_biped");
  SkeletonCache skeleton(character);
  LivePoseSource source(drivers::serialOpener(pty->slavePath()), options, character, "serial:" + pty->slavePath(),
                        std::nullopt, live);
  std::string text = "DIY rig\r\n";
  for (int i = 0; i < 20; ++i) text += std::to_string(i) + " 1 2 3\r\n";
  for (int i = 20; i < 40; ++i) text += std::to_string(i) + " 1 2 3 4 5\r\n";
  HudInfo info;
  ASSERT_TRUE(eventually([&] {  // the port is open: what is written now is read
    int64_t arrival = 0;
    source.poll(skeleton, &arrival);
    source.describe(info);
    return info.state == "waiting for hello";
  })) << info.state;
  ASSERT_EQ(::write(pty->master(), text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ASSERT_TRUE(eventually([&] {
    int64_t arrival = 0;
    source.poll(skeleton, &arrival);
    source.describe(info);
    return info.recordSamples >= 40;
  })) << info.recordSamples;
  const std::string message = source.finish();
  EXPECT_NE(message.find("1 channel-layout change"), std::string::npos) << message;
  EXPECT_EQ(source.exitCode(), kExitOk);

  auto take = sim::readSession(live.recordPath);
  ASSERT_TRUE(take) << take.error().str();
  EXPECT_TRUE(take->recovery.closedCleanly);
  ASSERT_EQ(take->samples.size(), 40u);
  ASSERT_EQ(take->devices.size(), 2u);
  EXPECT_EQ(take->devices[0].channelCount, 4);
  EXPECT_EQ(take->devices[1].channelCount, 6);
  EXPECT_EQ(take->layoutChanges, (std::vector<sim::SessionLayoutChange>{{1, 0, 20}}));
  for (size_t i = 0; i < take->samples.size(); ++i) {
    EXPECT_EQ(take->samples[i].counts[0], i);
    EXPECT_EQ(take->sampleDevice[i], i < 20 ? 0 : 1);
  }
  ASSERT_EQ(take->counters.size(), 1u);
  bool layoutCounted = false;
  for (const sim::SessionCounter& c : take->counters[0].values)
    if (c.name == "layoutChanges") layoutCounted = c.value == 1;
  EXPECT_TRUE(layoutCounted);
}

// Issue 14 item 7: a device that cannot be opened is a problem the HUD shows (state and error, in the problem
// colour), and a run that never received a sample ends with the I/O exit code.
TEST(LiveDevice, MissingDeviceIsAProblemAndFailsTheRun) {
  const Character& character = test::exampleCharacter("simple_biped");
  SkeletonCache skeleton(character);
  LivePoseSource source(drivers::serialOpener("/dev/ttyNOPE-imps-test"), {}, character, "serial:/dev/ttyNOPE-imps-test",
                        std::nullopt, {});
  HudInfo info;
  ASSERT_TRUE(eventually([&] {
    int64_t arrival = 0;
    source.poll(skeleton, &arrival);
    source.describe(info);
    return info.problem && !info.lastError.empty();
  })) << info.state;
  EXPECT_NE(info.lastError.find("ttyNOPE-imps-test"), std::string::npos) << info.lastError;
  EXPECT_LT(info.sampleAgeMs, 0.0);  // no sample: no "sample age 0.0 ms" as if connected
  source.finish();
  EXPECT_EQ(source.exitCode(), kExitIoError);
}

TEST(LiveCalibration, KeyNeedsARigMapAndSomewhereToSave) {
  TempDir dir;
  const fs::path source = writeSourceSession(dir.path, false, 50);
  Rig rig("sim:" + source.string() + "?rate=1000", std::nullopt, {});
  rig.run(3000, [&] { return rig.skeleton.generation() > 1; });
  EXPECT_NE(rig.source->recalibrate().find("needs a rig map"), std::string::npos);
}

// The simulator's default motion under the bundled calibration (docs/cli.md's `live --device 'sim:?rate=1000'
// --calibration examples/simple_biped.calibration.json`) is a performance, not a tumble: over whole cycles every
// channel's angle stays inside its joint's limits (no clamping needed), and the waving forearm really moves.
TEST(LiveDefaultMotion, EveryGeneratedAngleIsWithinTheRigMapsLimits) {
  auto spec = drivers::parseDeviceSpec("sim:?rate=1000");
  ASSERT_TRUE(spec) << spec.error().str();
  auto options = sim::armatureOptionsFromSpec(*spec);
  ASSERT_TRUE(options) << options.error().str();
  const sim::SimulatedArmature armature(*options);
  auto cal = calibration::Calibration::readFile(kCalibration, &test::exampleCharacter("simple_biped"),
                                                &options->info);
  ASSERT_TRUE(cal) << cal.error().str();
  const calibration::RigMap& map = cal->rigMap();
  std::vector<double> lowest(map.channels.size(), 1e9), highest(map.channels.size(), -1e9);
  const int64_t periodNs = int64_t(options->motionPeriodS * 1e9);
  for (int64_t t = 0; t <= 3 * periodNs; t += 5'000'000) {
    const drivers::Sample s = armature.poseAt(uint64_t(t / 1'000'000), t);
    for (size_t i = 0; i < map.channels.size(); ++i) {
      const double angle = cal->rawAngle(i, double(s.counts[size_t(map.channels[i].channel)]));
      EXPECT_GE(angle, map.channels[i].minAngle) << map.channels[i].joint << " at " << t << " ns";
      EXPECT_LE(angle, map.channels[i].maxAngle) << map.channels[i].joint << " at " << t << " ns";
      lowest[i] = std::min(lowest[i], angle);
      highest[i] = std::max(highest[i], angle);
    }
  }
  // Every channel moves (a performance, not a statue), the waving forearm by more than 45 degrees.
  for (size_t i = 0; i < map.channels.size(); ++i) {
    EXPECT_GT(highest[i] - lowest[i], 0.5 * std::numbers::pi / 180) << map.channels[i].joint;
    if (map.channels[i].joint == "R_Forearm") {
      EXPECT_GT(highest[i] - lowest[i], std::numbers::pi / 4);
    }
  }
}

// motion=still holds the calibration pose: the bundled calibration maps it to zero angles on every channel.
TEST(LiveDefaultMotion, StillMotionIsTheBundledCalibrationsPose) {
  auto spec = drivers::parseDeviceSpec("sim:?motion=still");
  ASSERT_TRUE(spec) << spec.error().str();
  auto options = sim::armatureOptionsFromSpec(*spec);
  ASSERT_TRUE(options) << options.error().str();
  const sim::SimulatedArmature armature(*options);
  auto cal = calibration::Calibration::readFile(kCalibration, &test::exampleCharacter("simple_biped"),
                                                &options->info);
  ASSERT_TRUE(cal) << cal.error().str();
  for (int64_t t : {int64_t(0), int64_t(700'000'000), int64_t(5'000'000'000)}) {
    const drivers::Sample s = armature.poseAt(0, t);
    for (size_t i = 0; i < cal->rigMap().channels.size(); ++i)
      EXPECT_EQ(cal->rawAngle(i, double(s.counts[size_t(cal->rigMap().channels[i].channel)])), 0.0);
  }
}

// Only the live source offers keys o and k in the HUD.
TEST(LiveRecording, TheLiveSourceHandlesTheDeviceKeys) {
  Rig rig("sim:?rate=1000", exampleCalibration(), {});
  EXPECT_TRUE(rig.source->handlesDeviceKeys());
}

}  // namespace
}  // namespace imps::app
