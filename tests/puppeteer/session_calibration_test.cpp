// SPDX-License-Identifier: MIT
// Calibrations stored in sessions (puppeteer/src/session_calibration.cpp): appendCalibration → readSession → the
// calibration in force for a sample, round trips of the stored blob, and the legacy BVH channel mapping read as none.
#include "session_calibration.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "calibration/calibration.h"
#include "cli_run.h"
#include "examples.h"
#include "scratch_dir.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

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

TEST(SessionCalibration, ReplayFindsTheCalibrationItWasCapturedWith) {
  const ScratchDir dir("imps_session_calibration");
  const auto path = dir / "take.session";
  const drivers::DeviceInfo dev = device32();
  auto first = calibration::Calibration::readFile(test::sourceFile("examples/simple_biped.calibration.json"),
                                                  &test::exampleCharacter("simple_biped"), &dev);
  ASSERT_TRUE(first.has_value()) << first.error().str();
  calibration::RigMap shifted = first->rigMap();
  for (auto& c : shifted.channels) c.offset = *c.offset + 100;
  auto second = calibration::Calibration::create(shifted, &test::exampleCharacter("simple_biped"), &dev);
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
  auto at5 = calibrationForSample(*session, 5, &test::exampleCharacter("simple_biped"), path.string());
  auto at15 = calibrationForSample(*session, 15, &test::exampleCharacter("simple_biped"), path.string());
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
  auto bad = calibrationForSample(*session, 15, &test::exampleCharacter("simple_biped"), "take.session");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().str(), "take.session calibration #1:1:39: error: expected a value, found '}'\n");
}

// Sessions converted from BVH by earlier versions carry the clip's channel mapping as a CALIBRATION blob: it is
// not a calibration (channels map by name), so none is in force — no error to report.
TEST(SessionCalibration, OldBvhChannelMappingIsNoCalibration) {
  auto old = sim::readSession(test::sourceFile("tests/data/sessions/legacy_bvh_mapping.session"));
  ASSERT_TRUE(old.has_value()) << old.error().str();
  ASSERT_EQ(old->calibrations.size(), 1u);
  EXPECT_TRUE(isBvhChannelMapping(old->calibrations[0].json));
  auto found = calibrationForSample(*old, 0, &test::exampleCharacter("simple_biped"), "legacy_bvh_mapping.session");
  ASSERT_TRUE(found.has_value()) << found.error().str();
  EXPECT_FALSE(found->has_value());
  EXPECT_FALSE(isBvhChannelMapping("{\"version\": 1, \"bits\": 12, \"info\": {\"source\":\"bvh\"}, \"joints\": []}"));
}

// The calibration in force is found from the sample it was recorded at: none before it; a calibration for another
// device (here one with fewer channels) is an error against the session, not a silent mismatch.
TEST(SessionCalibration, NoneBeforeItsFirstSampleAndCheckedAgainstTheDevice) {
  const ScratchDir dir("imps_session_calibration");
  const Character& biped = test::exampleCharacter("simple_biped");
  const drivers::DeviceInfo dev = device32();
  auto cal =
      calibration::Calibration::readFile(test::sourceFile("examples/simple_biped.calibration.json"), &biped, &dev);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  drivers::DeviceInfo small = dev;
  small.channelCount = 4;
  small.channelNames.resize(4);
  for (const auto& [device, name] : {std::pair{dev, "late.session"}, std::pair{small, "small.session"}}) {
    auto w = sim::SessionWriter::create(dir / name, device);
    ASSERT_TRUE(w.has_value()) << w.error().str();
    drivers::Sample s;
    s.channelCount = uint16_t(device.channelCount);
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(w->append(s).has_value());
    ASSERT_TRUE(appendCalibration(*w, *cal).has_value());
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(w->append(s).has_value());
    ASSERT_TRUE(w->close().has_value());
  }
  auto late = sim::readSession(dir / "late.session");
  ASSERT_TRUE(late.has_value()) << late.error().str();
  ASSERT_EQ(late->calibrations.size(), 1u);
  EXPECT_EQ(late->calibrations[0].firstSample, 5u);
  EXPECT_EQ(late->calibrations[0].json, cal->toJson()) << "stored as the calibration file's text";
  auto before = calibrationForSample(*late, 4, &biped, "late.session");
  ASSERT_TRUE(before.has_value()) << before.error().str();
  EXPECT_FALSE(before->has_value());
  auto after = calibrationForSample(*late, 5, &biped, "late.session");
  ASSERT_TRUE(after.has_value() && after->has_value());
  EXPECT_EQ((*after)->toJson(), cal->toJson());
  auto small4 = sim::readSession(dir / "small.session");
  ASSERT_TRUE(small4.has_value()) << small4.error().str();
  auto mismatch = calibrationForSample(*small4, 5, &biped, "small.session");
  ASSERT_FALSE(mismatch.has_value());
  EXPECT_NE(mismatch.error().str().find("small.session calibration #0:"), std::string::npos) << mismatch.error().str();
}

}  // namespace
}  // namespace imps::app
