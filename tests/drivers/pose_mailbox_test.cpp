// SPDX-License-Identifier: MIT
// Tests for drivers/pose_mailbox: newest-wins hand-off, in-order queue, counters, sample age, and no torn samples
// between a producer and consumers running concurrently.
#include "drivers/pose_mailbox.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <limits>
#include <thread>

namespace imps::drivers {
namespace {

// A sample whose every field derives from its sequence, so a torn copy is detectable.
Sample stamped(uint32_t sequence, int64_t arrivalTimeNs = 0) {
  Sample s;
  s.sequence = sequence;
  s.deviceTimeNs = static_cast<int64_t>(sequence) * 7;
  s.arrivalTimeNs = arrivalTimeNs;
  s.channelCount = kMaxChannels;
  s.counts.fill(sequence);
  s.flags.fill(static_cast<ChannelFlag>(sequence % 3));
  return s;
}

PoseMailboxOptions withQueue(size_t capacity) {
  PoseMailboxOptions options;
  options.queueCapacity = capacity;
  return options;
}

bool whole(const Sample& s) {
  if (s.channelCount != kMaxChannels || s.deviceTimeNs != static_cast<int64_t>(s.sequence) * 7) return false;
  for (int i = 0; i < kMaxChannels; ++i)
    if (s.counts[i] != s.sequence || s.flags[i] != static_cast<ChannelFlag>(s.sequence % 3)) return false;
  return true;
}

TEST(PoseMailbox, NewestWinsAndIsTakenOnce) {
  PoseMailbox box;
  Sample out = stamped(99);
  EXPECT_FALSE(box.latest(out));
  EXPECT_EQ(out, stamped(99));  // untouched
  EXPECT_FALSE(box.takeNewest());

  box.publish(stamped(1));
  auto got = box.takeNewest();
  ASSERT_TRUE(got);
  EXPECT_EQ(*got, stamped(1));
  EXPECT_FALSE(box.takeNewest());

  box.publish(stamped(2));
  box.publish(stamped(3));
  box.publish(stamped(4));
  ASSERT_TRUE(box.latest(out));
  EXPECT_EQ(out, stamped(4));
  EXPECT_FALSE(box.latest(out));

  box.publish(stamped(5));
  const auto s = box.stats();
  EXPECT_EQ(s.published, 5u);
  EXPECT_EQ(s.consumed, 2u);
  EXPECT_EQ(s.overwritten, 2u);  // 2 and 3 were never seen
  EXPECT_EQ(s.published, s.consumed + s.overwritten + 1);  // 5 is pending
  EXPECT_EQ(box.queueCapacity(), 0u);
  std::vector<Sample> drained;
  EXPECT_FALSE(box.drain(drained));
}

TEST(PoseMailbox, AgeIsMeasuredOnTheInjectedClock) {
  ManualClock clock(0);
  PoseMailbox box({.queueCapacity = 0, .clock = &clock});
  box.publish(stamped(1, 1000));
  clock.set(1500);
  ASSERT_TRUE(box.takeNewest());
  EXPECT_EQ(box.stats().lastAgeNs, 500);
  box.publish(stamped(2, 1600));
  clock.set(1800);
  ASSERT_TRUE(box.takeNewest());
  box.publish(stamped(3, 5000));  // arrival after "now": age clamps to 0
  ASSERT_TRUE(box.takeNewest());
  const auto s = box.stats();
  EXPECT_EQ(s.lastAgeNs, 0);
  EXPECT_EQ(s.maxAgeNs, 500);
  EXPECT_EQ(s.totalAgeNs, 700);
  EXPECT_EQ(s.consumed, 3u);
}

// Stamps from another clock or from long ago (a replayed session's come from its file): the age and its sum saturate
// instead of overflowing (undefined behaviour, which UBSan found in make test-sanitize when the concurrent test below
// summed ages of samples stamped 0 on a machine up for hours).
TEST(PoseMailbox, AgesSaturateInsteadOfOverflowing) {
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max(), kMin = std::numeric_limits<int64_t>::min();
  ManualClock clock(kMax);
  PoseMailbox box({.queueCapacity = 0, .clock = &clock});
  box.publish(stamped(1, kMin));  // now - arrival would be 2^64 - 1
  ASSERT_TRUE(box.takeNewest());
  EXPECT_EQ(box.stats().lastAgeNs, kMax);
  box.publish(stamped(2, kMax / 2));
  ASSERT_TRUE(box.takeNewest());
  box.publish(stamped(3, -1));  // an age of exactly 2^63: one more than the largest
  ASSERT_TRUE(box.takeNewest());
  const auto s = box.stats();
  EXPECT_EQ(s.lastAgeNs, kMax);
  EXPECT_EQ(s.maxAgeNs, kMax);
  EXPECT_EQ(s.totalAgeNs, kMax);
  EXPECT_EQ(s.consumed, 3u);
}

TEST(PoseMailbox, QueueKeepsOrderAndCountsOverflow) {
  PoseMailbox box(withQueue(5));
  EXPECT_EQ(box.queueCapacity(), 8u);  // rounded up to a power of two
  for (uint32_t q = 0; q < 8; ++q) box.publish(stamped(q));
  std::vector<Sample> out;
  ASSERT_TRUE(box.drain(out, 3));
  ASSERT_EQ(out.size(), 3u);
  ASSERT_TRUE(box.drain(out));
  ASSERT_EQ(out.size(), 8u);
  for (uint32_t q = 0; q < 8; ++q) EXPECT_EQ(out[q], stamped(q));
  EXPECT_FALSE(box.drain(out));

  // Full: later samples are not queued (the producer never waits), earlier ones are kept.
  for (uint32_t q = 8; q < 20; ++q) box.publish(stamped(q));
  out.clear();
  ASSERT_TRUE(box.drain(out));
  ASSERT_EQ(out.size(), 8u);
  for (uint32_t i = 0; i < 8; ++i) EXPECT_EQ(out[i].sequence, 8 + i);
  auto s = box.stats();
  EXPECT_EQ(s.queueOverflows, 4u);
  EXPECT_EQ(s.queued, 16u);
  EXPECT_EQ(s.drained, 16u);
  EXPECT_EQ(s.published, 20u);
  // The newest path is independent of the queue.
  EXPECT_EQ(box.takeNewest()->sequence, 19u);
}

constexpr uint32_t kConcurrentSamples = 1'000'000;

TEST(PoseMailbox, ConcurrentNewestConsumerNeverSeesATornOrOlderSample) {
  PoseMailbox box;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (uint32_t q = 1; q <= kConcurrentSamples; ++q) box.publish(stamped(q));
    done.store(true, std::memory_order_release);
  });
  uint64_t seen = 0, torn = 0, backwards = 0;
  uint32_t last = 0;
  Sample s;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    while (box.latest(s)) {
      ++seen;
      if (!whole(s)) ++torn;
      if (s.sequence <= last) ++backwards;
      last = s.sequence;
    }
    if (finished) break;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kConcurrentSamples);  // the very last sample is always delivered
  const auto st = box.stats();
  EXPECT_EQ(st.published, kConcurrentSamples);
  EXPECT_EQ(st.consumed, seen);
  EXPECT_EQ(st.consumed + st.overwritten, st.published);
  EXPECT_GT(seen, 1u);
}

