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

// The stand-in line: absent until a particle mesh was replaced, then the count on every frame, and why on a frame that
// shows one.
TEST(Hud, StandInLineSaysWhyAndHowOften) {
  HudInfo info;
  info.particleMeshes = 40;
  EXPECT_EQ(standInText(info), "");
  info.standIn = true, info.standIns = 1, info.particleMeshes = 41;
  EXPECT_EQ(standInText(info), "MC stand-in (hole or pinch)  1 of 41 meshes");
  info.standInCutOff = true, info.standIns = 2, info.particleMeshes = 42;
  EXPECT_EQ(standInText(info), "MC stand-in (part cut off)  2 of 42 meshes");
  info.standIn = info.standInCutOff = false, info.particleMeshes = 43;
  EXPECT_EQ(standInText(info), "MC stand-ins: 2 of 43 meshes");
}

}  // namespace
}  // namespace imps::app
