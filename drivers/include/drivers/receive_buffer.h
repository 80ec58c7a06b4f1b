// SPDX-License-Identifier: MIT
// The bytes a decoder has received and not yet consumed, shared by the binary and line protocol decoders.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace imps::drivers {

// Bytes are appended at the end and consumed from the front. Consumed bytes are dropped (the rest moved to the
// front) only when new bytes arrive, so once the buffer has grown to its working size nothing is allocated.
// Positions are indices into data(), valid until the next append(). Not thread-safe (one decoder owns it).
class ReceiveBuffer {
 public:
  void reserve(size_t bytes) { buf_.reserve(bytes); }

  // Drops the consumed bytes, then appends `bytes`.
  void append(std::span<const uint8_t> bytes) {
    if (pos_ > 0) {
      if (end_ > pos_) std::memmove(buf_.data(), buf_.data() + pos_, end_ - pos_);
      end_ -= pos_;
      pos_ = 0;
    }
    if (buf_.size() < end_ + bytes.size()) buf_.resize(end_ + bytes.size());
    if (!bytes.empty()) std::memcpy(buf_.data() + end_, bytes.data(), bytes.size());
    end_ += bytes.size();
  }

  const uint8_t* data() const { return buf_.data(); }
  size_t begin() const { return pos_; }  // first unconsumed byte
  size_t end() const { return end_; }    // one past the last received byte
  size_t size() const { return end_ - pos_; }
  void consume(size_t n) { pos_ += n; }
  void clear() { pos_ = end_ = 0; }

 private:
  std::vector<uint8_t> buf_;
  size_t pos_ = 0;
  size_t end_ = 0;
};

}  // namespace imps::drivers
