// SPDX-License-Identifier: MIT
// Offsets from a calibration-pose window (circular mean, noise rejection), the check pose (reversed / mis-scaled
// channels), calibration files and session blobs, and the end-to-end path: known angles → counts → calibrate →
// apply → the same angles.
#include "examples.h"
#include "calibration/offset_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "imps/scene_reader.h"

namespace imps::calibration {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
constexpr double kTurn = 4096;
constexpr double kGain12 = kTurn / (2 * kPi);

const Character& biped() { return test::exampleCharacter("simple_biped"); }

drivers::DeviceInfo device32() {
  drivers::DeviceInfo d;
  d.name = "IMPS Simulated Monkey";
  d.channelCount = 32;
  d.bitsPerChannel = 12;
  for (int i = 0; i < 32; ++i) d.channelNames.push_back("enc" + std::to_string(i));
  return d;
}

RigMap exampleRig() {
  const drivers::DeviceInfo dev = device32();
  auto rig = readRigMapFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.rig.json", {&biped(), &dev});
  EXPECT_TRUE(rig.has_value()) << rig.error().str();
  return *rig;
}

// A one-channel map of a 12-bit absolute encoder on joint A's x axis.
RigMap oneChannelMap(double gain = kGain12) {
  RigMap m;
  m.bits = 12;
  ChannelMap c;
  c.channel = 0;
  c.joint = "A";
  c.axis = Axis::X;
  c.gain = gain;
  m.channels.push_back(c);
  m.joints.push_back({"A", "X", {0}, {}});
  return m;
}

drivers::Sample sampleOf(const std::vector<uint32_t>& counts) {
  drivers::Sample s;
  s.channelCount = static_cast<uint16_t>(counts.size());
  for (size_t i = 0; i < counts.size(); ++i) s.counts[i] = counts[i];
  return s;
}

// The physical armature of the end-to-end test: each channel reads mount + sign * angle * gain (mod 2^12), rounded
// to whole counts, with every channel's mounting offset different and some near the wrap.
struct Armature {
  std::vector<double> mount;  // counts at the T-pose
  std::vector<int> sign;
  uint32_t count(size_t ch, double angle) const {
    double c = std::round(mount[ch] + sign[ch] * angle * kGain12);
    c = std::fmod(c, kTurn);
    if (c < 0) c += kTurn;
    return static_cast<uint32_t>(c);
  }
};

TEST(AverageWindow, ArithmeticMeanAndSpread) {
  std::vector<drivers::Sample> w;
  for (uint32_t c : {1000u, 1002u, 1000u, 1002u, 1001u}) w.push_back(sampleOf({c}));
  const WindowAverage a = averageWindow(oneChannelMap(), w);
  ASSERT_TRUE(a.ok());
  EXPECT_NEAR(a.channels[0].mean, 1001, 1e-9);
  EXPECT_NEAR(a.channels[0].stdDev, std::sqrt(0.8), 1e-9);
  EXPECT_EQ(a.channels[0].samples, 5u);
}

TEST(AverageWindow, CircularMeanAcrossTheWrap) {
  // Readings straddling 0 / 4096: an arithmetic mean would say ~2048 (the opposite side of the turn).
  std::vector<drivers::Sample> w;
  for (uint32_t c : {4094u, 4095u, 0u, 1u, 2u, 4093u}) w.push_back(sampleOf({c}));
  const WindowAverage a = averageWindow(oneChannelMap(), w);
  ASSERT_TRUE(a.ok()) << a.problems[0];
  EXPECT_NEAR(a.channels[0].mean, 4095.5, 1e-9);
  EXPECT_LT(a.channels[0].stdDev, 3);
  // A mean a hair below 0 must come out as a count in [0, 4096), never as 4096.
  std::vector<drivers::Sample> w3;
  for (uint32_t c : {4095u, 1u, 4095u, 1u}) w3.push_back(sampleOf({c}));
  const double m3 = averageWindow(oneChannelMap(), w3).channels[0].mean;
  EXPECT_GE(m3, 0);
  EXPECT_LT(m3, 4096);
  EXPECT_NEAR(countDelta(m3, 0, kTurn, EncoderKind::Absolute), 0, 1e-9);
  std::vector<drivers::Sample> w2;
  for (uint32_t c : {4095u, 1u, 2u, 0u}) w2.push_back(sampleOf({c}));
  EXPECT_NEAR(averageWindow(oneChannelMap(), w2).channels[0].mean, 0.5, 1e-9);
}

TEST(AverageWindow, RejectsANoisyWindowNamingTheChannel) {
  RigMap m = oneChannelMap();
  m.channels[0].joint = "L_Forearm";
  m.channels[0].axis = Axis::Y;
  drivers::DeviceInfo dev;
  dev.channelCount = 1;
  dev.channelNames = {"L_elbow"};
  std::vector<drivers::Sample> w;
  for (uint32_t c : {1000u, 1020u, 990u, 1015u, 985u}) w.push_back(sampleOf({c}));  // ~14 counts = 1.2 degrees
  WindowOptions o;
  o.device = &dev;
  const WindowAverage a = averageWindow(m, w, o);
  ASSERT_EQ(a.problems.size(), 1u);
  EXPECT_EQ(a.problems[0],
            "channel 0 'L_elbow' (L_Forearm y) is too noisy: standard deviation 1.20 deg (13.6 counts) > 0.50 deg; "
            "hold the armature still, or check the encoder");
  o.maxStdDev = 2 * kDeg;
  EXPECT_TRUE(averageWindow(m, w, o).ok());
  auto offsets = calibrateOffsets(m, w, WindowOptions{});
  ASSERT_FALSE(offsets.has_value());
  ASSERT_EQ(offsets.error().errorCount(), 1);
  EXPECT_EQ(offsets.error().all().front().message, averageWindow(m, w, WindowOptions{}).problems.front());
}

TEST(AverageWindow, SkipsFlaggedReadingsAndRejectsADeadChannel) {
  std::vector<drivers::Sample> w;
  for (int i = 0; i < 10; ++i) {
    auto s = sampleOf({100, 3000});
    s.flags[1] = drivers::ChannelFlag::NotConnected;
    if (i == 3) {
      s.counts[0] = 3500;  // a glitch the decoder flagged
      s.flags[0] = drivers::ChannelFlag::Outlier;
    }
    w.push_back(s);
  }
  RigMap m = oneChannelMap();
  ChannelMap second = m.channels[0];
  second.channel = 1;
  second.joint = "B";
  m.channels.push_back(second);
  m.joints.push_back({"B", "X", {1}, {}});
  const WindowAverage a = averageWindow(m, w);
  EXPECT_NEAR(a.channels[0].mean, 100, 1e-9);
  EXPECT_EQ(a.channels[0].samples, 9u);
  ASSERT_EQ(a.problems.size(), 1u);
  EXPECT_EQ(a.problems[0], "channel 1 (B x): only 0 valid readings in the window (need 5); is it connected?");
}

TEST(CalibrateOffsets, OffsetsAreTheWindowMeans) {
  std::vector<drivers::Sample> w;
  for (int i = 0; i < 20; ++i) w.push_back(sampleOf({static_cast<uint32_t>(4095 + (i % 3)) % 4096}));
  auto m = calibrateOffsets(oneChannelMap(), w);
  ASSERT_TRUE(m.has_value());
  ASSERT_TRUE(m->channels[0].offset.has_value());
  const double off = *m->channels[0].offset;
  // Readings 4095, 0, 1 repeating (7×4095, 7×0, 6×1): the mean is just below 0, across the wrap.
  EXPECT_NEAR(countDelta(off, 0, kTurn, EncoderKind::Absolute), (-7.0 + 6.0) / 20.0, 1e-9);
}

TEST(CheckPose, FindsReversedAndMisScaledChannels) {
  // Four channels driving the elbows, knees; calibrated at mid-scale.
  RigMap m;
  m.bits = 12;
  const char* joints[] = {"L_Forearm", "R_Forearm", "L_Calf", "R_Calf"};
  const Axis axes[] = {Axis::Y, Axis::Y, Axis::X, Axis::X};
  for (int i = 0; i < 4; ++i) {
    ChannelMap c;
    c.channel = i;
    c.joint = joints[i];
    c.axis = axes[i];
    c.gain = kGain12;
    c.offset = 2048;
    m.channels.push_back(c);
    m.joints.push_back({joints[i], axes[i] == Axis::X ? "X" : "Y", {static_cast<size_t>(i)}, {}});
  }
  auto cal = Calibration::create(m, &biped());
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  auto targets = parseCheckPose(R"({"version": 1, "pose": "elbows and knees at 90",
    "joints": {"L_Forearm": {"y_deg": -90}, "R_Forearm": {"y_deg": 90}, "L_Calf": {"x": 1.5707963267948966},
               "R_Calf": {"x_deg": 90}, "Head": {"y_deg": 30}, "Neck": {"x_deg": 2}}})",
                                "pose.json", &biped());
  ASSERT_TRUE(targets.has_value()) << targets.error().str();
  ASSERT_EQ(targets->size(), 6u);
  // The armature: channel 0 right; channel 1 mounted reversed; channel 2 reads 30% short; channel 3 within 10%.
  const double q = 1024;  // 90 degrees of counts
  std::vector<drivers::Sample> w(8, sampleOf({static_cast<uint32_t>(2048 - q), static_cast<uint32_t>(2048 - q),
                                               static_cast<uint32_t>(2048 + 0.75 * q),
                                               static_cast<uint32_t>(2048 + 1.1 * q)}));
  const WindowAverage avg = averageWindow(cal->rigMap(), w);
  ASSERT_TRUE(avg.ok());
  const PoseCheck check = checkPose(*cal, avg, *targets);
  ASSERT_EQ(check.channels.size(), 4u);
  EXPECT_FALSE(check.channels[0].reversed || check.channels[0].misScaled);
  EXPECT_TRUE(check.channels[1].reversed);
  EXPECT_FALSE(check.channels[1].misScaled);
  EXPECT_FALSE(check.channels[2].reversed);
  EXPECT_TRUE(check.channels[2].misScaled);
  EXPECT_NEAR(check.channels[2].suggestedGain, 0.75 * kGain12, 1e-9);
  EXPECT_FALSE(check.channels[3].reversed || check.channels[3].misScaled);
  ASSERT_EQ(check.problems.size(), 2u);
  EXPECT_EQ(check.problems[0],
            "channel 1 (R_Forearm y) reads -90.0 deg for a target of 90.0 deg: looks reversed; set \"sign\": -1");
  EXPECT_EQ(check.problems[1],
            "channel 2 (L_Calf x) reads 67.5 deg for a target of 90.0 deg: looks mis-scaled (off by -25%); set "
            "\"gain\": 488.924");
  ASSERT_EQ(check.warnings.size(), 2u);
  EXPECT_EQ(check.warnings[0], "no channel drives Head y; its target is ignored");
  EXPECT_EQ(check.warnings[1], "no channel drives Neck x; its target is ignored");
  const PoseTarget small[] = {{"L_Forearm", Axis::Y, 2 * kDeg, {}}};
  const PoseCheck smallCheck = checkPose(*cal, avg, small);
  EXPECT_TRUE(smallCheck.channels.empty());
  ASSERT_EQ(smallCheck.warnings.size(), 1u);
  EXPECT_EQ(smallCheck.warnings[0], "L_Forearm y: target 2.0 deg is too small to check (need 10.0 deg or more)");
}

