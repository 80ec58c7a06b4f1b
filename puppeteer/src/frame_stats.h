// SPDX-License-Identifier: MIT
// The live app's frame statistics, free of any window or clock: per-phase times, frame times and sample-to-screen
// latencies, summarised every half second for the HUD and once at exit (median and 99th percentile), and the exit
// summary's text. The viewer feeds it steady-clock timestamps; tests feed made-up ones.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace imps::app {

// The q-quantile (q in [0, 1]) of `values` by nearest rank: the element at index round(q * (n - 1)) of the sorted
// values. -1 for no values. `values` is a copy (reordered by the selection).
double percentile(std::vector<double> values, double q);

// Median and 99th percentile (percentile() at 0.5 and 0.99); both -1 for no values.
struct MedianP99 {
  double median = -1.0;
  double p99 = -1.0;
};
MedianP99 medianP99(std::vector<double> values);

// The phases of one frame, in the order the frame runs them.
enum class FramePhase { Pose, Polygonize, Upload, Draw, Hud, Swap };
inline constexpr int kFramePhases = 6;
// "pose", "polygonize", "upload", "draw", "hud", "swap".
const char* phaseName(FramePhase phase);

// What the HUD shows for the last window of frames (about half a second).
struct FrameWindow {
  double fps = 0.0;                            // frames in the window / its length
  double frameMs = 0.0;                        // the window's length / frames in it
  std::array<double, kFramePhases> phaseMs{};  // mean milliseconds per frame of each phase in the window
  // Over the recent latencies (FrameStats::kRecentLatencies); -1 for none.
  double latencyMedianMs = -1.0, latencyP99Ms = -1.0;
};

// The exit summary's figures.
struct FrameSummary {
  int frames = 0;
  double seconds = 0.0;                              // from start() to the end of the last frame
  MedianP99 frameMs;                                 // over every frame time
  std::array<double, kFramePhases> phaseMedianMs{};  // each phase's median over every frame (-1: never timed)
  size_t latencies = 0;                              // frames that showed a new sample
  MedianP99 latencyMs;                               // over every latency
  // Particle meshes shown (frames with a new particle triangulation) and how many of them were the tesselator's
  // Marching Cubes stand-in (TesselatorStats::fallback: the particles' own mesh had a hole, a pinch or a part cut
  // off), `standInsCutOff` of those for a part cut off.
  uint64_t particleMeshes = 0, standIns = 0, standInsCutOff = 0;
  double fps() const { return seconds > 0.0 ? frames / seconds : 0.0; }
};

// The statistics of one run of the frame loop. Not thread-safe (the frame loop's thread only). Every frame's times
// are kept for the exact exit percentiles (8 bytes for each phase, the frame time and the latency: about 64 bytes per
// frame, some 14 MB an hour at 60 FPS); the HUD's latency window is bounded (kRecentLatencies).
class FrameStats {
 public:
  // The HUD's figures are recomputed once a window this long (nanoseconds) has passed.
  static constexpr int64_t kWindowNs = 500'000'000;
  // The latencies the HUD's percentiles look at: when a window closes with more than this many, all but the last
  // kKeptLatencies are dropped, so they never exceed kRecentLatencies plus one window's frames.
  static constexpr size_t kRecentLatencies = 2000;
  static constexpr size_t kKeptLatencies = 1000;

  // `expectedFrames` > 0 reserves room for that many frames (a headless run); else for 65536.
  explicit FrameStats(int expectedFrames = 0);

  // The loop starts at `nowNs` (steady clock, nanoseconds): the first frame's time and the first window count
  // from here.
  void start(int64_t nowNs);
  // `ms` milliseconds spent in `phase` this frame (a phase may be added more than once per frame; each call is kept
  // as one sample for the exit medians and summed for the HUD's mean).
  void addPhase(FramePhase phase, double ms);
  // A frame showed a sample that arrived `ms` milliseconds before it was on screen.
  void addLatency(double ms);
  // A new particle mesh is shown this frame; `standIn`: it is the Marching Cubes stand-in, `cutOff`: for a part cut
  // off.
  void addParticleMesh(bool standIn, bool cutOff);
  // The frame ended (is on screen) at `nowNs`. Returns true when this closed a window: window() then holds the new
  // figures and the next window starts here.
  bool endFrame(int64_t nowNs);

  int frames() const { return frames_; }
  uint64_t particleMeshes() const { return particleMeshes_; }
  uint64_t standIns() const { return standIns_; }
  // The last frame's time (ms); 0 before the first frame.
  double lastFrameMs() const { return frameMs_.empty() ? 0.0 : frameMs_.back(); }
  // The figures of the last window closed (all zero / -1 before the first).
  const FrameWindow& window() const { return window_; }
  // How many latencies the HUD's percentiles look at now.
  size_t recentLatencyCount() const { return recentLatencies_.size(); }
  FrameSummary summary() const;

 private:
  int64_t startNs_ = 0, lastFrameEndNs_ = 0, windowStartNs_ = 0;
  int frames_ = 0, framesInWindow_ = 0;
  uint64_t particleMeshes_ = 0, standIns_ = 0, standInsCutOff_ = 0;
  std::array<double, kFramePhases> phaseSum_{};
  std::array<std::vector<double>, kFramePhases> phaseMs_;
  std::vector<double> frameMs_, latencies_, recentLatencies_;
  FrameWindow window_;
};

// The exit summary, as the viewer prints it: "puppeteer: N frames in S s: F FPS (frame time median M ms, p99 P ms),
// T triangles, WxH", the phases' medians ("(GL finished after each)" when `syncedPhases`), and the sample-to-screen
// latency when any frame showed a sample, and "the particles' mesh was replaced by Marching Cubes in N of M particle
// meshes (K for a part cut off, the rest for a hole or a pinch)" when any was. Each line ends in '\n'.
std::string summaryText(const FrameSummary& summary, size_t triangles, int width, int height, bool syncedPhases);

}  // namespace imps::app
