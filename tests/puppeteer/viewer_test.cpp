// SPDX-License-Identifier: MIT
// The live app's window and frame loop (runViewer) under Xvfb, headless: the requested number of frames is drawn
// and the screenshot written at the window's size, a pose source is polled every frame and finished once with its
// exit code passed on, an unwritable screenshot fails the run, the exit summary counts the frames, the same run
// gives the same picture, and a scripted drag beside the character orbits the camera. Skipped without a display
// (gl_display.h).
#include "viewer.h"

#include <gtest/gtest.h>

#include <string>

#include "cli.h"
#include "gl_display.h"
#include "imps/character.h"
#include "imps/scene_reader.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

std::unique_ptr<ViewerPipeline> biped() {
  auto scene = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/examples/simple_biped.wrl");
  EXPECT_TRUE(scene.has_value());
  auto character = Character::fromScene(*scene);
  EXPECT_TRUE(character.has_value());
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;  // deterministic and quick under a software GL
  o.mcResolution = 32;
  return std::make_unique<ViewerPipeline>(std::move(*scene), std::move(*character), o);
}

ViewerOptions headless(int frames, const std::string& screenshot) {
  ViewerOptions o;
  o.width = 200, o.height = 150;
  o.frames = frames;
  o.screenshot = screenshot;
  o.hud = false;
  o.title = "viewer_test";
  return o;
}

// A pose source that never has a new pose and counts what the frame loop asks of it.
class CountingSource : public PoseSource {
 public:
  explicit CountingSource(int exitCode = kExitOk) : exitCode_(exitCode) {}
  bool poll(SkeletonCache&, int64_t*) override {
    ++polls;
    return false;
  }
  void describe(HudInfo&) override { ++describes; }
  void frameDone() override { ++framesDone; }
  std::string finish() override {
    ++finishes;
    return "source finished";
  }
  int exitCode() const override { return exitCode_; }
  int polls = 0, describes = 0, framesDone = 0, finishes = 0;

 private:
  int exitCode_;
};

// The width and height in a PNG's IHDR chunk (big-endian at bytes 16-23), or 0, 0 when it is no PNG.
std::pair<uint32_t, uint32_t> pngSize(const std::string& bytes) {
  if (bytes.size() < 24 || bytes.compare(1, 3, "PNG") != 0) return {0, 0};
  auto be32 = [&](size_t at) {
    return uint32_t(uint8_t(bytes[at])) << 24 | uint32_t(uint8_t(bytes[at + 1])) << 16 |
           uint32_t(uint8_t(bytes[at + 2])) << 8 | uint32_t(uint8_t(bytes[at + 3]));
  };
  return {be32(16), be32(20)};
}

TEST(ViewerGl, RunsTheFramesPollsTheSourceAndWritesTheScreenshot) {
  IMPS_NEED_DISPLAY();
  ScratchDir dir("viewer");
  auto pipeline = biped();
  CountingSource source;
  testing::internal::CaptureStdout();
  const int code = runViewer(*pipeline, &source, headless(4, (dir / "shot.png").string()));
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, kExitOk);
  EXPECT_EQ(source.framesDone, 4);
  EXPECT_GE(source.polls, 5) << "polled for the settle and every frame";
  EXPECT_EQ(source.finishes, 1);
  EXPECT_EQ(source.describes, 0) << "no HUD, nothing to describe";
  EXPECT_EQ(pngSize(fileBytes(dir / "shot.png")), std::make_pair(200u, 150u));
  EXPECT_NE(out.find("puppeteer: source finished\n"), std::string::npos) << out;
  EXPECT_NE(out.find("puppeteer: 4 frames in "), std::string::npos) << out;
  EXPECT_NE(out.find("triangles, 200x150\n"), std::string::npos) << out;
  EXPECT_NE(out.find("puppeteer: median ms per phase: pose "), std::string::npos) << out;
  EXPECT_EQ(out.find("sample-to-screen latency"), std::string::npos) << "no sample reached the screen";
}

TEST(ViewerGl, TheSourcesExitCodeAndAFailedScreenshotFailTheRun) {
  IMPS_NEED_DISPLAY();
  ScratchDir dir("viewer");
  auto pipeline = biped();
  CountingSource failing(kExitIoError);
  testing::internal::CaptureStdout();
  EXPECT_EQ(runViewer(*pipeline, &failing, headless(1, "")), kExitIoError);
  EXPECT_EQ(failing.finishes, 1);
  testing::internal::CaptureStderr();
  EXPECT_EQ(runViewer(*pipeline, nullptr, headless(1, (dir / "no/such/dir/shot.png").string())), kExitIoError);
  const std::string err = testing::internal::GetCapturedStderr();
  testing::internal::GetCapturedStdout();
  EXPECT_NE(err.find("puppeteer: error: "), std::string::npos) << err;
}

TEST(ViewerGl, TheSameRunGivesTheSamePictureAndADragOrbits) {
  IMPS_NEED_DISPLAY();
  ScratchDir dir("viewer");
  testing::internal::CaptureStdout();
  auto run = [&](const std::string& name, std::vector<ScriptedEvent> script) {
    auto pipeline = biped();
    ViewerOptions o = headless(2, (dir / name).string());
    o.msaaSamples = 0;
    o.script = std::move(script);
    EXPECT_EQ(runViewer(*pipeline, nullptr, o), kExitOk);
    return fileBytes(dir / name);
  };
  const std::string first = run("a.png", {});
  const std::string again = run("b.png", {});
  // A drag in the top-left corner, away from the character: the camera turns.
  ScriptedEvent drag;
  drag.kind = ScriptedEvent::Kind::Drag;
  drag.x0 = 5, drag.y0 = 5, drag.x1 = 60, drag.y1 = 5;
  const std::string orbited = run("c.png", {drag});
  testing::internal::GetCapturedStdout();
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(first, again) << "the same headless run drew a different picture";
  EXPECT_NE(first, orbited) << "the drag did not move the camera";
}

}  // namespace
}  // namespace imps::app