TEST(PoseMailbox, ConcurrentDrainSeesEverySampleInOrderWhenItKeepsUp) {
  PoseMailbox box(withQueue(4096));
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (uint32_t q = 0; q < kConcurrentSamples; ++q) {
      // Pace the producer as a device would, so the recorder keeps up (the mailbox itself never waits).
      while (box.stats().queued - box.stats().drained > 2048) std::this_thread::yield();
      box.publish(stamped(q));
    }
    done.store(true, std::memory_order_release);
  });
  // Meanwhile a newest-consumer runs too (on this thread, interleaved with the recorder).
  std::vector<Sample> batch;
  uint64_t next = 0, torn = 0, outOfOrder = 0, newestTorn = 0;
  Sample newest;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    if (box.latest(newest) && !whole(newest)) ++newestTorn;
    batch.clear();
    box.drain(batch);
    for (const auto& s : batch) {
      if (!whole(s)) ++torn;
      if (s.sequence != next) ++outOfOrder;
      next = s.sequence + 1;
    }
    if (finished && batch.empty()) break;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(newestTorn, 0u);
  EXPECT_EQ(outOfOrder, 0u);
  EXPECT_EQ(next, kConcurrentSamples);
  const auto st = box.stats();
  EXPECT_EQ(st.queueOverflows, 0u);
  EXPECT_EQ(st.drained, kConcurrentSamples);
}

TEST(PoseMailbox, ConcurrentSlowDrainCountsOverflowAndNeverBlocksTheProducer) {
  PoseMailbox box(withQueue(64));
  constexpr uint32_t kSamples = 200'000;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (uint32_t q = 0; q < kSamples; ++q) box.publish(stamped(q));
    done.store(true, std::memory_order_release);
  });
  std::vector<Sample> all;
  for (;;) {
    const bool finished = done.load(std::memory_order_acquire);
    const size_t before = all.size();
    box.drain(all, 16);
    for (size_t i = before; i < all.size(); ++i) EXPECT_TRUE(whole(all[i]));
    if (finished && all.size() == before) break;
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
  producer.join();
  const auto st = box.stats();
  EXPECT_EQ(st.published, kSamples);
  EXPECT_GT(st.queueOverflows, 0u);
  EXPECT_EQ(st.queued + st.queueOverflows, st.published);
  EXPECT_EQ(st.drained, st.queued);
  EXPECT_EQ(all.size(), st.drained);
  // In order, and the gaps in the drained sequence add up to the overflow count.
  uint64_t missing = 0;
  for (size_t i = 1; i < all.size(); ++i) {
    ASSERT_GT(all[i].sequence, all[i - 1].sequence);
    missing += all[i].sequence - all[i - 1].sequence - 1;
  }
  missing += all.front().sequence + (kSamples - 1 - all.back().sequence);
  EXPECT_EQ(missing, st.queueOverflows);
}

}  // namespace
}  // namespace imps::drivers