TEST(CheckPose, FileErrors) {
  auto r = parseCheckPose("{\"version\": 1,\n \"joints\": {\"L_Forarm\": {\"y_dg\": 90}}}", "pose.json", &biped());
  ASSERT_FALSE(r.has_value());
  EXPECT_EQ(r.error().str(),
            "pose.json:2:13: error: unknown joint 'L_Forarm'; did you mean 'L_Forearm'?\n"
            "pose.json:2:26: error: unknown field 'y_dg' in the targets of joint 'L_Forarm'; did you mean 'y_deg'?\n");
}

TEST(CalibrationFile, SaveAndLoadRoundTrip) {
  RigMap rig = exampleRig();
  for (size_t i = 0; i < rig.channels.size(); ++i) rig.channels[i].offset = 100.25 + 97.0 * static_cast<double>(i);
  rig.info = R"({"window_ms":500})";
  const drivers::DeviceInfo dev = device32();
  auto cal = Calibration::create(rig, &biped(), &dev);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  const auto dir = std::filesystem::temp_directory_path() / ("imps_cal_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "biped.calibration.json";
  {
    std::ofstream old(path);
    old << "an older calibration";
  }
  ASSERT_TRUE(cal->save(path).has_value());
  // Replaced whole, and no temporary file is left behind.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir), std::filesystem::directory_iterator()), 1);
  auto back = Calibration::readFile(path, &biped(), &dev);
  ASSERT_TRUE(back.has_value()) << back.error().str();
  EXPECT_EQ(back->toJson(), cal->toJson());
  for (size_t i = 0; i < rig.channels.size(); ++i)
    EXPECT_EQ(back->rigMap().channels[i].offset, rig.channels[i].offset) << i;
  // Same poses from the same sample.
  drivers::Sample s = sampleOf(std::vector<uint32_t>(32, 1234));
  const auto p1 = cal->apply(s), p2 = back->apply(s);
  ASSERT_EQ(p1.size(), p2.size());
  for (size_t i = 0; i < p1.size(); ++i) EXPECT_EQ(p1[i].rotation, p2[i].rotation) << p1[i].joint;
  // A save into a directory that does not exist fails and says where.
  auto bad = cal->save(dir / "missing" / "x.json");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().path, (dir / "missing" / "x.json").string());
  EXPECT_EQ(bad.error().message.rfind("cannot save '" + bad.error().path + "': creating a temporary file: ", 0), 0u)
      << bad.error().message;
  std::filesystem::remove_all(dir);
}

