// SPDX-License-Identifier: MIT
// The pose mailbox: triple buffer for the newest sample, SPSC ring for the in-order queue, and their counters.
#include "drivers/pose_mailbox.h"

#include <algorithm>
#include <bit>
#include <chrono>
#include <limits>

namespace imps::drivers {

static_assert(std::atomic<uint8_t>::is_always_lock_free);
static_assert(std::atomic<uint64_t>::is_always_lock_free);
static_assert(std::atomic<int64_t>::is_always_lock_free);

namespace {
// Counters are written by one thread each, so a relaxed load + store is enough (and cheaper than an RMW).
template <class T>
void bump(std::atomic<T>& counter, T by = 1) {
  counter.store(counter.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

// now - arrival: 0 for a sample stamped after now, and at most the largest int64_t. A sample stamped on another clock
// or long ago (a replayed session's stamps come from its file) must not overflow the age or its sum.
constexpr int64_t kMaxAge = std::numeric_limits<int64_t>::max();
int64_t ageNs(int64_t now, int64_t arrival) {
  if (arrival >= now) return 0;
  const uint64_t age = uint64_t(now) - uint64_t(arrival);  // the exact difference: now > arrival
  return age > uint64_t(kMaxAge) ? kMaxAge : int64_t(age);
}
}  // namespace

PoseMailbox::PoseMailbox(PoseMailboxOptions options) : clock_(options.clock) {
  if (options.queueCapacity > 0) {
    ring_.resize(std::bit_ceil(options.queueCapacity));
    mask_ = ring_.size() - 1;
  }
}

int64_t PoseMailbox::now() const { return clock_ ? clock_->nowNs() : steadyNowNs(); }

void PoseMailbox::publish(const Sample& sample) {
  // Newest: fill the back slot, then swap it with the middle. acq_rel: release publishes the slot's contents,
  // acquire makes sure the consumer has finished reading the slot we get back before we overwrite it.
  slots_[back_].sample = sample;
  const uint8_t previous = state_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
  back_ = previous & kIndexMask;
  if (previous & kFresh) bump(overwritten_);
  bump(published_);

  // In order: never wait for the queue consumer; a full ring drops this sample from the queue only.
  if (!ring_.empty()) {
    const uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - cachedTail_ >= ring_.size()) cachedTail_ = tail_.load(std::memory_order_acquire);
    if (head - cachedTail_ >= ring_.size()) {
      bump(queueOverflows_);
    } else {
      ring_[head & mask_] = sample;
      head_.store(head + 1, std::memory_order_release);
      bump(queued_);
    }
  }
}

bool PoseMailbox::latest(Sample& out) {
  if ((state_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
  // Only this thread clears kFresh, so the exchange is guaranteed to return a fresh middle slot.
  const uint8_t previous = state_.exchange(front_, std::memory_order_acq_rel);
  front_ = previous & kIndexMask;
  out = slots_[front_].sample;

  const int64_t age = ageNs(now(), out.arrivalTimeNs);
  bump(consumed_);
  lastAgeNs_.store(age, std::memory_order_relaxed);
  if (age > maxAgeNs_.load(std::memory_order_relaxed)) maxAgeNs_.store(age, std::memory_order_relaxed);
  const int64_t total = totalAgeNs_.load(std::memory_order_relaxed);  // saturating, as the ages themselves
  totalAgeNs_.store(age > kMaxAge - total ? kMaxAge : total + age, std::memory_order_relaxed);
  return true;
}

std::optional<Sample> PoseMailbox::takeNewest() {
  std::optional<Sample> out(std::in_place);
  if (!latest(*out)) out.reset();
  return out;
}

bool PoseMailbox::drain(std::vector<Sample>& out, size_t maxSamples) {
  if (ring_.empty()) return false;
  const uint64_t tail = tail_.load(std::memory_order_relaxed);
  const uint64_t head = head_.load(std::memory_order_acquire);
  const uint64_t n = std::min<uint64_t>(head - tail, maxSamples);
  if (n == 0) return false;
  for (uint64_t i = 0; i < n; ++i) out.push_back(ring_[(tail + i) & mask_]);
  tail_.store(tail + n, std::memory_order_release);
  bump(drained_, n);
  return true;
}

PoseMailboxStats PoseMailbox::stats() const {
  PoseMailboxStats s;
  s.published = published_.load(std::memory_order_relaxed);
  s.consumed = consumed_.load(std::memory_order_relaxed);
  s.overwritten = overwritten_.load(std::memory_order_relaxed);
  s.queued = queued_.load(std::memory_order_relaxed);
  s.drained = drained_.load(std::memory_order_relaxed);
  s.queueOverflows = queueOverflows_.load(std::memory_order_relaxed);
  s.lastAgeNs = lastAgeNs_.load(std::memory_order_relaxed);
  s.maxAgeNs = maxAgeNs_.load(std::memory_order_relaxed);
  s.totalAgeNs = totalAgeNs_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace imps::drivers
