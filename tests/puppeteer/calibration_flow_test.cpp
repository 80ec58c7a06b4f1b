// SPDX-License-Identifier: MIT
// Joint-offset calibration as a flow over a sample stream (puppeteer/src/calibration_flow.cpp): the window collected
// after the countdown, a still window giving the offsets its samples hold, a noisy one rejected naming its channels,
// and the info object `puppeteer calibrate` writes.
#include "calibration_flow.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibration/rig_map.h"
#include "cli_run.h"
#include "examples.h"

namespace imps::app {
namespace {

TEST(CalibrationFlow, CollectsTheWindowAfterTheCountdown) {
  CalibrationFlow flow({.delayMs = 1000, .windowMs = 500, .maxNoiseDeg = 0.5});
  EXPECT_EQ(flow.phase(), CalibrationFlow::Phase::Idle);
  flow.start(0);
  EXPECT_EQ(flow.phase(), CalibrationFlow::Phase::Countdown);
  EXPECT_NE(flow.progress(400'000'000).find("averaging in 0.6s"), std::string::npos) << flow.progress(400'000'000);
  auto at = [](int64_t ms) {
    drivers::Sample s;
    s.channelCount = 1;
    s.arrivalTimeNs = ms * 1'000'000;
    return s;
  };
  const std::vector<drivers::Sample> early = {at(100), at(999)};
  EXPECT_FALSE(flow.update(early, 999'000'000));
  EXPECT_TRUE(flow.window().empty());
  const std::vector<drivers::Sample> inside = {at(1000), at(1200), at(1499)};
  EXPECT_FALSE(flow.update(inside, 1'300'000'000));
  EXPECT_EQ(flow.phase(), CalibrationFlow::Phase::Averaging);
  EXPECT_NE(flow.progress(1'300'000'000).find("3 samples"), std::string::npos);
  const std::vector<drivers::Sample> late = {at(1500), at(1600)};
  EXPECT_TRUE(flow.update(late, 1'600'000'000));
  EXPECT_EQ(flow.phase(), CalibrationFlow::Phase::Complete);
  EXPECT_EQ(flow.window().size(), 3u);
  EXPECT_FALSE(flow.update(late, 1'700'000'000));  // only once
  flow.reset();
  EXPECT_EQ(flow.phase(), CalibrationFlow::Phase::Idle);
  EXPECT_TRUE(flow.window().empty());
}

drivers::DeviceInfo monkey() {
  drivers::DeviceInfo d;
  d.name = "IMPS Simulated Monkey";
  d.serialNumber = "SIM0001";
  d.channelCount = 32;
  d.bitsPerChannel = 12;
  for (int i = 0; i < 32; ++i) d.channelNames.push_back("ch" + std::to_string(i));
  return d;
}

calibration::RigMap bipedRig() {
  auto rig = calibration::readRigMapFile(test::sourceFile("examples/simple_biped.rig.json"));
  EXPECT_TRUE(rig) << rig.error().str();
  return rig ? std::move(*rig) : calibration::RigMap{};
}

// 100 samples at 1 kHz: channel c at 1000 + 50 c counts, plus `wobble` counts alternating on channel 5.
std::vector<drivers::Sample> window(uint32_t wobble) {
  std::vector<drivers::Sample> out(100);
  for (size_t k = 0; k < out.size(); ++k) {
    out[k].sequence = uint32_t(k);
    out[k].arrivalTimeNs = int64_t(k) * 1'000'000;
    out[k].channelCount = 32;
    for (size_t c = 0; c < 32; ++c) out[k].counts[c] = uint32_t(1000 + 50 * c);
    out[k].counts[5] += (k % 2) ? wobble : 0;
  }
  return out;
}

TEST(CalibrateWindow, AStillWindowGivesTheOffsetsItHolds) {
  const drivers::DeviceInfo device = monkey();
  const std::string info = calibrationInfoJson("scene.wrl", "rig.json", "sim:", 100, 100, device.serialNumber);
  auto result = calibrateWindow(bipedRig(), window(0), device, test::exampleCharacter("simple_biped"), 0.5, info);
  ASSERT_TRUE(result) << (result ? "" : result.error().str());
  EXPECT_DOUBLE_EQ(result->maxNoiseDeg, 0.0);
  const calibration::RigMap& map = result->calibration.rigMap();
  ASSERT_FALSE(map.channels.empty());
  for (const auto& c : map.channels) {
    ASSERT_TRUE(c.offset) << c.channel;
    EXPECT_NEAR(*c.offset, 1000.0 + 50.0 * double(c.channel), 1e-9) << c.channel;
  }
  EXPECT_EQ(map.device, device.name);
  EXPECT_EQ(map.info, info);
}

TEST(CalibrateWindow, ANoisyWindowIsRejectedNamingItsChannel) {
  // 40 counts of wobble on a 12-bit encoder: about 1.8 degrees of standard deviation, above 0.5.
  auto result = calibrateWindow(bipedRig(), window(80), monkey(), test::exampleCharacter("simple_biped"), 0.5, "{}");
  ASSERT_FALSE(result);
  ASSERT_EQ(result.error().errorCount(), 1);
  EXPECT_TRUE(test::contains(result.error().str(), "channel 5")) << result.error().str();
  EXPECT_TRUE(test::contains(result.error().str(), "too noisy")) << result.error().str();
  // A looser limit accepts it and names the noisiest channel.
  auto loose = calibrateWindow(bipedRig(), window(80), monkey(), test::exampleCharacter("simple_biped"), 5.0, "{}");
  ASSERT_TRUE(loose);
  EXPECT_GT(loose->maxNoiseDeg, 0.5);
  EXPECT_TRUE(test::contains(loose->noisiestChannel, "5"));
}

TEST(CalibrationInfoJson, IsAJsonObjectOfTheCalibrationsProvenance) {
  const nlohmann::json info =
      nlohmann::json::parse(calibrationInfoJson("a \"quoted\" scene.wrl", "rig.json", "sim:", 500, 51, "SN-1"));
  EXPECT_EQ(info["scene"], "a \"quoted\" scene.wrl");
  EXPECT_EQ(info["rig"], "rig.json");
  EXPECT_EQ(info["source"], "sim:");
  EXPECT_DOUBLE_EQ(info["window_ms"].get<double>(), 500.0);
  EXPECT_EQ(info["samples"], 51);
  EXPECT_EQ(info["serial"], "SN-1");
  EXPECT_EQ(info["created"].get<std::string>().size(), 20u) << "YYYY-MM-DDTHH:MM:SSZ";
  EXPECT_FALSE(nlohmann::json::parse(calibrationInfoJson("s", "r", "x", 1, 1, "")).contains("serial"));
}

}  // namespace
}  // namespace imps::app
