// SPDX-License-Identifier: MIT
// Tests for Heckbert's uniform hash (imps/src/uniform_hash.cpp): queries agree with brute force, also when buckets
// alias far-apart cubes and when the query box is wider than the table.
#include "imps/uniform_hash.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace imps {
namespace {

TEST(UniformHashGrid, RadiusQueriesMatchBruteForce) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  std::vector<glm::vec3> pts(2000);
  for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
  for (int bits : {1, 2, 3, 5}) {
    UniformHashGrid grid(0.25f, bits);
    grid.build(pts);
    for (int q = 0; q < 50; ++q) {
      const glm::vec3 c{u(rng), u(rng), u(rng)};
      const float r = q % 5 == 0 ? 2.5f : 0.4f;
      std::vector<uint32_t> got, want;
      grid.forEachWithin(c, r, pts, [&](uint32_t j, float) { got.push_back(j); });
      for (uint32_t j = 0; j < pts.size(); ++j) {
        const glm::vec3 d = pts[j] - c;
        if (d.x * d.x + d.y * d.y + d.z * d.z <= r * r) want.push_back(j);
      }
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, want) << "bits " << bits << " query " << q;  // also: nothing reported twice
    }
  }
}

TEST(UniformHashGrid, OrderIsBucketSortedAndAdoptable) {
  std::vector<glm::vec3> pts = {{5, 5, 5}, {0, 0, 0}, {0.1f, 0, 0}, {5, 5, 5.1f}};
  UniformHashGrid grid(1.0f, 3);
  grid.build(pts);
  std::vector<glm::vec3> sorted;
  for (uint32_t k : grid.order()) sorted.push_back(pts[k]);
  for (size_t k = 1; k < sorted.size(); ++k) EXPECT_LE(grid.bucketOf(sorted[k - 1]), grid.bucketOf(sorted[k]));
  // Many points over many buckets (both radix digits vary): bucket order, ties by index, every point once.
  {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-40.0f, 40.0f);
    std::vector<glm::vec3> many;
    for (int k = 0; k < 2000; ++k) many.push_back({u(rng), u(rng), u(rng)});
    UniformHashGrid big(1.0f, 6);
    big.build(many);
    const auto order = big.order();
    ASSERT_EQ(order.size(), many.size());
    std::vector<uint32_t> seen(order.begin(), order.end());
    std::sort(seen.begin(), seen.end());
    for (size_t k = 0; k < seen.size(); ++k) EXPECT_EQ(seen[k], k);
    for (size_t k = 1; k < order.size(); ++k) {
      const uint32_t a = big.bucketOf(many[order[k - 1]]), b = big.bucketOf(many[order[k]]);
      EXPECT_TRUE(a < b || (a == b && order[k - 1] < order[k])) << k;
    }
  }
  grid.adoptOrder();
  size_t found = 0;
  grid.forEachWithin(sorted[0], 0.5f, sorted, [&](uint32_t j, float) { found += j < 2 ? 1 : 0; });
  EXPECT_GE(found, 1u);
}

}  // namespace
}  // namespace imps
