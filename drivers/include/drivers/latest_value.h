// SPDX-License-Identifier: MIT
// A wait-free single-producer single-consumer "newest value" hand-off (a triple buffer) for values too large or too
// different for the PoseMailbox's Sample slots: the OSC receiver's pose frames.
#pragma once

#include <atomic>
#include <cstdint>

namespace imps::drivers {

// One producer thread calls publish(), one consumer thread calls take(). Both are wait-free (no locks, no
// allocation, a bounded number of steps); the consumer never sees a torn value. The same protocol as PoseMailbox's
// newest-sample slots (drivers/pose_mailbox.h). `T` must be copy-assignable; copies happen on the calling thread.
template <class T>
class LatestValue {
 public:
  // Producer: makes `value` the newest. Returns true when it replaced a newer-than-taken value the consumer never
  // saw (an overwrite).
  bool publish(const T& value) {
    slots_[back_].value = value;
    const uint8_t previous = state_.exchange(static_cast<uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = previous & kIndexMask;
    return (previous & kFresh) != 0;
  }
  // Consumer: when a value was published since the last take, copies the newest into `out` and returns true;
  // otherwise leaves `out` alone and returns false.
  bool take(T& out) {
    if ((state_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    const uint8_t previous = state_.exchange(front_, std::memory_order_acq_rel);
    front_ = previous & kIndexMask;
    out = slots_[front_].value;
    return true;
  }

 private:
  static constexpr uint8_t kFresh = 0x4;
  static constexpr uint8_t kIndexMask = 0x3;
  struct alignas(64) Slot {
    T value{};
  };
  Slot slots_[3];
  alignas(64) std::atomic<uint8_t> state_{1};
  uint8_t back_ = 0;
  alignas(64) uint8_t front_ = 2;
};

}  // namespace imps::drivers
