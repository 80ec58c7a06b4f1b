// SPDX-License-Identifier: MIT
// The HUD's key help offers only what works: o (record) and k (calibrate) need a live device.
#include <gtest/gtest.h>

#include "hud.h"
#include "viewer.h"

namespace imps::app {
namespace {

TEST(Hud, KeyHelpOffersRecordAndCalibrateOnlyWithALiveDevice) {
  const std::string view = keyHelp(false), live = keyHelp(true);
  EXPECT_EQ(view.find("o record"), std::string::npos) << view;
  EXPECT_EQ(view.find("k calibrate"), std::string::npos) << view;
  EXPECT_NE(live.find("o record"), std::string::npos) << live;
  EXPECT_NE(live.find("k calibrate"), std::string::npos) << live;
  for (const char* key : {"r reset", "s save", "t paint", "p particles", "m MC", "F12 shot", "Esc quit"}) {
    EXPECT_NE(view.find(key), std::string::npos) << key;
    EXPECT_NE(live.find(key), std::string::npos) << key;
  }
}

// A pose source that is not a live device (view's hand posing has none; replay's is one of these) does not offer
// them either.
TEST(Hud, OnlyLiveSourcesHandleTheDeviceKeys) {
  struct Replayish final : PoseSource {
    bool poll(SkeletonCache&, int64_t*) override { return false; }
    void describe(HudInfo&) override {}
  } replay;
  EXPECT_FALSE(replay.handlesDeviceKeys());
}

}  // namespace
}  // namespace imps::app
