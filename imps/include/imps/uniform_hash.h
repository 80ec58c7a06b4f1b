// SPDX-License-Identifier: MIT
// Heckbert's uniform spatial hash for particle neighbour queries (thesis 3.7, figure A-1 `UniformHash`).
//
// Based on: P. Heckbert, "Fast Surface Particle Repulsion", SIGGRAPH '97 course notes (uniform hashing of space into
//           cubes whose integer coordinates are folded, `bitsPerDim` bits per axis, into one bucket index).
//
// Space is cut into cubes of edge `cubeSize` metres; cube (i, j, k) goes to bucket ((i & m) << 2b | (j & m) << b |
// (k & m)) with b = bitsPerDim and m = 2^b - 1, so many far-apart cubes share a bucket and queries check distances.
// The grid is rebuilt from scratch by build() (a sort by bucket, then index: deterministic), and queried read-only
// from any number of threads.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

namespace imps {

// floor(c) as an int, clamped to +-1e9: the cube of a coordinate c in cube units, so that far-away or non-finite
// coordinates give a valid (if useless) cube instead of an out-of-range conversion (undefined behaviour). Cubes hash
// into a few bits per axis anyway, and every user compares real distances.
int clampedCube(float c);

class UniformHashGrid {
 public:
  // cubeSize > 0 metres; bitsPerDim is clamped to [1, 7] (at most 2^21 buckets, 16 MiB of tables).
  explicit UniformHashGrid(float cubeSize = 0.6f, int bitsPerDim = 3);

  float cubeSize() const { return cubeSize_; }
  int bitsPerDim() const { return bits_; }

  // The bucket of a point.
  uint32_t bucketOf(const glm::vec3& p) const;

  // Rebuilds the grid over `points` (which the grid does not keep: queries take them again). O(n) (a radix sort).
  void build(std::span<const glm::vec3> points);

  // The point indices in bucket order (ties by index): a spatially coherent ordering of the last build's points.
  std::span<const uint32_t> order() const { return order_; }
  // After the caller has permuted its points into order() (new index k = old index order()[k]), makes the grid
  // refer to the permuted indices, so no second build() is needed.
  void adoptOrder();

  // Calls visit(j, distanceSquared) for every point j of the last build with |points[j] - p| <= radius, in a
  // deterministic order (cube by cube, then by index). `points` must be the span given to build().
  template <class Visit>
  void forEachWithin(const glm::vec3& p, float radius, std::span<const glm::vec3> points, Visit&& visit) const {
    const float r2 = radius * radius;
    int lo[3], n[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = cell(p[a] - radius);
      n[a] = cell(p[a] + radius) - lo[a] + 1;
      if (n[a] > (1 << bits_)) n[a] = 1 << bits_;  // every bucket of this axis once
    }
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const uint32_t b = bucket(lo[0] + i, lo[1] + j, lo[2] + k);
          const uint32_t first = start_[b];
          if (first == kEmpty) continue;
          const uint32_t last = end_[b];
          for (uint32_t s = first; s < last; ++s) {
            const uint32_t q = order_[s];
            const glm::vec3 d = points[q] - p;
            const float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
            if (d2 <= r2) visit(q, d2);
          }
        }
  }

  // Calls visit(j) for every point j of the last build in a bucket of a cube overlapping the box [lo, hi] (a superset
  // of the points in the box: buckets are shared by far-apart cubes), in the same deterministic order as
  // forEachWithin(). For gathering the candidates of a group of nearby queries once.
  template <class Visit>
  void forEachInBox(const glm::vec3& lo, const glm::vec3& hi, Visit&& visit) const {
    int c0[3] = {}, n[3] = {};
    for (int a = 0; a < 3; ++a) {
      c0[a] = cell(lo[a]);
      n[a] = cell(hi[a]) - c0[a] + 1;
      if (n[a] > (1 << bits_)) n[a] = 1 << bits_;
    }
    for (int i = 0; i < n[0]; ++i)
      for (int j = 0; j < n[1]; ++j)
        for (int k = 0; k < n[2]; ++k) {
          const uint32_t b = bucket(c0[0] + i, c0[1] + j, c0[2] + k);
          const uint32_t first = start_[b];
          if (first == kEmpty) continue;
          for (uint32_t s = first; s < end_[b]; ++s) visit(order_[s]);
        }
  }

 private:
  static constexpr uint32_t kEmpty = 0xffffffffu;
  int cell(float x) const;
  uint32_t bucket(int i, int j, int k) const {
    const uint32_t m = (1u << bits_) - 1u;
    return ((uint32_t(i) & m) << (2 * bits_)) | ((uint32_t(j) & m) << bits_) | (uint32_t(k) & m);
  }

  float cubeSize_;
  float invCube_;
  int bits_;
  std::vector<uint32_t> start_, end_;  // per bucket: range in order_, kEmpty when unused
  std::vector<uint32_t> touched_;      // buckets set by the last build (reset by the next)
  std::vector<uint32_t> buckets_, counts_, spare_;  // build()'s radix sort: bucket per point, digit counts, pass 1
  std::vector<uint32_t> order_;
};

}  // namespace imps
