// SPDX-License-Identifier: MIT
// Counts → angles → joint rotations: offsets, signs, gains, limits, wrap-around, composition order, rest rotation,
// and the Calibrator's deadband, smoothing and hold-last-good.
#include "calibration/calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "imps/scene_reader.h"

namespace imps::calibration {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kGain12 = 4096 / (2 * kPi);  // counts per radian, one turn of a 12-bit encoder

ChannelMap channel(int index, std::string joint, Axis axis, double offset, int sign = 1, double gain = kGain12) {
  ChannelMap c;
  c.channel = index;
  c.joint = std::move(joint);
  c.axis = axis;
  c.sign = sign;
  c.gain = gain;
  c.offset = offset;
  return c;
}

// A map with the given channels, joints grouped in first-appearance order with `order` for multi-axis joints.
RigMap makeMap(std::vector<ChannelMap> channels, std::string order = "") {
  RigMap m;
  m.bits = 12;
  m.channels = std::move(channels);
  for (size_t i = 0; i < m.channels.size(); ++i) {
    JointMap* jm = nullptr;
    for (JointMap& j : m.joints)
      if (j.joint == m.channels[i].joint) jm = &j;
    if (!jm) {
      m.joints.push_back({m.channels[i].joint, "", {}, {}});
      jm = &m.joints.back();
    }
    jm->mappings.push_back(i);
    jm->order += static_cast<char>('X' + static_cast<int>(m.channels[i].axis));
  }
  if (!order.empty()) m.joints[0].order = order;
  return m;
}

Calibration make(RigMap m) {
  auto c = Calibration::create(std::move(m));
  EXPECT_TRUE(c.has_value()) << (c ? "" : c.error().str());
  return std::move(*c);
}

drivers::Sample sample(std::vector<uint32_t> counts, int64_t timeNs = 0) {
  drivers::Sample s;
  s.channelCount = static_cast<uint16_t>(counts.size());
  for (size_t i = 0; i < counts.size(); ++i) s.counts[i] = counts[i];
  s.deviceTimeNs = timeNs;
  s.arrivalTimeNs = timeNs;
  return s;
}

double angleOf(const glm::quat& q, Axis axis) {
  // For a rotation about one known axis: signed angle.
  const glm::dquat d(q);
  const double s = axis == Axis::X ? d.x : axis == Axis::Y ? d.y : d.z;
  return 2 * std::atan2(s, d.w);
}

TEST(CountDelta, WrapsToTheShortestSignedDifference) {
  EXPECT_DOUBLE_EQ(countDelta(10, 4090, 4096, EncoderKind::Absolute), 16);
  EXPECT_DOUBLE_EQ(countDelta(4090, 10, 4096, EncoderKind::Absolute), -16);
  EXPECT_DOUBLE_EQ(countDelta(2048 + 2047, 2048, 4096, EncoderKind::Absolute), 2047);
  EXPECT_DOUBLE_EQ(countDelta(2048 + 2048, 2048, 4096, EncoderKind::Absolute), -2048);  // half a turn: [-T/2, T/2)
  EXPECT_DOUBLE_EQ(countDelta(0, 2048, 4096, EncoderKind::Absolute), -2048);
  EXPECT_DOUBLE_EQ(countDelta(10, 4090, 4096, EncoderKind::Linear), -4080);
}

TEST(Calibration, OffsetSignAndGain) {
  auto cal = make(makeMap({channel(0, "A", Axis::X, 1000), channel(1, "B", Axis::X, 1000, -1),
                           channel(2, "C", Axis::X, 1000, 1, 100.0)}));
  EXPECT_DOUBLE_EQ(cal.angle(0, 1000), 0);
  EXPECT_NEAR(cal.angle(0, 1000 + 1024), kPi / 2, 1e-12);  // a quarter turn
  EXPECT_NEAR(cal.angle(1, 1000 + 1024), -kPi / 2, 1e-12);  // reversed
  EXPECT_NEAR(cal.angle(2, 1000 - 50), -0.5, 1e-12);         // 100 counts per radian
}

TEST(Calibration, AbsoluteEncodersWrapAcrossZero) {
  // Calibrated with the encoder near the top of its range: small motions either way cross 0 / 4096.
  auto cal = make(makeMap({channel(0, "A", Axis::X, 4090)}));
  EXPECT_NEAR(cal.angle(0, 5), 11 / kGain12, 1e-12);
  EXPECT_NEAR(cal.angle(0, 4080), -10 / kGain12, 1e-12);
  EXPECT_NEAR(cal.angle(0, 0), 6 / kGain12, 1e-12);
}

TEST(Calibration, LinearSensorsDoNotWrap) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 4090, 1, 1000)});
  m.channels[0].encoder = EncoderKind::Linear;
  auto cal = make(m);
  EXPECT_NEAR(cal.angle(0, 90), -4.0, 1e-12);
}

