// Heckbert's uniform spatial hash: bucket tables rebuilt by sorting points by bucket.
#include "imps/uniform_hash.h"

#include <algorithm>
#include <cmath>

namespace imps {

UniformHashGrid::UniformHashGrid(float cubeSize, int bitsPerDim)
    : cubeSize_(cubeSize > 0.0f ? cubeSize : 0.6f),
      invCube_(1.0f / cubeSize_),
      bits_(std::clamp(bitsPerDim, 1, 7)) {
  const size_t buckets = size_t(1) << (3 * bits_);
  start_.assign(buckets, kEmpty);
  end_.assign(buckets, kEmpty);
}

int UniformHashGrid::cell(float x) const {
  // Clamp so that far-away or non-finite coordinates still give a valid (if useless) cell.
  const float c = std::floor(x * invCube_);
  if (!(c > -1e9f)) return -1000000000;
  if (c > 1e9f) return 1000000000;
  return static_cast<int>(c);
}

uint32_t UniformHashGrid::bucketOf(const glm::vec3& p) const { return bucket(cell(p.x), cell(p.y), cell(p.z)); }

void UniformHashGrid::build(std::span<const glm::vec3> points) {
  for (uint32_t b : touched_) start_[b] = end_[b] = kEmpty;
  touched_.clear();
  const size_t n = points.size();
  keys_.resize(n);
  for (size_t i = 0; i < n; ++i) keys_[i] = (uint64_t(bucketOf(points[i])) << 32) | uint64_t(i);
  std::sort(keys_.begin(), keys_.end());
  order_.resize(n);
  for (size_t s = 0; s < n; ++s) {
    const uint32_t b = uint32_t(keys_[s] >> 32);
    order_[s] = uint32_t(keys_[s]);
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
