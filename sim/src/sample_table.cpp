// SPDX-License-Identifier: MIT
#include "sim/sample_table.h"

#include <algorithm>

namespace imps::sim {

void SampleTable::push_back(const drivers::Sample& sample) {
  const uint16_t n = std::min<uint16_t>(sample.channelCount, drivers::kMaxChannels);
  headers_.push_back({sample.deviceTimeNs, sample.arrivalTimeNs, counts_.size(), sample.sequence, sample.channelCount});
  counts_.insert(counts_.end(), sample.counts.begin(), sample.counts.begin() + n);
  flags_.insert(flags_.end(), sample.flags.begin(), sample.flags.begin() + n);
}

drivers::Sample SampleTable::operator[](size_t i) const {
  const Header& h = headers_[i];
  drivers::Sample s;
  s.sequence = h.sequence;
  s.deviceTimeNs = h.deviceTimeNs;
  s.arrivalTimeNs = h.arrivalTimeNs;
  s.channelCount = h.channelCount;
  const size_t n = std::min<size_t>(h.channelCount, drivers::kMaxChannels);
  std::copy_n(counts_.begin() + std::ptrdiff_t(h.first), n, s.counts.begin());
  std::copy_n(flags_.begin() + std::ptrdiff_t(h.first), n, s.flags.begin());
  return s;
}

size_t SampleTable::bytes() const {
  return headers_.capacity() * sizeof(Header) + counts_.capacity() * sizeof(uint32_t) +
         flags_.capacity() * sizeof(drivers::ChannelFlag);
}

}  // namespace imps::sim