TEST(Calibration, LimitsClamp) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 2048)});
  m.channels[0].minAngle = -0.5;
  m.channels[0].maxAngle = 1.0;
  auto cal = make(m);
  EXPECT_DOUBLE_EQ(cal.angle(0, 4000), 1.0);
  EXPECT_DOUBLE_EQ(cal.angle(0, 100), -0.5);
  EXPECT_NEAR(cal.angle(0, 2048 + 300), 300 / kGain12, 1e-12);
  EXPECT_GT(cal.rawAngle(0, 4000), 1.0);
}

TEST(Calibration, ComposesAxesInTheDeclaredOrder) {
  // Joint A: z then x (R = Rz * Rx); 90 degrees each.
  auto zx = make(makeMap({channel(0, "A", Axis::X, 0), channel(1, "A", Axis::Z, 0)}, "ZX"));
  auto xz = make(makeMap({channel(0, "A", Axis::X, 0), channel(1, "A", Axis::Z, 0)}, "XZ"));
  const auto s = sample({1024, 1024});
  const glm::quat a = zx.apply(s)[0].rotation, b = xz.apply(s)[0].rotation;
  const glm::dquat rz = glm::angleAxis(kPi / 2, glm::dvec3(0, 0, 1)), rx = glm::angleAxis(kPi / 2, glm::dvec3(1, 0, 0));
  const glm::vec3 y(0, 1, 0);
  const glm::vec3 expectA = glm::vec3(rz * rx * glm::dvec3(y)), expectB = glm::vec3(rx * rz * glm::dvec3(y));
  EXPECT_NEAR(glm::length(a * y - expectA), 0, 1e-5);
  EXPECT_NEAR(glm::length(b * y - expectB), 0, 1e-5);
  EXPECT_GT(glm::length(expectA - expectB), 0.5f);  // the order matters for this pair
}

TEST(Calibration, PoseIsRestRotationTimesCalibratedRotation) {
  // A joint whose rest rotation in the file is 90 degrees about z.
  const char* text =
      "#VRML V2.0 utf8\n"
      "Tesselator3MP { sceneGraph DEF Arm RigidTransform { rotation 0 0 1 1.5707963267948966\n"
      "  children [ LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.1 radius2 0.1 } ] } }\n";
  auto scene = readScene(text, "arm.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  auto character = Character::fromScene(*scene);
  ASSERT_TRUE(character.has_value()) << character.error().str();
  auto cal = Calibration::create(makeMap({channel(0, "Arm", Axis::X, 2048)}), &*character);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  const auto pose = cal->apply(sample({2048 + 1024}));  // 90 degrees about the joint's own x
  ASSERT_EQ(pose.size(), 1u);
  EXPECT_EQ(pose[0].joint, "Arm");
  EXPECT_FALSE(pose[0].hasTranslation);
  // The calibrated rotation acts in the joint's frame, after (to the right of) the rest rotation.
  const glm::dquat rest = glm::angleAxis(kPi / 2, glm::dvec3(0, 0, 1));
  const glm::dquat expected = rest * glm::angleAxis(kPi / 2, glm::dvec3(1, 0, 0));
  for (const glm::dvec3 v : {glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)})
    EXPECT_NEAR(glm::length(glm::dvec3(pose[0].rotation * glm::vec3(v)) - expected * v), 0, 1e-6);
  // The calibration pose reproduces the file's rest rotation exactly.
  const auto restPose = cal->apply(sample({2048}));
  EXPECT_NEAR(glm::length(glm::dvec3(restPose[0].rotation * glm::vec3(0, 1, 0)) - rest * glm::dvec3(0, 1, 0)), 0, 1e-6);
}

