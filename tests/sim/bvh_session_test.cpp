// SPDX-License-Identifier: MIT
// Tests for sim/bvh_session: the count mapping is exactly invertible, and BVH -> session -> BVH reproduces angles
// within the quantisation step (session -> BVH -> session reproduces counts exactly).
#include "sim/bvh_session.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

namespace imps::sim {
namespace {

namespace fs = std::filesystem;
using C = BvhChannel;

fs::path data(const std::string& name) { return fs::path(IMPS_SOURCE_DIR) / "tests/data/bvh" / name; }

BvhClip read(const std::string& name) {
  auto clip = readBvh(data(name));
  EXPECT_TRUE(clip) << clip.error().str();
  return clip ? *clip : BvhClip{};
}

// Every rotation within half a count (plus float rounding) of the original, positions within half a position step.
void expectSameMotion(const BvhClip& original, const BvhClip& back, int bits, double unitsPerCount, bool modulo360) {
  ASSERT_EQ(back.frames.size(), original.frames.size());
  const double halfStep = 180.0 / std::ldexp(1.0, bits) + 1e-4;
  for (size_t f = 0; f < original.frames.size(); ++f) {
    size_t i = 0;
    for (const auto& joint : original.joints)
      for (BvhChannel c : joint.channels) {
        double error = static_cast<double>(back.frames[f][i]) - original.frames[f][i];
        if (modulo360 && isRotation(c)) error = std::remainder(error, 360.0);
        EXPECT_LE(std::fabs(error), isRotation(c) ? halfStep : unitsPerCount / 2 + 1e-6)
            << "frame " << f << " channel " << i << " (" << joint.name << ":" << bvhChannelName(c) << ") "
            << original.frames[f][i] << " came back as " << back.frames[f][i];
        ++i;
      }
  }
}

TEST(CountMapping, ZeroAtMidScaleAndWrapsAround) {
  EXPECT_EQ(degreesToCounts(0, 16), 32768u);
  EXPECT_EQ(degreesToCounts(-180, 16), 0u);
  EXPECT_EQ(degreesToCounts(180, 16), 0u);  // the same angle as -180
  EXPECT_EQ(degreesToCounts(90, 16), 49152u);
  EXPECT_EQ(degreesToCounts(370, 16), degreesToCounts(10, 16));
  EXPECT_EQ(degreesToCounts(-725, 12), degreesToCounts(-5, 12));
  EXPECT_EQ(degreesToCounts(1e12, 16), degreesToCounts(std::fmod(1e12, 360.0), 16));
  EXPECT_DOUBLE_EQ(countsToDegrees(0, 16), -180.0);
  EXPECT_DOUBLE_EQ(countsToDegrees(65535, 16), 180.0 - 360.0 / 65536);
  EXPECT_DOUBLE_EQ(countsToDegrees(1024, 12), -90.0);
}

TEST(CountMapping, ExactlyInvertibleThroughFloatForEveryCount) {
  for (int bits : {8, 12, 16, 20}) {
    const uint32_t n = 1u << bits;
    const uint32_t stride = bits == 20 ? 7 : 1;
    for (uint32_t c = 0; c < n; c += stride) {
      const float degrees = static_cast<float>(countsToDegrees(c, bits));  // BVH frames hold floats
      ASSERT_EQ(degreesToCounts(degrees, bits), c) << bits << " bits";
    }
  }
}

TEST(BvhToSession, ChannelsTimestampsAndDescription) {
  const BvhClip clip = read("colon_names.bvh");
  auto session = bvhToSession(clip, "colon_names.bvh");
  ASSERT_TRUE(session) << session.error().firstError();
  ASSERT_EQ(session->devices.size(), 1u);
  const DeviceInfo& d = session->devices[0];
  EXPECT_EQ(d.name, "BVH: colon_names.bvh");
  EXPECT_EQ(d.channelCount, 12);
  EXPECT_EQ(d.bitsPerChannel, 16);
  EXPECT_TRUE(d.hasDeviceTimestamp);
  EXPECT_EQ(d.channelNames[0], "mixamorig:Hips:Xposition");
  EXPECT_EQ(d.channelNames[3], "mixamorig:Hips:Zrotation");
  EXPECT_EQ(d.channelNames[11], "mixamorig:LeftArm:Yrotation");
  ASSERT_EQ(session->samples.size(), 2u);
  EXPECT_EQ(session->samples[1].sequence, 1u);
  EXPECT_EQ(session->samples[1].deviceTimeNs, 33'333'300);
  EXPECT_EQ(session->samples[1].arrivalTimeNs, 33'333'300);
  EXPECT_EQ(session->samples[0].counts[3], degreesToCounts(1, 16));
  // Positions up to 99.25: the finest power-of-two step that holds +-99.25 in 16 bits is 2^-8.
  ASSERT_TRUE(session->skeleton);
  EXPECT_EQ(session->skeleton->positionUnitsPerCount, 1.0 / 256);
  EXPECT_EQ(session->samples[0].counts[1], 32768u + 99u * 256 + 64);
  auto hierarchy = readBvhText(session->skeleton->bvh);
  ASSERT_TRUE(hierarchy);
  EXPECT_EQ(hierarchy->joints, clip.joints);
  EXPECT_TRUE(hierarchy->frames.empty());
  // No calibration record: the channel names and the skeleton say how counts become the clip's channels.
  EXPECT_TRUE(session->calibrations.empty());
  EXPECT_EQ(session->devices[0].channelNames[11], "mixamorig:LeftArm:Yrotation");
}

TEST(BvhToSession, RoundTripReproducesEveryQuirkFile) {
  for (const std::string file : {"line_endings.bvh", "channel_orders.bvh", "colon_names.bvh", "end_joint.bvh",
                                 "frames_fewer_than_data.bvh"}) {
    for (int bits : {12, 16, 20}) {
      SCOPED_TRACE(file + " at " + std::to_string(bits) + " bits");
      const BvhClip clip = read(file);
      BvhToSessionOptions options;
      options.bitsPerChannel = bits;
      auto session = bvhToSession(clip, file, options);
      ASSERT_TRUE(session) << session.error().firstError();
      // All the test clips keep angles in [-180, 180), so without unwrapping they come back as they were.
      auto back = sessionToBvh(*session, {.unwrap = false});
      ASSERT_TRUE(back) << back.error().firstError();
      EXPECT_EQ(back->joints, clip.joints);
      EXPECT_DOUBLE_EQ(back->frameTime, clip.frameTime);
      expectSameMotion(clip, *back, bits, session->skeleton->positionUnitsPerCount, false);
      // And the counts survive the other way exactly.
      auto again = bvhToSession(*back, file, options);
      ASSERT_TRUE(again);
      EXPECT_EQ(again->samples, session->samples);
    }
  }
}

TEST(BvhToSession, RoundTripThroughASessionFile) {
  const fs::path dir = fs::temp_directory_path() / ("imps_bvh_session_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const BvhClip clip = read("channel_orders.bvh");
  auto session = bvhToSession(clip, "channel_orders.bvh");
  ASSERT_TRUE(session);
  ASSERT_TRUE(saveSession(dir / "c.session", *session));
  auto loaded = readSession(dir / "c.session");
  ASSERT_TRUE(loaded) << loaded.error().firstError();
  EXPECT_EQ(loaded->samples, session->samples);
  EXPECT_EQ(loaded->skeleton, session->skeleton);
  auto back = sessionToBvh(*loaded);
  ASSERT_TRUE(back);
  ASSERT_TRUE(saveBvh(dir / "c.bvh", *back));
  auto reread = readBvh(dir / "c.bvh");
  ASSERT_TRUE(reread);
  expectSameMotion(clip, *reread, 16, session->skeleton->positionUnitsPerCount, false);
  fs::remove_all(dir);
}

// A skeleton with more channels than one device carries is split across devices and joined again.
TEST(BvhToSession, MoreThan64ChannelsSpanSeveralDevices) {
  BvhClip clip;
  clip.frameTime = 1.0 / 120;
  clip.joints.push_back({"Hips",
                         -1,
                         {0, 0, 0},
                         {C::Xposition, C::Yposition, C::Zposition, C::Zrotation, C::Yrotation, C::Xrotation},
                         false,
                         {}});
  for (int j = 0; j < 40; ++j)
    clip.joints.push_back(
        {"J" + std::to_string(j), j, {0, 1, 0}, {C::Zrotation, C::Xrotation, C::Yrotation}, j == 39, {0, 1, 0}});
  const size_t channels = clip.channelCount();
  ASSERT_EQ(channels, 126u);
  for (int f = 0; f < 50; ++f) {
    std::vector<float> frame(channels);
    for (size_t i = 0; i < channels; ++i)
      frame[i] = static_cast<float>(std::fmod(f * 3.7 + static_cast<double>(i) * 11.3, 340.0) - 170.0);
    clip.frames.push_back(frame);
  }
  auto session = bvhToSession(clip, "big.bvh");
  ASSERT_TRUE(session) << session.error().firstError();
  ASSERT_EQ(session->devices.size(), 2u);
  EXPECT_EQ(session->devices[0].channelCount, 64);
  EXPECT_EQ(session->devices[1].channelCount, 62);
  EXPECT_EQ(session->devices[1].serialNumber, "part 2/2");
  EXPECT_EQ(session->devices[1].channelNames[0], "J19:Xrotation");
  ASSERT_EQ(session->samples.size(), 100u);
  EXPECT_EQ(session->sampleDevice[0], 0);
  EXPECT_EQ(session->sampleDevice[1], 1);
  EXPECT_EQ(session->samples[3].sequence, 1u);
  auto back = sessionToBvh(*session, {.unwrap = false});
  ASSERT_TRUE(back) << back.error().firstError();
  expectSameMotion(clip, *back, 16, session->skeleton->positionUnitsPerCount, false);
}

TEST(SessionToBvh, UnwrapReproducesTracksCrossing180) {
  BvhClip clip;
  clip.frameTime = 0.01;
  clip.joints.push_back({"Arm", -1, {0, 0, 0}, {C::Zrotation, C::Xrotation}, true, {1, 0, 0}});
  for (int f = 0; f < 40; ++f)
    clip.frames.push_back(
        {static_cast<float>(160 + 2.5 * f), static_cast<float>(-150 - 4.25 * f)});  // to 257.5, -315.75
  auto session = bvhToSession(clip, "spin.bvh");
  ASSERT_TRUE(session);
  auto unwrapped = sessionToBvh(*session);
  ASSERT_TRUE(unwrapped);
  expectSameMotion(clip, *unwrapped, 16, 1, false);
  auto wrapped = sessionToBvh(*session, {.unwrap = false});
  ASSERT_TRUE(wrapped);
  expectSameMotion(clip, *wrapped, 16, 1, true);
  EXPECT_NEAR(wrapped->frames[39][0], 257.5 - 360, 0.01);
}

TEST(SessionToBvh, LiveSessionGetsAFlatSkeleton) {
  Session s;
  DeviceInfo d;
  d.name = "IMPS Monkey-4";
  d.channelCount = 5;
  d.bitsPerChannel = 12;
  d.channelNames = {"Elbow:Zrotation", "Elbow:Xrotation", "knee", "wrist twist", "Hip:Yposition"};
  s.devices = {d};
  for (int i = 0; i < 4; ++i) {
    Sample x;
    x.channelCount = 5;
    x.arrivalTimeNs = 1'000'000'000 + i * 20'000'000 + (i == 2 ? 1'000'000 : 0);
    for (size_t k = 0; k < 5; ++k) x.counts[k] = 2048 + static_cast<uint32_t>(i * 100 + static_cast<int>(k));
    if (i == 2) x.flags[2] = drivers::ChannelFlag::NotConnected;  // knee holds its previous reading
    s.samples.push_back(x);
    s.sampleDevice.push_back(0);
  }
  auto clip = sessionToBvh(s, {.unwrap = true, .positionUnitsPerCount = 0.5});
  ASSERT_TRUE(clip) << clip.error().firstError();
  ASSERT_EQ(clip->joints.size(), 5u);
  EXPECT_EQ(clip->joints[0].name, "Session");
  EXPECT_TRUE(clip->joints[0].channels.empty());
  EXPECT_EQ(clip->joints[1].name, "Elbow");
  EXPECT_EQ(clip->joints[1].channels, (std::vector<C>{C::Zrotation, C::Xrotation}));
  EXPECT_EQ(clip->joints[2].name, "knee");
  EXPECT_EQ(clip->joints[2].channels, (std::vector<C>{C::Zrotation}));
  EXPECT_EQ(clip->joints[3].name, "wrist_twist");
  EXPECT_EQ(clip->joints[4].name, "Hip");
  EXPECT_EQ(clip->joints[4].channels, (std::vector<C>{C::Yposition}));
  EXPECT_DOUBLE_EQ(clip->frameTime, 0.02);  // the median spacing, not the jittered one
  ASSERT_EQ(clip->frames.size(), 4u);
  const double step = 360.0 / 4096;
  EXPECT_FLOAT_EQ(clip->frames[1][0], static_cast<float>(100 * step));
  EXPECT_FLOAT_EQ(clip->frames[2][2], clip->frames[1][2]);  // held
  EXPECT_FLOAT_EQ(clip->frames[3][2], static_cast<float>(302 * step));
  EXPECT_FLOAT_EQ(clip->frames[3][4], static_cast<float>(304 * 0.5));
  // The flat skeleton is a valid BVH file.
  auto reread = readBvhText(writeBvh(*clip).value());
  ASSERT_TRUE(reread) << reread.error().str();
  EXPECT_EQ(*reread, *clip);
}

TEST(SessionToBvh, TimestampsWhoseDifferencesOverflowGiveNoFrameTime) {
  // Timestamps are whatever the file holds. Every difference here overflows int64; it used to wrap into a frame time
  // of hundreds of years (undefined behaviour); now no spacing is measurable and the default 1/60 s applies.
  Session s;
  DeviceInfo d;
  d.name = "extreme";
  d.channelCount = 1;
  d.bitsPerChannel = 12;
  s.devices = {d};
  for (int i = 0; i < 5; ++i) {
    Sample x;
    x.channelCount = 1;
    x.arrivalTimeNs = i % 2 ? 9'000'000'000'000'000'000 : -9'000'000'000'000'000'000;
    s.samples.push_back(x);
    s.sampleDevice.push_back(0);
  }
  auto clip = sessionToBvh(s);
  ASSERT_TRUE(clip) << clip.error().firstError();
  EXPECT_DOUBLE_EQ(clip->frameTime, 1.0 / 60.0);
}

TEST(BvhToSession, AClipLongerThanSessionTimestampsReachIsRefused) {
  BvhClip clip;
  clip.joints.push_back({"A", -1, {0, 0, 0}, {C::Xrotation}, false, {}});
  clip.frames = {{0.f}, {1.f}, {2.f}};
  clip.frameTime = 1e308;  // built in memory: the reader refuses this, the conversion must not trust it either
  auto s = bvhToSession(clip, "long.bvh");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().firstError().find("long.bvh: error: the clip lasts longer than a session can time"),
            std::string::npos)
      << s.error().firstError();
}

TEST(BvhToSession, AClipOfMoreChannelsThanASessionHoldsIsAnInputError) {
  // 1.2 M channels used to reach the session writer, fail on a record beyond the format's limit, and be reported as
  // an I/O error naming the temporary file.
  BvhClip clip;
  clip.joints.push_back({"Root", -1, {0, 0, 0}, {}, false, {}});
  for (int j = 0; j < 11000; ++j)
    clip.joints.push_back({"J" + std::to_string(j), 0, {0, 0, 0},
                           {C::Xposition, C::Yposition, C::Zposition, C::Xrotation, C::Yrotation, C::Zrotation},
                           false, {}});
  auto s = bvhToSession(clip, "wide.bvh");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().firstError(),
            "wide.bvh: error: the clip has 66000 channels, more than the 65536 a session holds (1024 "
            "devices of 64)");
  // Long joint names: within the channel limit, but the hierarchy's text is beyond a record's 64 MiB.
  clip.joints.resize(1 + 4000);
  clip.joints[0].channels = {C::Xrotation};
  for (size_t j = 1; j < clip.joints.size(); ++j) {
    clip.joints[j].name = std::string(17000, 'n') + std::to_string(j);
    clip.joints[j].channels.clear();
  }
  s = bvhToSession(clip, "long.bvh");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().firstError().find("more than the 64 MiB a session record holds"), std::string::npos)
      << s.error().firstError();
}

