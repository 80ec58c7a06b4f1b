// SPDX-License-Identifier: MIT
// A recorded take's samples, stored compactly. drivers::Sample is a fixed 350-byte record (room for kMaxChannels
// counts and flags, so it can cross the lock-free mailbox); a take of 3-channel samples held that way takes ~10x
// its file size in memory. SampleTable keeps a 32-byte header per sample and only the channelCount counts and
// flags the sample has, so a session in memory is about its size on disk. Reads return Samples by value with the
// counts and flags beyond channelCount zero, exactly as they were appended (channelCount <= kMaxChannels).
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <vector>

#include "drivers/sample.h"

namespace imps::sim {

class SampleTable {
 public:
  class const_iterator {
   public:
    using iterator_category = std::random_access_iterator_tag;
    using value_type = drivers::Sample;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = drivers::Sample;
    const_iterator() = default;
    const_iterator(const SampleTable* table, size_t index) : table_(table), index_(index) {}
    drivers::Sample operator*() const { return (*table_)[index_]; }
    const_iterator& operator++() { return ++index_, *this; }
    const_iterator operator++(int) { auto old = *this; ++index_; return old; }
    difference_type operator-(const const_iterator& o) const {
      return difference_type(index_) - difference_type(o.index_);
    }
    bool operator==(const const_iterator& o) const { return index_ == o.index_; }
   private:
    const SampleTable* table_ = nullptr;
    size_t index_ = 0;
  };

  size_t size() const { return headers_.size(); }
  bool empty() const { return headers_.empty(); }
  void reserve(size_t samples) { headers_.reserve(samples); }
  void clear() { headers_.clear(), counts_.clear(), flags_.clear(); }
  // Gives back the growth slack once a table is complete (readSession does).
  void shrink_to_fit() { headers_.shrink_to_fit(), counts_.shrink_to_fit(), flags_.shrink_to_fit(); }
  void push_back(const drivers::Sample& sample);
  // Requires i < size().
  drivers::Sample operator[](size_t i) const;
  drivers::Sample front() const { return (*this)[0]; }
  drivers::Sample back() const { return (*this)[size() - 1]; }
  // Header fields without building a whole Sample (the link analysis and replay pacing read only these).
  int64_t arrivalTimeNs(size_t i) const { return headers_[i].arrivalTimeNs; }
  int64_t deviceTimeNs(size_t i) const { return headers_[i].deviceTimeNs; }
  uint32_t sequence(size_t i) const { return headers_[i].sequence; }
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }
  // Heap bytes in use (what `info` reports as the take's memory).
  size_t bytes() const;
  bool operator==(const SampleTable&) const = default;

 private:
  struct Header {
    int64_t deviceTimeNs = 0;
    int64_t arrivalTimeNs = 0;
    uint64_t first = 0;  // index of the sample's first count in counts_ (and flag in flags_)
    uint32_t sequence = 0;
    uint16_t channelCount = 0;
    bool operator==(const Header&) const = default;
  };
  std::vector<Header> headers_;
  std::vector<uint32_t> counts_;
  std::vector<drivers::ChannelFlag> flags_;
};

}  // namespace imps::sim