TEST(CalibrationFile, SessionBlobRoundTrip) {
  // The blob stored with SessionWriter::appendCalibration is the calibration file's text.
  RigMap rig = exampleRig();
  for (size_t i = 0; i < rig.channels.size(); ++i) rig.channels[i].offset = static_cast<double>((i * 331) % 4096);
  auto cal = Calibration::create(rig, &biped());
  ASSERT_TRUE(cal.has_value());
  const std::string blob = cal->toJson();
  auto back = Calibration::parse(blob, "session calibration 0", &biped());
  ASSERT_TRUE(back.has_value()) << back.error().str();
  EXPECT_EQ(back->toJson(), blob);
  auto newer = Calibration::parse(R"({"version": 7, "bits": 12, "joints": []})", "session calibration 1");
  ASSERT_FALSE(newer.has_value());
  EXPECT_EQ(newer.error().str(),
            "session calibration 1:1:13: error: file format version 7 is newer than this program reads (1); update "
            "puppeteer\n");
}

TEST(EndToEnd, KnownAnglesSurviveCalibrateAndApply) {
  const RigMap rig = exampleRig();
  const size_t n = rig.channels.size();
  ASSERT_EQ(n, 32u);
  // An armature whose encoders were mounted anywhere on the turn (several within a few counts of the wrap), some
  // reversed (the rig map says so), with ±1 count of noise in the T-pose window.
  Armature arm;
  std::mt19937 rng(7);
  for (size_t i = 0; i < n; ++i) {
    arm.mount.push_back(i % 4 == 0 ? std::fmod(4096.0 - 2 + static_cast<double>(i % 5), kTurn)
                                   : static_cast<double>((i * 977 + 13) % 4096));
    arm.sign.push_back(i % 3 == 0 ? -1 : 1);
  }
  RigMap map = rig;
  for (size_t i = 0; i < n; ++i) {
    map.channels[i].sign = arm.sign[i];
  }
  std::vector<drivers::Sample> window;
  std::uniform_int_distribution<int> noise(-1, 1);
  for (int k = 0; k < 50; ++k) {
    drivers::Sample s;
    s.channelCount = 32;
    for (size_t i = 0; i < n; ++i)
      s.counts[i] = arm.count(i, static_cast<double>(noise(rng)) / kGain12);
    window.push_back(s);
  }
  const drivers::DeviceInfo dev = device32();
  WindowOptions wo;
  wo.device = &dev;
  auto calibrated = calibrateOffsets(map, window, wo);
  ASSERT_TRUE(calibrated.has_value()) << calibrated.error().str();
  auto cal = Calibration::create(*calibrated, &biped(), &dev);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();

  // Known joint angles within each channel's limits.
  std::vector<double> known(n);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) {
    const ChannelMap& c = map.channels[i];
    known[i] = c.minAngle + (c.maxAngle - c.minAngle) * u(rng);
  }
  drivers::Sample posed;
  posed.channelCount = 32;
  for (size_t i = 0; i < n; ++i) posed.counts[i] = arm.count(i, known[i]);
  for (size_t i = 0; i < n; ++i) {
    const double recovered = cal->angle(i, posed.counts[i]);
    EXPECT_LE(std::abs(recovered - known[i]) * kGain12, 1.0)
        << rig.channelLabel(i) << " " << map.channels[i].joint << " " << toString(map.channels[i].axis);
  }
  // And through the rotations: each joint's pose equals rest * R(order) of the known angles within a count.
  const auto pose = cal->apply(posed);
  std::vector<JointPose> expected;
  cal->compose(known, expected);
  ASSERT_EQ(pose.size(), expected.size());
  for (size_t j = 0; j < pose.size(); ++j) {
    const float dot = std::abs(glm::dot(pose[j].rotation, expected[j].rotation));
    const double angleBetween = 2 * std::acos(std::min(1.0f, dot));
    EXPECT_LE(angleBetween * kGain12, 2.0) << pose[j].joint;  // a count per axis, up to three axes
    EXPECT_EQ(pose[j].joint, expected[j].joint);
  }
  // The Calibrator (with the example's deadband and smoothing) settles on the same angles.
  Calibrator live(*cal);
  for (int k = 0; k < 200; ++k) {
    posed.deviceTimeNs = k * 1'000'000;
    live.update(posed);
  }
  for (size_t i = 0; i < n; ++i) EXPECT_LE(std::abs(live.angles()[i] - known[i]) * kGain12, 1.0) << i;
}

}  // namespace
}  // namespace imps::calibration