TEST(SaveSession, ErrorsNameTheTargetNotTheTemporaryFile) {
  const fs::path target = fs::temp_directory_path() / ("imps_save_" + std::to_string(::getpid()) + ".session");
  Session s;
  DeviceInfo bad;
  bad.name = "no channels";  // refused by the writer
  s.devices = {bad};
  auto saved = saveSession(target, s);
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().firstError().rfind(target.string() + ": error: ", 0), 0u) << saved.error().firstError();
  EXPECT_EQ(saved.error().firstError().find(".tmp"), std::string::npos) << saved.error().firstError();
  EXPECT_FALSE(fs::exists(target));
  for (const auto& e : fs::directory_iterator(target.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(target.filename().string() + ".tmp"), std::string::npos) << e.path();
}

TEST(BvhToSession, Errors) {
  BvhClip empty;
  empty.joints.push_back({"A", -1, {0, 0, 0}, {}, false, {}});
  auto none = bvhToSession(empty, "e.bvh");
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().firstError(), "e.bvh: error: the clip has no channels");
  BvhClip clip;
  clip.joints.push_back({"A", -1, {0, 0, 0}, {C::Xposition}, false, {}});
  clip.frames = {{1000.f}};
  auto tooFar = bvhToSession(clip, "far.bvh", {.bitsPerChannel = 12, .positionUnitsPerCount = 0.01});
  ASSERT_FALSE(tooFar);
  EXPECT_EQ(tooFar.error().firstError(),
            "far.bvh: error: A:Xposition = 1000 in frame 1 does not fit 12 bits at 0.01 units per count");
  auto bits = bvhToSession(clip, "b.bvh", {.bitsPerChannel = 24});
  ASSERT_FALSE(bits);
  EXPECT_EQ(bits.error().firstError(), "b.bvh: error: bits per channel 24 outside 8..20");

  Session mismatched;
  auto s = bvhToSession(read("end_joint.bvh"), "end_joint.bvh");
  ASSERT_TRUE(s);
  mismatched = *s;
  mismatched.devices[0].channelNames[1] = "Base:Wposition";
  auto bad = sessionToBvh(mismatched);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().firstError(),
            "session: error: channel 1 is 'Base:Wposition', the skeleton says 'Base:Yposition'");
}

}  // namespace
}  // namespace imps::sim