// A translation channel moves the joint from its rest translation (the file's) along the parent's axis, in metres,
// clamped to its limits; the rotation channels of the same joint are unaffected by it.
TEST(Calibration, TranslationChannelsMoveTheJointFromItsRestTranslation) {
  const char* text =
      "#VRML V2.0 utf8\n"
      "Tesselator3MP { sceneGraph DEF Arm RigidTransform { translation 0.5 1 0 rotation 0 0 1 1.5707963267948966\n"
      "  children [ LineSeg { point1 0 0 0 point2 1 0 0 radius1 0.1 radius2 0.1 } ] } }\n";
  auto scene = readScene(text, "arm.wrl");
  ASSERT_TRUE(scene.has_value()) << scene.error().str();
  auto character = Character::fromScene(*scene);
  ASSERT_TRUE(character.has_value()) << character.error().str();
  ChannelMap ty = channel(1, "Arm", Axis::Y, 1000, -1, 1000.0);  // 1 mm per count, reversed
  ty.translation = true;
  ty.encoder = EncoderKind::Linear;
  ty.maxAngle = 0.25;
  RigMap map = makeMap({channel(0, "Arm", Axis::X, 2048), ty});
  map.joints[0].order = "X";
  auto cal = Calibration::create(map, &*character);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  const auto pose = cal->apply(sample({2048 + 1024, 1000 - 150}));  // 90 degrees about x; 150 counts the other way
  ASSERT_EQ(pose.size(), 1u);
  EXPECT_TRUE(pose[0].hasTranslation);
  EXPECT_NEAR(pose[0].translation.x, 0.5f, 1e-6f);
  EXPECT_NEAR(pose[0].translation.y, 1.0f + 0.150f, 1e-6f);
  EXPECT_NEAR(pose[0].translation.z, 0.0f, 1e-6f);
  const glm::dquat expected =
      glm::angleAxis(kPi / 2, glm::dvec3(0, 0, 1)) * glm::angleAxis(kPi / 2, glm::dvec3(1, 0, 0));
  EXPECT_NEAR(glm::length(glm::dvec3(pose[0].rotation * glm::vec3(0, 1, 0)) - expected * glm::dvec3(0, 1, 0)), 0, 1e-6);
  // Limits are metres.
  EXPECT_NEAR(cal->apply(sample({2048, 1000 - 900}))[0].translation.y, 1.25f, 1e-6f);
  // Linear: no wrap-around even far from the offset.
  EXPECT_NEAR(cal->apply(sample({2048, 1000 + 3000}))[0].translation.y, 1.0f - 3.0f, 1e-5f);
  // The calibration pose is the file's pose.
  EXPECT_NEAR(glm::length(cal->apply(sample({2048, 1000}))[0].translation - glm::vec3(0.5f, 1, 0)), 0, 1e-6f);
  // The stateful Calibrator carries translations too.
  Calibrator calibrator(*cal);
  EXPECT_NEAR(calibrator.update(sample({2048, 1000 - 40}))[0].translation.y, 1.04f, 1e-6f);
}

// Channels of a second device take their readings from that device's samples only.
TEST(Calibrator, EachDeviceDrivesItsOwnChannels) {
  ChannelMap second = channel(0, "B", Axis::X, 2048);
  second.device = 1;
  Calibrator c(make(makeMap({channel(0, "A", Axis::X, 2048), second})));
  c.update(0, sample({2048 + 1024}));
  EXPECT_NEAR(c.angles()[0], kPi / 2, 1e-9);
  EXPECT_NEAR(c.angles()[1], 0.0, 1e-12) << "device 0's channel 0 is not device 1's";
  c.update(1, sample({2048 - 1024}));
  EXPECT_NEAR(c.angles()[0], kPi / 2, 1e-9) << "held";
  EXPECT_NEAR(c.angles()[1], -kPi / 2, 1e-9);
  // The stateless conversion reads device 0 only.
  auto pose = c.calibration().apply(sample({2048 + 1024}));
  EXPECT_NEAR(glm::angle(pose[1].rotation), 0.0f, 1e-6f);
}

