// SPDX-License-Identifier: MIT
// The lock-free hand-off of Samples from a device I/O thread to the frame loop (newest wins, via a triple buffer)
// and, optionally, to a recorder (every sample in order, via a bounded single-producer single-consumer ring).
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "imps/clock.h"
#include "drivers/sample.h"

namespace imps::drivers {

struct PoseMailboxOptions {
  // Capacity of the in-order queue behind drain(), rounded up to a power of two; 0 disables the queue.
  size_t queueCapacity = 0;
  // Host clock in nanoseconds, the clock Sample::arrivalTimeNs is on; used for the sample age at consumption.
  // Null: steadyNowNs. Inject a fake for deterministic tests and replays; it must outlive the mailbox and be safe
  // to read from the consuming thread.
  Clock* clock = nullptr;
};

// A snapshot of the counters; each field is read atomically but the fields are not one consistent snapshot.
struct PoseMailboxStats {
  uint64_t published = 0;    // publish() calls
  uint64_t consumed = 0;     // samples handed out by latest()/takeNewest()
  uint64_t overwritten = 0;  // samples replaced by a newer one before the newest-consumer took them
  uint64_t queued = 0;       // samples put into the in-order queue
  uint64_t drained = 0;      // samples handed out by drain()
  uint64_t queueOverflows = 0;  // samples not queued because the queue was full (the recorder will see a gap)
  // Age = clock() - Sample::arrivalTimeNs when latest()/takeNewest() hands a sample out (negative ages count as 0;
  // ages and their sum saturate at the largest int64_t rather than overflow).
  int64_t lastAgeNs = 0;
  int64_t maxAgeNs = 0;
  int64_t totalAgeNs = 0;  // sum over consumed samples; mean = totalAgeNs / consumed
};

// Single-producer hand-off of Samples. Thread-safety contract:
//  * publish() is called from one producer thread only (the device session's I/O thread).
//  * latest() and takeNewest() are called from one "newest" consumer thread only (the frame loop).
//  * drain() is called from one "queue" consumer thread only (the recorder); it may be the newest consumer.
//  * stats() and queueCapacity() may be called from any thread.
// publish(), latest() and takeNewest() are wait-free: no locks, no allocation, no blocking, a bounded number of
// steps; the producer never waits for a consumer. A consumer never observes a torn sample: each Sample returned
// was published whole by one publish() call. Construction and destruction are not concurrent with anything.
class PoseMailbox {
 public:
  explicit PoseMailbox(PoseMailboxOptions options = {});
  PoseMailbox(const PoseMailbox&) = delete;
  PoseMailbox& operator=(const PoseMailbox&) = delete;

  // Producer: makes `sample` the newest (replacing an unread newer-than-taken one, counted as overwritten) and
  // appends it to the queue when there is one (when full the sample is not queued and queueOverflows grows).
  void publish(const Sample& sample);

  // Newest consumer: if a sample was published since the last take, copies the newest into `out` and returns
  // true; otherwise leaves `out` untouched and returns false (keep showing the pose you have).
  bool latest(Sample& out);
  // Newest consumer: the newest sample published since the last take, or nullopt.
  std::optional<Sample> takeNewest();

  // Queue consumer: appends every queued sample, oldest first, to `out` (at most maxSamples of them); returns
  // true when it appended any. Allocation, if any, happens in `out` on the consumer's side.
  bool drain(std::vector<Sample>& out, size_t maxSamples = SIZE_MAX);

  PoseMailboxStats stats() const;
  size_t queueCapacity() const { return ring_.size(); }

 private:
  int64_t now() const;

  // Triple buffer: the producer owns slots_[back_], the consumer owns slots_[front_], and state_ holds the
  // index of the middle slot plus kFresh when it holds a sample the consumer has not taken.
  static constexpr uint8_t kFresh = 0x4;
  static constexpr uint8_t kIndexMask = 0x3;
  struct alignas(64) Slot {
    Sample sample;
  };
  Slot slots_[3];
  alignas(64) std::atomic<uint8_t> state_{1};  // middle = slot 1, nothing fresh
  uint8_t back_ = 0;                           // producer's
  alignas(64) uint8_t front_ = 2;              // newest consumer's

  // SPSC ring: head_ written by the producer, tail_ by the queue consumer; indices grow without wrapping.
  std::vector<Sample> ring_;
  size_t mask_ = 0;
  alignas(64) std::atomic<uint64_t> head_{0};
  uint64_t cachedTail_ = 0;  // producer's view of tail_
  alignas(64) std::atomic<uint64_t> tail_{0};

  // Counters, grouped by the thread that writes them.
  alignas(64) std::atomic<uint64_t> published_{0}, overwritten_{0}, queued_{0}, queueOverflows_{0};
  alignas(64) std::atomic<uint64_t> consumed_{0};
  std::atomic<int64_t> lastAgeNs_{0}, maxAgeNs_{0}, totalAgeNs_{0};
  alignas(64) std::atomic<uint64_t> drained_{0};

  Clock* clock_;  // null: steadyNowNs
};

}  // namespace imps::drivers
