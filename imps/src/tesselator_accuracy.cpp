// SPDX-License-Identifier: MIT
// Accuracy measure for polygonizers: worst distance from surface samples to a triangle mesh (bucketed search).
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <glm/glm.hpp>

#include "imps/tesselator.h"

namespace imps {
namespace {

// Squared distance from p to triangle (a, b, c) (Ericson, "Real-Time Collision Detection", 5.1.5, re-derived).
float pointTriangle2(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  auto sq = [](const glm::vec3& v) { return glm::dot(v, v); };
  if (d1 <= 0 && d2 <= 0) return sq(ap);
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return sq(bp);
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return sq(p - (a + d1 / (d1 - d3) * ab));
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return sq(cp);
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return sq(p - (a + d2 / (d2 - d6) * ac));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return sq(p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)));
  const float denom = 1.0f / (va + vb + vc);
  return sq(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

uint64_t cellKey(int x, int y, int z) {
  return (uint64_t(uint32_t(x) & 0x1fffffu) << 42) | (uint64_t(uint32_t(y) & 0x1fffffu) << 21) |
         uint64_t(uint32_t(z) & 0x1fffffu);
}

}  // namespace

double worstDistanceToMesh(const Mesh& mesh, std::span<const glm::vec3> points, float searchRadius) {
  if (points.empty()) return 0.0;
  if (mesh.triangleCount() == 0) return searchRadius;
  const float cs = searchRadius;
  auto cell = [&](float v) { return int(std::floor(v / cs)); };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 v = mesh.position(mesh.indices[3 * t + size_t(k)]);
      lo = glm::min(lo, v);
      hi = glm::max(hi, v);
    }
    for (int x = cell(lo.x); x <= cell(hi.x); ++x)
      for (int y = cell(lo.y); y <= cell(hi.y); ++y)
        for (int z = cell(lo.z); z <= cell(hi.z); ++z) grid[cellKey(x, y, z)].push_back(uint32_t(t));
  }
  double worst = 0.0;
  for (const glm::vec3& p : points) {
    float best = searchRadius * searchRadius;
    for (int x = cell(p.x) - 1; x <= cell(p.x) + 1; ++x)
      for (int y = cell(p.y) - 1; y <= cell(p.y) + 1; ++y)
        for (int z = cell(p.z) - 1; z <= cell(p.z) + 1; ++z) {
          auto it = grid.find(cellKey(x, y, z));
          if (it == grid.end()) continue;
          for (uint32_t t : it->second)
            best = std::min(best, pointTriangle2(p, mesh.position(mesh.indices[3 * t]),
                                                 mesh.position(mesh.indices[3 * t + 1]),
                                                 mesh.position(mesh.indices[3 * t + 2])));
        }
    worst = std::max(worst, double(std::sqrt(best)));
  }
  return worst;
}

}  // namespace imps
