// SPDX-License-Identifier: MIT
// Benchmarks for OSC pose streaming (docs/osc.md) over loopback: the decoder's cost per pose, poses per second
// sustained sender → receiver, and the latency streaming adds at 1 kHz (issue 13's goal: < 1 ms median), measured
// from the frame loop's send() to the receiver's publish.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/osc_receiver.h"
#include "drivers/osc_sender.h"
#include "imps/clock.h"

namespace {

using namespace imps::drivers;
using imps::steadyNowNs;

// The simple biped's 19 joints with a plausible pose.
std::unique_ptr<OscPose> bipedPose() {
  static const char* names[] = {"Pelvis",     "Spine",      "Chest",      "Neck",       "Head",
                                "L_Clavicle", "L_UpperArm", "L_Forearm",  "L_Hand",     "R_Clavicle",
                                "R_UpperArm", "R_Forearm",  "R_Hand",     "L_Thigh",    "L_Calf",
                                "L_Foot",     "R_Thigh",    "R_Calf",     "R_Foot"};
  auto p = std::make_unique<OscPose>();
  for (int i = 0; i < 19; ++i) {
    std::strcpy(p->joints[i].name.data(), names[i]);
    p->joints[i].w = 0.9f, p->joints[i].x = 0.1f * float(i % 3), p->joints[i].y = 0.2f, p->joints[i].z = -0.1f;
  }
  p->jointCount = 19;
  p->hasRoot = true;
  p->root = {0.0f, 0.97f, 0.0f};
  return p;
}

void BM_OscDecodePose(benchmark::State& state) {
  const std::vector<uint8_t> packet = encodeOscPose(*bipedPose());
  auto out = std::make_unique<OscPose>();
  Sample channels;
  for (auto _ : state) {
    auto r = decodeOscPacket(packet, 1, *out, channels);
    benchmark::DoNotOptimize(r);
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(packet.size()));
  state.counters["bytes_per_pose"] = double(packet.size());
}
BENCHMARK(BM_OscDecodePose);

// Sender and receiver in one process, over loopback UDP.
struct Link {
  PoseMailbox mailbox;
  std::mutex mutex;
  std::vector<int64_t> latencyNs;  // receiver publish − send() call, per pose
  std::unique_ptr<OscReceiver> receiver;
  std::unique_ptr<OscPoseSender> sender;
  explicit Link(size_t reserve) {
    latencyNs.reserve(reserve);
    OscReceiverOptions o;
    o.host = "127.0.0.1";
    o.onPose = [this](const OscPose& p) {
      const int64_t now = steadyNowNs();
      std::lock_guard lock(mutex);
      latencyNs.push_back(now - p.sampleTimeNs);
    };
    receiver = std::move(*OscReceiver::open(o, mailbox));
    receiver->start();
    sender = std::move(*OscPoseSender::open({"osc.udp://127.0.0.1:" + std::to_string(receiver->port())}, 256));
  }
  size_t received() {
    std::lock_guard lock(mutex);
    return latencyNs.size();
  }
  void settle(size_t expected) {
    const int64_t until = steadyNowNs() + 2'000'000'000;
    while (received() < expected && steadyNowNs() < until) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
};

// As many poses as the link carries: the producer retries while the sender's queue is full.
void BM_OscSustainedPosesPerSecond(benchmark::State& state) {
  const size_t poses = 20'000;
  auto pose = bipedPose();
  for (auto _ : state) {
    Link link(poses);
    const int64_t start = steadyNowNs();
    for (size_t i = 0; i < poses; ++i) {
      pose->sampleTimeNs = steadyNowNs();
      while (!link.sender->send(*pose)) std::this_thread::yield();
    }
    link.settle(poses);
    const double seconds = double(steadyNowNs() - start) * 1e-9;
    state.counters["poses_per_s"] = double(link.received()) / seconds;
    state.counters["lost_in_kernel"] = double(poses - link.received());
  }
}
BENCHMARK(BM_OscSustainedPosesPerSecond)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// One pose per millisecond for two seconds, as a 1 kHz armature host would send them.
void BM_OscLatencyAt1kHz(benchmark::State& state) {
  const size_t poses = 2000;
  auto pose = bipedPose();
  for (auto _ : state) {
    Link link(poses);
    auto next = std::chrono::steady_clock::now();
    for (size_t i = 0; i < poses; ++i) {
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
      pose->sampleTimeNs = steadyNowNs();
      link.sender->send(*pose);
    }
    link.settle(poses);
    std::vector<int64_t> l;
    {
      std::lock_guard lock(link.mutex);
      l = link.latencyNs;
    }
    std::sort(l.begin(), l.end());
    auto at = [&](double q) { return l.empty() ? -1.0 : double(l[size_t(q * double(l.size() - 1))]) * 1e-3; };
    state.counters["median_us"] = at(0.5);
    state.counters["p99_us"] = at(0.99);
    state.counters["max_us"] = at(1.0);
    state.counters["received"] = double(l.size());
    state.counters["dropped"] = double(link.sender->stats().dropped);
  }
}
BENCHMARK(BM_OscLatencyAt1kHz)->Iterations(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
