// SPDX-License-Identifier: MIT
// Heckbert's uniform spatial hash: bucket tables rebuilt by sorting points by bucket.
#include "imps/uniform_hash.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace imps {

UniformHashGrid::UniformHashGrid(float cubeSize, int bitsPerDim)
    : cubeSize_(cubeSize > 0.0f ? cubeSize : 0.6f),
      invCube_(1.0f / cubeSize_),
      bits_(std::clamp(bitsPerDim, 1, 7)) {
  const size_t buckets = size_t(1) << (3 * bits_);
  start_.assign(buckets, kEmpty);
  end_.assign(buckets, kEmpty);
}

int clampedCube(float c) {
  const float f = std::floor(c);
  if (!(f > -1e9f)) return -1000000000;
  if (f > 1e9f) return 1000000000;
  return static_cast<int>(f);
}

int UniformHashGrid::cell(float x) const { return clampedCube(x * invCube_); }

uint32_t UniformHashGrid::bucketOf(const glm::vec3& p) const { return bucket(cell(p.x), cell(p.y), cell(p.z)); }

void UniformHashGrid::build(std::span<const glm::vec3> points) {
  for (uint32_t b : touched_) start_[b] = end_[b] = kEmpty;
  touched_.clear();
  const size_t n = points.size();
  buckets_.resize(n);
  for (size_t i = 0; i < n; ++i) buckets_[i] = bucketOf(points[i]);
  // Bucket order, ties by index: a stable radix sort of the indices by bucket in two passes (low digit, then high),
  // linear in n where a comparison sort was the largest serial step of the tesselator's update.
  const int low = (3 * bits_ + 1) / 2;
  const uint32_t lowMask = (1u << low) - 1u;
  counts_.resize(size_t(1) << low);
  spare_.resize(n);
  order_.resize(n);
  auto pass = [&](auto digit, auto index, uint32_t* out) {
    std::fill(counts_.begin(), counts_.end(), 0u);
    for (size_t k = 0; k < n; ++k) ++counts_[digit(buckets_[index(k)])];
    uint32_t sum = 0;
    for (uint32_t& c : counts_) sum += std::exchange(c, sum);
    for (size_t k = 0; k < n; ++k) out[counts_[digit(buckets_[index(k)])]++] = uint32_t(index(k));
  };
  pass([&](uint32_t b) { return b & lowMask; }, [](size_t k) { return k; }, spare_.data());
  pass([&](uint32_t b) { return b >> low; }, [&](size_t k) { return spare_[k]; }, order_.data());
  for (size_t s = 0; s < n; ++s) {
    const uint32_t b = buckets_[order_[s]];
    if (start_[b] == kEmpty) {
      start_[b] = uint32_t(s);
      touched_.push_back(b);
    }
    end_[b] = uint32_t(s + 1);
  }
}

void UniformHashGrid::adoptOrder() {
  for (size_t s = 0; s < order_.size(); ++s) order_[s] = uint32_t(s);
}

}  // namespace imps
