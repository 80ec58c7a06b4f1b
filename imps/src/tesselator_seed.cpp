// SPDX-License-Identifier: MIT
// Seeding the particle tesselator from every primitive (issue 3: never depend on one random point finding the
// surface): points spread over each primitive's own surface are projected onto the blended surface and thinned.
#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "imps/uniform_hash.h"
#include "tesselator_state.h"

namespace imps {
namespace {

constexpr float kGoldenAngle = 2.39996323f;

// n points spread evenly over the unit sphere (Fibonacci lattice).
void fibonacciSphere(size_t n, std::vector<glm::vec3>& out) {
  for (size_t k = 0; k < n; ++k) {
    const float z = 1.0f - (2.0f * float(k) + 1.0f) / float(n);
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    const float a = kGoldenAngle * float(k);
    out.push_back({r * std::cos(a), r * std::sin(a), z});
  }
}

// ceil(x) points, or none where x is not a number or beyond any budget (a segment too long for float: its length and
// the spacing seedSpacing widens for it are both infinite).
size_t pointCount(float x) { return x >= 0.0f && x < 1e7f ? size_t(std::ceil(x)) : 0; }

// Candidate points on primitive p's own d = 1 surface, about `spacing` apart.
void primitivePoints(const Primitive& p, float spacing, std::vector<glm::vec3>& out) {
  std::vector<glm::vec3> unit;
  const float area = spacing * spacing;
  switch (p.kind) {
    case PrimitiveKind::Metaball: {
      fibonacciSphere(pointCount(4.0f * 3.14159265f * p.radius * p.radius / area) + 4, unit);
      for (const glm::vec3& u : unit) out.push_back(p.center + p.radius * u);
      break;
    }
    case PrimitiveKind::Ellipsoid: {
      const float r = (p.radii.x + p.radii.y + p.radii.z) / 3.0f;
      fibonacciSphere(pointCount(4.0f * 3.14159265f * r * r / area) + 4, unit);
      for (const glm::vec3& u : unit) out.push_back(p.center + p.rotation * (p.radii * u));
      break;
    }
    case PrimitiveKind::LineSeg: {
      for (int end = 0; end < 2; ++end) {
        const float r = end == 0 ? p.r1 : p.r2;
        const glm::vec3 c = end == 0 ? p.p1 : p.p2;
        unit.clear();
        fibonacciSphere(pointCount(4.0f * 3.14159265f * r * r / area) + 4, unit);
        for (const glm::vec3& u : unit) out.push_back(c + r * u);
      }
      glm::vec3 b0, b1;
      tangentBasis(p.axis, b0, b1);
      const int rings = int(pointCount(p.length / spacing));
      for (int k = 1; k < rings; ++k) {
        const float t = p.length * float(k) / float(rings);
        const float r = p.r1 + p.slope * t;
        const int m = std::max(3, int(pointCount(2.0f * 3.14159265f * r / spacing)));
        for (int j = 0; j < m; ++j) {
          const float a = 2.0f * 3.14159265f * (float(j) + 0.5f * float(k & 1)) / float(m);
          out.push_back(p.p1 + t * p.axis + r * (std::cos(a) * b0 + std::sin(a) * b1));
        }
      }
      break;
    }
  }
}

// About how many points primitivePoints gives at `spacing` (its surface area over spacing^2).
double pointEstimate(const Primitive& p, float spacing) {
  return primitiveSurfaceArea(p) / (double(spacing) * spacing) + 8.0;
}

// The candidates' spacing: 0.8 desiredRadius, widened when that would give more than a few times maxParticles
// candidates (a tiny desiredRadius on a large character), so seeding's memory stays in proportion to the limit.
float seedSpacing(const Field& field, const TesselatorOptions& o) {
  const float spacing = 0.8f * o.desiredRadius;
  double total = 0.0;
  for (const Primitive& p : field.primitives()) total += pointEstimate(p, spacing);
  const double budget = 4.0 * double(std::max<size_t>(o.maxParticles, 1));
  return total > budget ? float(double(spacing) * std::sqrt(total / budget)) : spacing;
}

}  // namespace

double primitiveSurfaceArea(const Primitive& p) {
  constexpr double kPi = 3.14159265358979;
  switch (p.kind) {
    case PrimitiveKind::Metaball: return 4.0 * kPi * double(p.radius) * double(p.radius);
    case PrimitiveKind::Ellipsoid: {
      const double r = (double(p.radii.x) + double(p.radii.y) + double(p.radii.z)) / 3.0;
      return 4.0 * kPi * r * r;
    }
    case PrimitiveKind::LineSeg:
      return 4.0 * kPi * (double(p.r1) * p.r1 + double(p.r2) * p.r2) +
             2.0 * kPi * std::max(double(p.r1), double(p.r2)) * double(p.length);
  }
  return 0.0;
}

void seedParticles(Tesselator::State& s, const Field& field, const TesselatorOptions& o) {
  const float h = o.desiredRadius;
  std::vector<glm::vec3> points;
  const float spacing = seedSpacing(field, o);
  for (const Primitive& p : field.primitives()) primitivePoints(p, spacing, points);

  FieldScratch scratch;
  Box all = field.bounds();
  field.prepare(all, scratch);
  const float iso = field.iso();

  // Thinning grid: accepted points no closer than 0.8 desiredRadius (a Poisson-disk sample in seed order).
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  const float cellSize = 0.8f * h;
  auto key = [&](const glm::vec3& x, int dx, int dy, int dz) {
    const auto c = [&](float v, int d) { return uint64_t(uint32_t(clampedCube(v / cellSize) + d) & 0x1fffffu); };
    return (c(x.x, dx) << 42) | (c(x.y, dy) << 21) | c(x.z, dz);
  };
  const float minD2 = cellSize * cellSize;
  for (glm::vec3 x : points) {
    if (s.size() >= o.maxParticles) break;
    // Newton projection onto F = iso along the gradient, steps clamped to one desiredRadius.
    bool ok = false;
    FieldSample fs;
    for (int it = 0; it < 12; ++it) {
      if (!all.contains(x)) break;
      fs = field.sample(x, scratch);
      const float g2 = glm::dot(fs.gradient, fs.gradient);
      if (!(g2 > 1e-12f)) break;
      const float err = (iso - fs.value) / std::sqrt(g2);
      if (std::fabs(err) < 1e-4f * h) {
        ok = true;
        break;
      }
      glm::vec3 step = (iso - fs.value) / g2 * fs.gradient;
      const float len = glm::length(step);
      if (len > h) step *= h / len;
      x += step;
    }
    if (!ok || !finite3(x)) continue;
    bool nearOther = false;
    for (int dx = -1; dx <= 1 && !nearOther; ++dx)
      for (int dy = -1; dy <= 1 && !nearOther; ++dy)
        for (int dz = -1; dz <= 1 && !nearOther; ++dz) {
          auto it = grid.find(key(x, dx, dy, dz));
          if (it == grid.end()) continue;
          for (uint32_t q : it->second) {
            const glm::vec3 d = s.pos[q] - x;
            if (glm::dot(d, d) < minD2) {
              nearOther = true;
              break;
            }
          }
        }
    if (nearOther) continue;
    grid[key(x, 0, 0, 0)].push_back(uint32_t(s.size()));
    s.add(x, fs.gradient, h, fs.owner);
  }
}

}  // namespace imps
