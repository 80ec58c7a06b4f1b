// SPDX-License-Identifier: MIT
// A render host's side of the OSC streaming test (tests/puppeteer/osc_stream_test.sh): listens for pose frames with
// drivers::OscReceiver in a process of its own, writes its port to READY_FILE once bound, and receives until the
// stream has been idle for IDLE_MS after its first frame (or 60 s pass). Prints one line:
//   received N first F last L dropped D out_of_order O malformed M late T latency_median_us X latency_p99_us Y
// Latency is sender → receiver: arrival minus the bundle's send time (both processes on one host share the steady
// clock). Exit 0 when every frame from 0 to L arrived, in order, and exactly MALFORMED datagrams (default 0) were
// malformed; 1 otherwise.
// Usage: osc_receive_check READY_FILE [IDLE_MS [MALFORMED]]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "drivers/osc_receiver.h"

using namespace imps::drivers;

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: osc_receive_check READY_FILE [IDLE_MS [MALFORMED]]\n");
    return 2;
  }
  const int idleMs = argc >= 3 ? std::atoi(argv[2]) : 1500;
  const uint64_t expectedMalformed = argc == 4 ? std::strtoull(argv[3], nullptr, 10) : 0;
  std::mutex mutex;
  std::vector<uint32_t> frames;
  std::vector<int64_t> transitNs;
  OscReceiverOptions options;
  options.onPose = [&](const OscPose& p) {
    std::lock_guard lock(mutex);
    frames.push_back(p.frame);
    transitNs.push_back(p.arrivalTimeNs - p.sentTimeNs);
  };
  PoseMailbox channels;
  auto receiver = OscReceiver::open(options, channels);
  if (!receiver) {
    std::fprintf(stderr, "%s\n", errorText(receiver.error()).c_str());
    return 1;
  }
  (*receiver)->start();
  {
    std::ofstream ready(std::string(argv[1]) + ".tmp");
    ready << (*receiver)->port() << "\n";
  }
  std::rename((std::string(argv[1]) + ".tmp").c_str(), argv[1]);

  const auto start = std::chrono::steady_clock::now();
  auto lastChange = start;
  size_t seen = 0;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const auto now = std::chrono::steady_clock::now();
    size_t n;
    {
      std::lock_guard lock(mutex);
      n = frames.size();
    }
    if (n != seen) seen = n, lastChange = now;
    if (seen > 0 && now - lastChange > std::chrono::milliseconds(idleMs)) break;
    if (now - start > std::chrono::seconds(60)) break;
  }
  (*receiver)->stop();
  const OscReceiverStats s = (*receiver)->stats();
  std::vector<int64_t> sorted = transitNs;
  std::sort(sorted.begin(), sorted.end());
  auto at = [&](double q) {
    return sorted.empty() ? -1.0 : double(sorted[size_t(q * double(sorted.size() - 1))]) * 1e-3;
  };
  const uint32_t first = frames.empty() ? 0 : frames.front(), last = frames.empty() ? 0 : frames.back();
  std::printf("received %zu first %u last %u dropped %llu out_of_order %llu malformed %llu late %llu "
              "latency_median_us %.1f latency_p99_us %.1f\n",
              frames.size(), first, last, static_cast<unsigned long long>(s.dropped),
              static_cast<unsigned long long>(s.outOfOrder), static_cast<unsigned long long>(s.malformed),
              static_cast<unsigned long long>(s.late), at(0.5), at(0.99));
  bool ok = !frames.empty() && first == 0 && s.malformed == expectedMalformed && s.outOfOrder == 0 && s.dropped == 0;
  for (size_t i = 0; ok && i < frames.size(); ++i) ok = frames[i] == uint32_t(i);
  if (!ok) std::printf("FAIL: frames missing, out of order or malformed\n");
  return ok ? 0 : 1;
}
