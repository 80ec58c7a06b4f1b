// SPDX-License-Identifier: MIT
// Frame statistics: percentiles, the HUD's half-second windows and the exit summary (see frame_stats.h).
#include "frame_stats.h"

#include <algorithm>
#include <cstdio>
#include <iterator>

namespace imps::app {
namespace {

size_t phaseIndex(FramePhase phase) { return static_cast<size_t>(phase); }

}  // namespace

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return -1.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * double(values.size() - 1) + 0.5));
  std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
  return values[k];
}

MedianP99 medianP99(std::vector<double> values) {
  if (values.empty()) return {};
  // One copy for both: nth_element leaves the k-th element in place whatever order the vector is in.
  const double median = percentile(values, 0.5);
  return {median, percentile(std::move(values), 0.99)};
}

const char* phaseName(FramePhase phase) {
  static const char* const kNames[kFramePhases] = {"pose", "polygonize", "upload", "draw", "hud", "swap"};
  return kNames[phaseIndex(phase)];
}

FrameStats::FrameStats(int expectedFrames) {
  const size_t reserve = expectedFrames > 0 ? size_t(expectedFrames) : size_t{1} << 16;
  frameMs_.reserve(reserve);
  latencies_.reserve(reserve);
  for (auto& v : phaseMs_) v.reserve(reserve);
  recentLatencies_.reserve(kRecentLatencies + 48);
}

void FrameStats::start(int64_t nowNs) { startNs_ = lastFrameEndNs_ = windowStartNs_ = nowNs; }

void FrameStats::addPhase(FramePhase phase, double ms) {
  phaseSum_[phaseIndex(phase)] += ms;
  phaseMs_[phaseIndex(phase)].push_back(ms);
}

void FrameStats::addLatency(double ms) {
  recentLatencies_.push_back(ms);
  latencies_.push_back(ms);
}

void FrameStats::addParticleMesh(bool standIn, bool cutOff) {
  ++particleMeshes_;
  standIns_ += standIn;
  standInsCutOff_ += standIn && cutOff;
}

bool FrameStats::endFrame(int64_t nowNs) {
  frameMs_.push_back(double(nowNs - lastFrameEndNs_) * 1e-6);
  lastFrameEndNs_ = nowNs;
  ++framesInWindow_;
  ++frames_;
  if (nowNs - windowStartNs_ < kWindowNs) return false;
  const double windowNs = double(nowNs - windowStartNs_);
  window_.fps = framesInWindow_ / (windowNs * 1e-9);
  window_.frameMs = windowNs * 1e-6 / framesInWindow_;
  for (size_t p = 0; p < phaseSum_.size(); ++p) window_.phaseMs[p] = phaseSum_[p] / framesInWindow_, phaseSum_[p] = 0.0;
  const MedianP99 latency = medianP99(recentLatencies_);
  window_.latencyMedianMs = latency.median, window_.latencyP99Ms = latency.p99;
  if (recentLatencies_.size() > kRecentLatencies)
    recentLatencies_.erase(recentLatencies_.begin(), recentLatencies_.end() - std::ptrdiff_t(kKeptLatencies));
  windowStartNs_ = nowNs, framesInWindow_ = 0;
  return true;
}

FrameSummary FrameStats::summary() const {
  FrameSummary s;
  s.frames = frames_;
  s.seconds = double(lastFrameEndNs_ - startNs_) * 1e-9;
  s.frameMs = medianP99(frameMs_);
  for (size_t p = 0; p < phaseMs_.size(); ++p) s.phaseMedianMs[p] = medianP99(phaseMs_[p]).median;
  s.latencies = latencies_.size();
  s.latencyMs = medianP99(latencies_);
  s.particleMeshes = particleMeshes_, s.standIns = standIns_, s.standInsCutOff = standInsCutOff_;
  return s;
}

std::string summaryText(const FrameSummary& s, size_t triangles, int width, int height, bool syncedPhases) {
  std::string text;
  auto append = [&text](const char* format, auto... args) {
    char line[256];
    const int n = std::snprintf(line, sizeof line, format, args...);
    if (n > 0) text.append(line, std::min(size_t(n), sizeof line - 1));
  };
  append("puppeteer: %d frames in %.2f s: %.1f FPS (frame time median %.1f ms, p99 %.1f ms), %zu triangles, %dx%d\n",
         s.frames, s.seconds, s.fps(), s.frameMs.median, s.frameMs.p99, triangles, width, height);
  append("puppeteer: median ms per phase%s:", syncedPhases ? " (GL finished after each)" : "");
  for (int p = 0; p < kFramePhases; ++p) append(" %s %.2f", phaseName(FramePhase(p)), s.phaseMedianMs[size_t(p)]);
  text += '\n';
  if (s.latencies > 0)
    append("puppeteer: sample-to-screen latency over %zu frames: median %.1f ms, p99 %.1f ms\n", s.latencies,
           s.latencyMs.median, s.latencyMs.p99);
  if (s.standIns > 0)
    append(
        "puppeteer: the particles' mesh was replaced by Marching Cubes in %llu of %llu particle meshes (%llu for a "
        "part cut off, the rest for a hole or a pinch)\n",
        static_cast<unsigned long long>(s.standIns), static_cast<unsigned long long>(s.particleMeshes),
        static_cast<unsigned long long>(s.standInsCutOff));
  return text;
}

}  // namespace imps::app
