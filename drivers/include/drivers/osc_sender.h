// SPDX-License-Identifier: MIT
// Streaming pose frames as OSC bundles over UDP to one or more `osc.udp://HOST:PORT` targets (docs/osc.md), through
// liblo, on the sender's own thread so the frame loop never waits for the network.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <expected>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "drivers/osc_codec.h"
#include "imps/diagnostic.h"

namespace imps::drivers {

// Checks an OSC target URL: `osc.udp://HOST:PORT` with a non-empty host and a port in 1..65535. The error is one
// diagnostic at `file`:1:COLUMN, COLUMN 1-based into `url` (printed "osc:1:COLUMN: error: what was expected").
// Does not resolve the host.
std::expected<void, Diagnostics> checkOscTargetUrl(std::string_view url, std::string file = "osc");

// The bundle liblo sends for `pose` (docs/osc.md): its bytes, for tests and the decoder's seed files.
std::vector<uint8_t> encodeOscPose(const OscPose& pose);

// Counters since construction; each field read atomically, not one consistent snapshot.
struct OscSenderStats {
  uint64_t offered = 0;     // send() calls (= frame counters handed out)
  uint64_t sent = 0;        // bundles sent, per target (a frame to two targets counts 2)
  uint64_t dropped = 0;     // frames not sent because the queue was full (the receivers see a frame-counter gap)
  uint64_t sendErrors = 0;  // liblo send failures (per target)
};

// One sender thread and its queue. Thread-safety: send() from one producer thread only (the frame loop); stats()
// and lastError() from any thread; construct and destroy on the controlling thread.
class OscPoseSender {
 public:
  // Checks every target URL, makes its liblo address and starts the thread. `queueCapacity` (rounded up to a power
  // of two) frames may wait to be sent. Error: one diagnostic for the first URL that is wrong, printed
  // "URL: osc:1:COLUMN: error: …" (checkOscTargetUrl) or "URL: error: …" (liblo cannot use it).
  static std::expected<std::unique_ptr<OscPoseSender>, Diagnostics> open(const std::vector<std::string>& urls,
                                                                         size_t queueCapacity = 64);
  ~OscPoseSender();  // sends what is queued, then stops and joins
  OscPoseSender(const OscPoseSender&) = delete;
  OscPoseSender& operator=(const OscPoseSender&) = delete;

  // Queues `pose` for every target, stamping the next frame counter (0, 1, 2 …) into the copy; sentTimeNs is
  // stamped on the sender thread just before sending. Wait-free: never blocks, never allocates; when the queue is
  // full the frame is dropped (counted; its frame counter is still used, so receivers see the gap). Returns
  // whether the frame was queued.
  bool send(const OscPose& pose);

  // Waits until every frame queued so far has been sent, or timeoutMs passes; returns whether the queue emptied.
  // For the end of a performance (a summary that counts every frame), never for the frame loop.
  bool flush(int timeoutMs);

  OscSenderStats stats() const;
  std::string lastError() const;  // the latest send failure, "" when none
  const std::vector<std::string>& targets() const { return urls_; }

 private:
  struct Targets;  // liblo addresses (sender thread only)
  OscPoseSender(std::vector<std::string> urls, std::unique_ptr<Targets> targets, size_t queueCapacity);
  void run();

  std::vector<std::string> urls_;
  std::unique_ptr<Targets> targets_;
  std::vector<OscPose> ring_;
  size_t mask_ = 0;
  uint32_t nextFrame_ = 0;  // producer's
  alignas(64) std::atomic<uint64_t> head_{0};
  alignas(64) std::atomic<uint64_t> tail_{0};
  std::atomic<bool> stop_{false};
  alignas(64) std::atomic<uint32_t> wake_{0};  // bumped by send() and the destructor; the sender thread sleeps on it
  alignas(64) std::atomic<uint64_t> offered_{0}, dropped_{0};
  alignas(64) std::atomic<uint64_t> sent_{0}, sendErrors_{0};
  mutable std::mutex errorMutex_;  // guards lastError_ (the sender thread writes it; send() never touches it)
  std::string lastError_;
  std::thread thread_;
};

}  // namespace imps::drivers