TEST(Calibration, FlaggedChannelsReadAsTheCalibrationPose) {
  auto cal = make(makeMap({channel(0, "A", Axis::X, 2048), channel(1, "B", Axis::X, 2048)}));
  auto s = sample({3000, 3000});
  s.flags[1] = drivers::ChannelFlag::NotConnected;
  const auto pose = cal.apply(s);
  EXPECT_GT(std::abs(angleOf(pose[0].rotation, Axis::X)), 0.1);
  EXPECT_NEAR(angleOf(pose[1].rotation, Axis::X), 0, 1e-9);
}

TEST(Calibration, RefusesChannelsWithoutOffsets) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 0)});
  m.channels[0].offset.reset();
  m.channels[0].loc = {"rig.json", 3, 7};
  auto c = Calibration::create(m);
  ASSERT_FALSE(c.has_value());
  EXPECT_EQ(c.error().str(),
            "rig.json:3:7: error: missing field 'offset' for channel 0: a calibration needs every channel's offset "
            "(run `puppeteer calibrate`)\n");
}

TEST(Calibrator, HoldsThePreviousAngleForFlaggedChannels) {
  Calibrator c(make(makeMap({channel(0, "A", Axis::X, 2048)})));
  c.update(sample({2048 + 100}, 1'000'000));
  const double before = c.angles()[0];
  EXPECT_NEAR(before, 100 / kGain12, 1e-12);
  for (auto flag : {drivers::ChannelFlag::NotConnected, drivers::ChannelFlag::Outlier}) {
    auto s = sample({10}, 2'000'000);
    s.flags[0] = flag;
    c.update(s);
    EXPECT_DOUBLE_EQ(c.angles()[0], before);
  }
  auto shortSample = sample({}, 3'000'000);  // the channel is missing altogether
  c.update(shortSample);
  EXPECT_DOUBLE_EQ(c.angles()[0], before);
  c.update(sample({2048 + 200}, 4'000'000));
  EXPECT_NEAR(c.angles()[0], 200 / kGain12, 1e-12);
}

TEST(Calibrator, DeadbandIgnoresJitter) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 2048)});
  m.channels[0].deadband = 2.5 / kGain12;  // 2.5 counts
  Calibrator c(make(m));
  c.update(sample({2048}, 0));
  for (uint32_t jitter : {2049u, 2046u, 2050u, 2048u, 2046u}) {
    c.update(sample({jitter}, 1));
    EXPECT_DOUBLE_EQ(c.angles()[0], 0) << jitter;
  }
  c.update(sample({2051}, 2));  // 3 counts: beyond the deadband, taken whole
  EXPECT_NEAR(c.angles()[0], 3 / kGain12, 1e-12);
  c.update(sample({2049}, 3));  // back 2 counts: within the deadband of the new value
  EXPECT_NEAR(c.angles()[0], 3 / kGain12, 1e-12);
}

TEST(Calibrator, OnePoleSmoothingUsesSampleTimes) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 2048)});
  m.channels[0].smoothingMs = 10;
  Calibrator c(make(m));
  c.update(sample({2048}, 0));
  const double step = 1000 / kGain12;
  c.update(sample({3048}, 10'000'000));  // one time constant later
  EXPECT_NEAR(c.angles()[0], step * (1 - std::exp(-1.0)), 1e-9);
  c.update(sample({3048}, 30'000'000));  // two more
  EXPECT_NEAR(c.angles()[0], step * (1 - std::exp(-3.0)), 1e-9);
  c.reset();
  c.update(sample({3048}, 40'000'000));  // the first reading after a reset is taken as is
  EXPECT_NEAR(c.angles()[0], step, 1e-12);
}

TEST(Calibrator, ClampsBeforeFiltering) {
  RigMap m = makeMap({channel(0, "A", Axis::X, 2048)});
  m.channels[0].maxAngle = 0.25;
  Calibrator c(make(m));
  const auto& pose = c.update(sample({4000}, 0));
  EXPECT_DOUBLE_EQ(c.angles()[0], 0.25);
  EXPECT_NEAR(angleOf(pose[0].rotation, Axis::X), 0.25, 1e-6);
}

}  // namespace
}  // namespace imps::calibration
