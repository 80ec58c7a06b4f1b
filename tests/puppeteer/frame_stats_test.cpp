// SPDX-License-Identifier: MIT
// Frame statistics without a window or clock: nearest-rank percentiles on known distributions (empty, one sample,
// uniform, skewed), the HUD's half-second windows from made-up timestamps, the bounded latency window over a long
// run, and the exit summary's numbers and text.
#include "frame_stats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace imps::app {
namespace {

constexpr int64_t kMs = 1'000'000;  // nanoseconds

std::vector<double> oneTo(int n) {
  std::vector<double> v;
  for (int i = 1; i <= n; ++i) v.push_back(double(i));
  return v;
}

TEST(FrameStats, PercentilesOfKnownDistributions) {
  EXPECT_EQ(percentile({}, 0.5), -1.0);
  EXPECT_EQ(medianP99({}).median, -1.0);
  EXPECT_EQ(medianP99({}).p99, -1.0);
  // One sample is every percentile.
  EXPECT_EQ(medianP99({4.5}).median, 4.5);
  EXPECT_EQ(medianP99({4.5}).p99, 4.5);
  // 1..101 in any order: the median is 51, the 99th percentile 100 (index round(0.99 * 100) = 99).
  std::vector<double> values = oneTo(101);
  std::shuffle(values.begin(), values.end(), std::mt19937(7));
  EXPECT_EQ(medianP99(values).median, 51.0);
  EXPECT_EQ(medianP99(values).p99, 100.0);
  EXPECT_EQ(percentile(values, 0.0), 1.0);
  EXPECT_EQ(percentile(values, 1.0), 101.0);
  // Even counts round the index half up: 1..4 → index round(1.5) = 2 → 3.
  EXPECT_EQ(percentile(oneTo(4), 0.5), 3.0);
  // A skewed distribution: 99 fast frames and one stall; the p99 of 1000 such frames sees the stalls.
  std::vector<double> frames(1000, 16.7);
  for (size_t i = 0; i < frames.size(); i += 50) frames[i] = 250.0;  // 2 %
  EXPECT_EQ(medianP99(frames).median, 16.7);
  EXPECT_EQ(medianP99(frames).p99, 250.0);
}

TEST(FrameStats, TheCallersValuesAreNotTouched) {
  const std::vector<double> values = {5, 1, 4, 2, 3};
  std::vector<double> copy = values;
  (void)medianP99(copy);
  EXPECT_EQ(copy, values);
}

TEST(FrameStats, HudWindowClosesEveryHalfSecond) {
  FrameStats stats(100);
  stats.start(1000 * kMs);
  int64_t now = 1000 * kMs;
  int closed = 0;
  // 20 ms frames: the 25th frame ends 500 ms after the start and closes the first window.
  for (int f = 1; f <= 25; ++f) {
    stats.addPhase(FramePhase::Draw, 12.0);
    stats.addPhase(FramePhase::Swap, 8.0);
    stats.addLatency(30.0 + f);
    now += 20 * kMs;
    if (stats.endFrame(now)) {
      ++closed;
      EXPECT_EQ(f, 25);
    }
  }
  ASSERT_EQ(closed, 1);
  const FrameWindow& w = stats.window();
  EXPECT_NEAR(w.fps, 50.0, 1e-9);
  EXPECT_NEAR(w.frameMs, 20.0, 1e-9);
  EXPECT_NEAR(w.phaseMs[size_t(FramePhase::Draw)], 12.0, 1e-9);
  EXPECT_NEAR(w.phaseMs[size_t(FramePhase::Swap)], 8.0, 1e-9);
  EXPECT_EQ(w.phaseMs[size_t(FramePhase::Pose)], 0.0);
  EXPECT_EQ(w.latencyMedianMs, 43.0);  // 31..55
  EXPECT_EQ(w.latencyP99Ms, 55.0);
  EXPECT_EQ(stats.lastFrameMs(), 20.0);
  // The next window starts from zero: slower frames show at once.
  for (int f = 0; f < 10; ++f) {
    stats.addPhase(FramePhase::Draw, 45.0);
    now += 50 * kMs;
    EXPECT_EQ(stats.endFrame(now), f == 9);
  }
  EXPECT_NEAR(stats.window().fps, 20.0, 1e-9);
  EXPECT_NEAR(stats.window().phaseMs[size_t(FramePhase::Draw)], 45.0, 1e-9);
  EXPECT_EQ(stats.window().phaseMs[size_t(FramePhase::Swap)], 0.0);
}

TEST(FrameStats, SummaryCoversEveryFrame) {
  FrameStats stats;
  EXPECT_EQ(stats.frames(), 0);
  EXPECT_EQ(stats.lastFrameMs(), 0.0);
  const FrameSummary none = stats.summary();
  EXPECT_EQ(none.frames, 0);
  EXPECT_EQ(none.fps(), 0.0);
  EXPECT_EQ(none.frameMs.median, -1.0);
  EXPECT_EQ(none.phaseMedianMs[0], -1.0);

  stats.start(0);
  int64_t now = 0;
  for (int f = 1; f <= 100; ++f) {
    stats.addPhase(FramePhase::Polygonize, double(f));
    now += (f == 100 ? 400 : 10) * kMs;
    if (f % 2 == 0) stats.addLatency(double(f));
    stats.endFrame(now);
  }
  const FrameSummary s = stats.summary();
  EXPECT_EQ(s.frames, 100);
  EXPECT_NEAR(s.seconds, 1.39, 1e-9);
  EXPECT_NEAR(s.fps(), 100 / 1.39, 1e-9);
  EXPECT_EQ(s.frameMs.median, 10.0);
  EXPECT_EQ(s.frameMs.p99, 10.0);  // index round(99 * 0.99) = 98: the stall is the 100th
  EXPECT_EQ(s.phaseMedianMs[size_t(FramePhase::Polygonize)], 51.0);
  EXPECT_EQ(s.phaseMedianMs[size_t(FramePhase::Draw)], -1.0);
  EXPECT_EQ(s.latencies, 50u);
  EXPECT_EQ(s.latencyMs.median, 52.0);  // 2, 4, ..., 100: index round(24.5) = 25 → 52
  EXPECT_EQ(s.latencyMs.p99, 100.0);
}

TEST(FrameStats, TheHudsLatencyWindowStaysBoundedOverALongRun) {
  // An hour at 60 FPS with a sample on every frame: the HUD looks at the recent latencies only, however long the
  // run, while the exit summary still counts them all.
  FrameStats stats;
  stats.start(0);
  int64_t now = 0;
  size_t largest = 0;
  const int frames = 60 * 3600;
  for (int f = 0; f < frames; ++f) {
    stats.addLatency(f < frames / 2 ? 10.0 : 20.0);
    now += 16'666'667;
    if (stats.endFrame(now)) {
      largest = std::max(largest, stats.recentLatencyCount());
      EXPECT_LE(stats.recentLatencyCount(), FrameStats::kRecentLatencies);
    }
  }
  EXPECT_GE(largest, FrameStats::kKeptLatencies);
  // The HUD follows the recent samples; the summary all of them.
  EXPECT_EQ(stats.window().latencyMedianMs, 20.0);
  EXPECT_EQ(stats.summary().latencies, size_t(frames));
  EXPECT_EQ(stats.summary().latencyMs.median, 20.0);  // half and half: index round(0.5 (n - 1)) is in the second half
}

TEST(FrameStats, SummaryText) {
  FrameSummary s;
  s.frames = 30;
  s.seconds = 0.5;
  s.frameMs = {16.0, 33.3};
  for (int p = 0; p < kFramePhases; ++p) s.phaseMedianMs[size_t(p)] = p + 0.5;
  const std::string text = summaryText(s, 5268, 640, 480, false);
  EXPECT_EQ(text,
            "puppeteer: 30 frames in 0.50 s: 60.0 FPS (frame time median 16.0 ms, p99 33.3 ms), 5268 triangles, "
            "640x480\n"
            "puppeteer: median ms per phase: pose 0.50 polygonize 1.50 upload 2.50 draw 3.50 hud 4.50 swap 5.50\n");
  // Synced phases say so; a latency line appears once a frame showed a sample.
  s.latencies = 12;
  s.latencyMs = {7.5, 19.0};
  const std::string synced = summaryText(s, 1, 2, 3, true);
  EXPECT_NE(synced.find("median ms per phase (GL finished after each): pose"), std::string::npos);
  EXPECT_NE(synced.find("puppeteer: sample-to-screen latency over 12 frames: median 7.5 ms, p99 19.0 ms\n"),
            std::string::npos);
  EXPECT_EQ(std::count(synced.begin(), synced.end(), '\n'), 3);
}

// Particle meshes replaced by the tesselator's Marching Cubes stand-in are counted and, when any was, reported.
TEST(FrameStats, StandInsAreCountedAndReported) {
  FrameStats stats;
  stats.start(0);
  stats.addParticleMesh(false, false);
  stats.addParticleMesh(true, true);
  stats.addParticleMesh(true, false);
  stats.addParticleMesh(false, true);  // a cut found but not shown is no stand-in
  EXPECT_EQ(stats.particleMeshes(), 4u);
  EXPECT_EQ(stats.standIns(), 2u);
  const FrameSummary s = stats.summary();
  EXPECT_EQ(s.standInsCutOff, 1u);
  EXPECT_NE(summaryText(s, 1, 2, 3, false)
                .find("puppeteer: the particles' mesh was replaced by Marching Cubes in 2 of 4 particle meshes (1 for "
                      "a part cut off, the rest for a hole or a pinch)\n"),
            std::string::npos);
  FrameStats none;
  none.addParticleMesh(false, false);
  EXPECT_EQ(summaryText(none.summary(), 1, 2, 3, false).find("Marching Cubes"), std::string::npos);
}

TEST(FrameStats, PhaseNames) {
  EXPECT_STREQ(phaseName(FramePhase::Pose), "pose");
  EXPECT_STREQ(phaseName(FramePhase::Polygonize), "polygonize");
  EXPECT_STREQ(phaseName(FramePhase::Swap), "swap");
}

}  // namespace
}  // namespace imps::app
