// SPDX-License-Identifier: MIT
// Field evaluation: terms per primitive, combined per blend set, maximum over sets.
#include "imps/field.h"

#include <algorithm>
#include <cmath>

#include "imps/check.h"
#include "vector_clones.h"

namespace imps {

void BlendSets::add(std::span<const uint32_t> sortedMembers) {
  members.insert(members.end(), sortedMembers.begin(), sortedMembers.end());
  offsets.push_back(static_cast<uint32_t>(members.size()));
}

BlendSets BlendSets::all(size_t n) {
  BlendSets sets;
  std::vector<uint32_t> everyone(n);
  for (size_t i = 0; i < n; ++i) everyone[i] = static_cast<uint32_t>(i);
  sets.add(everyone);
  return sets;
}

namespace {
// Support boxes are padded so that float rounding in bounds() can never exclude a point where a primitive still
// has a non-zero term (which would break the bit-identity of values across regions).
Box padded(Box b) {
  const glm::vec3 pad = 1e-4f * (glm::abs(b.lo) + glm::abs(b.hi)) + glm::vec3(1e-6f);
  b.lo -= pad;
  b.hi += pad;
  return b;
}
}  // namespace

Field::Field(std::vector<Primitive> primitives, std::vector<float> params, std::vector<glm::vec3> colors,
             BlendFunction blend, BlendSets sets, float iso)
    : primitives_(std::move(primitives)),
      params_(std::move(params)),
      colors_(std::move(colors)),
      blend_(blend),
      sets_(std::move(sets)),
      iso_(iso) {
  IMPS_CHECK_EQ(params_.size(), primitives_.size());
  IMPS_CHECK_EQ(colors_.size(), primitives_.size());
  support_.resize(primitives_.size());
  supportSkip_.resize(primitives_.size());
  for (size_t i = 0; i < primitives_.size(); ++i) {
    support_[i] = blend_.support(params_[i]);
    supportSkip_[i] = support_[i] * (1.0f + 1e-3f) + 1e-3f;
  }
  setPrimitives(std::move(primitives_));
}

void Field::setPrimitives(std::vector<Primitive> primitives) {
  IMPS_CHECK_EQ(primitives.size(), support_.size());
  primitives_ = std::move(primitives);
  supportBoxes_.resize(primitives_.size());
  for (size_t i = 0; i < primitives_.size(); ++i) supportBoxes_[i] = padded(primitives_[i].bounds(support_[i]));
}

Box Field::bounds() const {
  Box b;
  for (const Box& s : supportBoxes_) b.extend(s);
  return b;
}

Box Field::surfaceBounds() const {
  // Keep the cells of a coarse grid over the supports where F might reach iso: bin the primitives into the cells
  // their supports overlap, then bound F in each cell by the sum of every candidate's largest term there (an upper
  // bound for any blend set).
  const Box all = bounds();
  if (all.empty()) return all;
  constexpr int kCells = 8;
  const glm::vec3 cell = all.size() / float(kCells);
  std::vector<float> upper(kCells * kCells * kCells, 0.0f);
  std::vector<uint8_t> unbounded(upper.size(), 0);
  // The grid cell of a point, clamped before the conversion to int: a scene with coordinates near FLT_MAX gives an
  // infinite box, and inf or NaN must not reach int (undefined behaviour); NaN goes to cell 0.
  const auto cellOf = [&](const glm::vec3& p) {
    const glm::vec3 f = glm::floor((p - all.lo) / cell);
    glm::ivec3 c;
    for (int k = 0; k < 3; ++k) c[k] = !(f[k] > 0.0f) ? 0 : f[k] >= float(kCells - 1) ? kCells - 1 : int(f[k]);
    return c;
  };
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const glm::ivec3 lo = cellOf(supportBoxes_[i].lo);
    const glm::ivec3 hi = cellOf(supportBoxes_[i].hi);
    for (int k = lo.z; k <= hi.z; ++k)
      for (int j = lo.y; j <= hi.y; ++j)
        for (int c = lo.x; c <= hi.x; ++c) {
          Box b;
          b.lo = all.lo + cell * glm::vec3(c, j, k);
          b.hi = b.lo + cell;
          const float d = primitives_[i].minDistance(b, /*tight=*/false);
          const size_t index = size_t(c) + kCells * (size_t(j) + kCells * size_t(k));
          if (blend_.additive()) upper[index] += blend_.term(d, params_[i]);
          else if (d < support_[i]) unbounded[index] = 1;
        }
  }
  Box result;
  for (int k = 0; k < kCells; ++k)
    for (int j = 0; j < kCells; ++j)
      for (int c = 0; c < kCells; ++c) {
        const size_t index = size_t(c) + kCells * (size_t(j) + kCells * size_t(k));
        if (upper[index] < iso_ && !unbounded[index]) continue;
        Box b;
        b.lo = all.lo + cell * glm::vec3(c, j, k);
        b.hi = b.lo + cell;
        result.extend(b);
      }
  return result;
}

void Field::prepare(const Box& region, FieldScratch& scratch) const {
  scratch.candidates.clear();
  for (size_t i = 0; i < primitives_.size(); ++i)
    if (supportBoxes_[i].overlaps(region)) scratch.candidates.push_back(static_cast<uint32_t>(i));
  prepareSets(scratch);
}

void Field::prepare(std::span<const uint32_t> candidates, FieldScratch& scratch) const {
  scratch.candidates.assign(candidates.begin(), candidates.end());
  prepareSets(scratch);
}

namespace {
bool isSubset(std::span<const uint32_t> small, std::span<const uint32_t> big) {
  return std::includes(big.begin(), big.end(), small.begin(), small.end());
}
}  // namespace

// Restricts the blend sets to the candidates. Duplicate sets are dropped (they give equal values), and for the
// additive blends so are subsets of other sets: float addition of non-negative terms is monotone, so a subset never
// exceeds its superset and dropping it leaves every value bit-identical. (The rounded union is not monotone to the
// last bit, so elliptical sets keep their subsets.)
void Field::prepareSets(FieldScratch& scratch) const {
  const auto& cand = scratch.candidates;
  scratch.setOffsets.assign(1, 0);
  scratch.setMembers.clear();
  const bool singleSet = sets_.count() == 1 && sets_.members.size() == primitives_.size();
  if (singleSet) {
    if (!cand.empty()) {
      for (size_t k = 0; k < cand.size(); ++k) scratch.setMembers.push_back(static_cast<uint32_t>(k));
      scratch.setOffsets.push_back(static_cast<uint32_t>(cand.size()));
    }
  } else {
    // Restrict every set to the candidates (as positions in the candidate list, still ascending).
    auto& offsets = scratch.restrictOffsets;
    auto& members = scratch.restrictMembers;
    offsets.assign(1, 0);
    members.clear();
    scratch.globalToLocal.resize(primitives_.size(), -1);
    for (size_t k = 0; k < cand.size(); ++k) scratch.globalToLocal[cand[k]] = static_cast<int32_t>(k);
    for (size_t s = 0; s < sets_.count(); ++s) {
      const size_t before = members.size();
      for (uint32_t m : sets_.set(s))
        if (scratch.globalToLocal[m] >= 0) members.push_back(static_cast<uint32_t>(scratch.globalToLocal[m]));
      if (members.size() > before) offsets.push_back(static_cast<uint32_t>(members.size()));
    }
    for (uint32_t c : cand) scratch.globalToLocal[c] = -1;
    // Keep a set unless another is equal (and earlier) or, for additive blends, a strict superset.
    const size_t n = offsets.size() - 1;
    auto set = [&](size_t s) {
      return std::span<const uint32_t>(members).subspan(offsets[s], offsets[s + 1] - offsets[s]);
    };
    for (size_t a = 0; a < n; ++a) {
      const auto sa = set(a);
      bool drop = false;
      for (size_t b = 0; b < n && !drop; ++b) {
        if (a == b) continue;
        const auto sb = set(b);
        const bool equal = std::equal(sa.begin(), sa.end(), sb.begin(), sb.end());
        drop = equal ? b < a : (blend_.additive() && sb.size() > sa.size() && isSubset(sa, sb));
      }
      if (drop) continue;
      scratch.setMembers.insert(scratch.setMembers.end(), sa.begin(), sa.end());
      scratch.setOffsets.push_back(static_cast<uint32_t>(scratch.setMembers.size()));
    }
  }
  // Candidate -> the local sets holding it.
  scratch.memberOffsets.assign(cand.size() + 1, 0);
  for (uint32_t m : scratch.setMembers) ++scratch.memberOffsets[m + 1];
  for (size_t k = 0; k < cand.size(); ++k) scratch.memberOffsets[k + 1] += scratch.memberOffsets[k];
  scratch.memberSets.resize(scratch.setMembers.size());
  auto& fill = scratch.fill;
  fill.assign(scratch.memberOffsets.begin(), scratch.memberOffsets.end() - 1);
  for (size_t s = 0; s < scratch.setCount(); ++s)
    for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m)
      scratch.memberSets[fill[scratch.setMembers[m]]++] = static_cast<uint32_t>(s);
}

namespace {

// Normalised squared distance kernels, one per kind: branch-free (selects), no calls, so that loops over them
// vectorise and the scalar point path, which calls the very same functions, gives bit-identical values.
inline float metaballDistance(const Primitive& p, float x, float y, float z) {
  const float vx = x - p.center.x, vy = y - p.center.y, vz = z - p.center.z;
  return (vx * vx + vy * vy + vz * vz) / (p.radius * p.radius);
}

inline float ellipsoidDistance(const Primitive& p, float x, float y, float z) {
  const glm::mat3& w = p.worldToLocal;
  const float vx = x - p.center.x, vy = y - p.center.y, vz = z - p.center.z;
  const float qx = w[0][0] * vx + w[1][0] * vy + w[2][0] * vz;
  const float qy = w[0][1] * vx + w[1][1] * vy + w[2][1] * vz;
  const float qz = w[0][2] * vx + w[1][2] * vy + w[2][2] * vz;
  return qx * qx + qy * qy + qz * qz;
}

// The segment parameter s of the sphere nearest x: the arithmetic of lineSegParameter() in primitives.cpp, with
// selects for its branches.
inline float lineSegClosestParameter(const Primitive& p, float x, float y, float z) {
  const float vx = x - p.p1.x, vy = y - p.p1.y, vz = z - p.p1.z;
  const float vv = vx * vx + vy * vy + vz * vz;
  const float t = vx * p.axis.x + vy * p.axis.y + vz * p.axis.z;
  const float rho2 = std::max(0.0f, vv - t * t);
  const float a = p.r1 + p.slope * t;
  const float safeA = a > 0.0f ? a : 1.0f;
  const float sInside = std::min(std::max(t + p.slope * rho2 / safeA, 0.0f), p.length);
  const float wx = x - p.p2.x, wy = y - p.p2.y, wz = z - p.p2.z;
  const float sApex = vv / (p.r1 * p.r1) <= (wx * wx + wy * wy + wz * wz) / (p.r2 * p.r2) ? 0.0f : p.length;
  return a > 0.0f ? sInside : sApex;
}

inline float lineSegDistance(const Primitive& p, float x, float y, float z) {
  const float s = lineSegClosestParameter(p, x, y, z);
  const float ux = x - (p.p1.x + s * p.axis.x), uy = y - (p.p1.y + s * p.axis.y), uz = z - (p.p1.z + s * p.axis.z);
  const float r = p.r1 + p.slope * s;
  return (ux * ux + uy * uy + uz * uz) / (r * r);
}

inline float kernelDistance(const Primitive& p, float x, float y, float z) {
  switch (p.kind) {
    case PrimitiveKind::Metaball: return metaballDistance(p, x, y, z);
    case PrimitiveKind::Ellipsoid: return ellipsoidDistance(p, x, y, z);
    case PrimitiveKind::LineSeg: return lineSegDistance(p, x, y, z);
  }
  return 0.0f;
}

inline float metaballDistanceGradient(const Primitive& p, float x, float y, float z, float& gx, float& gy, float& gz) {
  const float vx = x - p.center.x, vy = y - p.center.y, vz = z - p.center.z;
  const float inv = 2.0f / (p.radius * p.radius);
  gx = inv * vx;
  gy = inv * vy;
  gz = inv * vz;
  return (vx * vx + vy * vy + vz * vz) / (p.radius * p.radius);
}

inline float ellipsoidDistanceGradient(const Primitive& p, float x, float y, float z, float& gx, float& gy, float& gz) {
  const glm::mat3& w = p.worldToLocal;
  const float vx = x - p.center.x, vy = y - p.center.y, vz = z - p.center.z;
  const float qx = w[0][0] * vx + w[1][0] * vy + w[2][0] * vz;
  const float qy = w[0][1] * vx + w[1][1] * vy + w[2][1] * vz;
  const float qz = w[0][2] * vx + w[1][2] * vy + w[2][2] * vz;
  gx = 2.0f * (w[0][0] * qx + w[0][1] * qy + w[0][2] * qz);
  gy = 2.0f * (w[1][0] * qx + w[1][1] * qy + w[1][2] * qz);
  gz = 2.0f * (w[2][0] * qx + w[2][1] * qy + w[2][2] * qz);
  return qx * qx + qy * qy + qz * qz;
}

inline float lineSegDistanceGradient(const Primitive& p, float x, float y, float z, float& gx, float& gy, float& gz) {
  const float s = lineSegClosestParameter(p, x, y, z);
  const float ux = x - (p.p1.x + s * p.axis.x), uy = y - (p.p1.y + s * p.axis.y), uz = z - (p.p1.z + s * p.axis.z);
  const float r = p.r1 + p.slope * s;
  const float inv = 2.0f / (r * r);
  gx = inv * ux;
  gy = inv * uy;
  gz = inv * uz;
  return (ux * ux + uy * uy + uz * uz) / (r * r);
}

// kernelDistance() (the very same arithmetic, so the same bits) and its gradient in x, for sample() and samples().
// Line segment: by the envelope theorem the gradient is that of the sphere at the closest parameter s.
inline float kernelDistanceGradient(const Primitive& p, const glm::vec3& x, glm::vec3& gradient) {
  float d = 0.0f;
  switch (p.kind) {
    case PrimitiveKind::Metaball:
      d = metaballDistanceGradient(p, x.x, x.y, x.z, gradient.x, gradient.y, gradient.z);
      break;
    case PrimitiveKind::Ellipsoid:
      d = ellipsoidDistanceGradient(p, x.x, x.y, x.z, gradient.x, gradient.y, gradient.z);
      break;
    case PrimitiveKind::LineSeg:
      d = lineSegDistanceGradient(p, x.x, x.y, x.z, gradient.x, gradient.y, gradient.z);
      break;
  }
  return d;
}

// Blend term kernels (blend.h's BlendFunction::term, written for vectorisation).
inline float exponentialTerm(float param, float d) {
  const float c = expAccurate(param * (d - 1.0f));
  return c >= kExponentialCutoff ? c : 0.0f;
}
inline float fastExponentialTerm(float param, float d) {
  const float c = expFast(param * (d - 1.0f));
  return c >= kExponentialCutoff ? c : 0.0f;
}
inline float blancSchlickTerm(float param, float d) {
  const float u = std::max(1.0f + 1.0f / param - d, 0.0f) * param;
  return u * u;
}
inline float ellipticalTerm(float param, float d) { return std::max((1.0f - d) / param, -1.0f); }

inline float kernelTerm(const BlendFunction& blend, float param, float d) {
  switch (blend.kind) {
    case BlendKind::Exponential: return blend.fastExp ? fastExponentialTerm(param, d) : exponentialTerm(param, d);
    case BlendKind::BlancSchlick: return blancSchlickTerm(param, d);
    case BlendKind::Elliptical: return ellipticalTerm(param, d);
  }
  return 0.0f;
}

// dc/dd of an additive blend given d and the term c = kernelTerm(d) already computed (the exponential's derivative
// is param * c: no second exponential).
inline float kernelTermSlope(const BlendFunction& blend, float param, float d, float c) {
  return blend.kind == BlendKind::Exponential ? param * c : blend.termDerivative(d, param);
}

inline float foldElliptical(float g, float x) {
  return g <= -1.0f ? x : (x <= -1.0f ? g : BlendFunction::roundedUnion(g, x));
}

template <float (*Distance)(const Primitive&, float, float, float)>
IMPS_VECTOR_CLONES void distanceLoop(const Primitive& p, const float* xs, const float* ys, const float* zs, size_t n,
                                     float* d) {
  for (size_t i = 0; i < n; ++i) d[i] = Distance(p, xs[i], ys[i], zs[i]);
}

template <float (*Term)(float, float)>
IMPS_VECTOR_CLONES void termLoop(float param, size_t n, float* t) {
  for (size_t i = 0; i < n; ++i) t[i] = Term(param, t[i]);
}

template <float (*DistanceGradient)(const Primitive&, float, float, float, float&, float&, float&)>
IMPS_VECTOR_CLONES void distanceGradientLoop(const Primitive& p, const float* __restrict xs, const float* __restrict ys,
                                             const float* __restrict zs, size_t n, float* __restrict d,
                                             float* __restrict gx, float* __restrict gy, float* __restrict gz) {
  const Primitive local = p;  // a local copy: the stores below cannot alias its fields, so the loop vectorises
  for (size_t i = 0; i < n; ++i) {
    float x, y, z;
    d[i] = DistanceGradient(local, xs[i], ys[i], zs[i], x, y, z);
    gx[i] = x;
    gy[i] = y;
    gz[i] = z;
  }
}

// samples()' per-candidate step: the points flagged in `use` add the candidate's gradient (slope x distance
// gradient), colour and weight, and take it as owner where its term is the largest so far. Arithmetic masks, not
// branches or selects into memory, which GCC compiles to masked stores (slow: most of this loop's time once): the
// other points add +-0, which changes nothing, the sums never being -0 (they start at +0, and x + y is -0 only for
// -0 + -0), so the bits are sample()'s.
IMPS_VECTOR_CLONES void accumulateGradientColour(size_t n, const uint8_t* __restrict use, const float* __restrict t,
                                                 const float* __restrict slope, const float* __restrict dgx,
                                                 const float* __restrict dgy, const float* __restrict dgz,
                                                 glm::vec3 c, int32_t candidate, float* __restrict gx,
                                                 float* __restrict gy, float* __restrict gz, float* __restrict cr,
                                                 float* __restrict cg, float* __restrict cb, float* __restrict weight,
                                                 float* __restrict bestWeight, int32_t* __restrict owner) {
  for (size_t i = 0; i < n; ++i) {
    const float m = use[i] != 0 ? 1.0f : 0.0f;  // x * m is x or +-0, every x here being finite
    gx[i] += slope[i] * dgx[i] * m;
    gy[i] += slope[i] * dgy[i] * m;
    gz[i] += slope[i] * dgz[i] * m;
    cr[i] += t[i] * c.x * m;
    cg[i] += t[i] * c.y * m;
    cb[i] += t[i] * c.z * m;
    weight[i] += t[i] * m;
    const float best = bestWeight[i];
    const bool better = (use[i] != 0) & (t[i] > best);
    bestWeight[i] = better ? t[i] : best;
    const int32_t o = owner[i];
    owner[i] = better ? candidate : o;
  }
}

// dc/dd given d and the term c (kernelTermSlope()'s arithmetic, one function per additive blend for the kernels).
inline float exponentialSlope(float param, float, float c) { return param * c; }
inline float blancSchlickSlope(float param, float d, float) {
  const float u = std::max(1.0f + 1.0f / param - d, 0.0f) * param;
  return -2.0f * u * param;
}

// A point's running sums in samplesOfOneSet(): value, gradient, colour, weight, the best term so far and its owner.
struct SampleSums {
  float v, x, y, z, r, g, b, w, best;
  int32_t o;
};

// samples()' one-pass step for a field of one additive blend set: one candidate's term, gradient, colour, weight
// and ownership at a point (one distance and one term, nothing stored between passes). Per point this is sample()'s
// arithmetic in its order (the set's sum, then each positive term's slope x distance gradient, colour and weight), so
// the same bits; beyond the support the term is exactly 0 and adds nothing.
template <float (*DistanceGradient)(const Primitive&, float, float, float, float&, float&, float&),
          float (*Term)(float, float), float (*Slope)(float, float, float)>
[[gnu::always_inline]] inline void addSampleTerm(const Primitive& p, float param, glm::vec3 c, int32_t candidate,
                                                 float px, float py, float pz, SampleSums& s) {
  float dx, dy, dz;
  const float d = DistanceGradient(p, px, py, pz, dx, dy, dz);
  const float t = Term(param, d);
  const float slope = Slope(param, d, t);
  // Where the term is 0 so is the slope (+-0): those points add +-0, which changes nothing (the sums are never -0,
  // see accumulateGradientColour), so no select is needed but for the owner.
  s.v += t;
  s.x += slope * dx;
  s.y += slope * dy;
  s.z += slope * dz;
  s.r += t * c.x;
  s.g += t * c.y;
  s.b += t * c.z;
  s.w += t;
  // The owner changes where the term beats 0 and every earlier term (bestWeight starts at 0 here).
  s.o = t > s.best ? candidate : s.o;
  s.best = std::max(s.best, t);
}

// K (1 or 2) candidates' steps at every point, one after the other, in one loop over the points.
template <float (*DistanceGradient)(const Primitive&, float, float, float, float&, float&, float&),
          float (*Term)(float, float), float (*Slope)(float, float, float), size_t K>
IMPS_VECTOR_CLONES void addSampleTerms(const std::array<const Primitive*, K>& ps, const std::array<float, K>& params,
                                       const std::array<glm::vec3, K>& cs, const std::array<int32_t, K>& candidates,
                                       size_t n, const float* __restrict xs, const float* __restrict ys,
                                       const float* __restrict zs, float* __restrict value, float* __restrict gx,
                                       float* __restrict gy, float* __restrict gz, float* __restrict cr,
                                       float* __restrict cg, float* __restrict cb, float* __restrict weight,
                                       float* __restrict bestWeight, int32_t* __restrict owner) {
  static_assert(K == 1 || K == 2);
  // Local copies: the stores below cannot alias their fields, so the loop vectorises.
  const Primitive p0 = *ps[0], p1 = *ps[K - 1];
  const float param0 = params[0], param1 = params[K - 1];
  const glm::vec3 c0 = cs[0], c1 = cs[K - 1];
  const int32_t candidate0 = candidates[0], candidate1 = candidates[K - 1];
  for (size_t i = 0; i < n; ++i) {
    SampleSums s{value[i], gx[i], gy[i], gz[i], cr[i], cg[i], cb[i], weight[i], bestWeight[i], owner[i]};
    addSampleTerm<DistanceGradient, Term, Slope>(p0, param0, c0, candidate0, xs[i], ys[i], zs[i], s);
    if constexpr (K == 2)
      addSampleTerm<DistanceGradient, Term, Slope>(p1, param1, c1, candidate1, xs[i], ys[i], zs[i], s);
    value[i] = s.v;
    gx[i] = s.x;
    gy[i] = s.y;
    gz[i] = s.z;
    cr[i] = s.r;
    cg[i] = s.g;
    cb[i] = s.b;
    weight[i] = s.w;
    bestWeight[i] = s.best;
    owner[i] = s.o;
  }
}

// samplesOfOneSet()'s step for K candidates of one kind (given by DistanceGradient), in ascending order: their terms
// one after the other at each point, the same arithmetic in the same order as K steps of one, so the same bits. Two
// at a time halve the accumulators' loads and stores and give the core two exponentials to overlap.
template <float (*DistanceGradient)(const Primitive&, float, float, float, float&, float&, float&), size_t K>
void addSampleTermsOfKind(const BlendFunction& blend, const std::array<const Primitive*, K>& ps,
                          const std::array<float, K>& params, const std::array<glm::vec3, K>& cs,
                          const std::array<int32_t, K>& candidates, size_t n, const float* xs, const float* ys,
                          const float* zs, FieldScratch::Lanes& l) {
  auto run = [&]<float (*Term)(float, float), float (*Slope)(float, float, float)>() {
    addSampleTerms<DistanceGradient, Term, Slope, K>(ps, params, cs, candidates, n, xs, ys, zs, l.d.data(), l.gx.data(),
                                                     l.gy.data(), l.gz.data(), l.cr.data(), l.cg.data(), l.cb.data(),
                                                     l.weight.data(), l.bestWeight.data(), l.owner.data());
  };
  switch (blend.kind) {
    case BlendKind::Exponential:
      if (blend.fastExp) run.template operator()<fastExponentialTerm, exponentialSlope>();
      else run.template operator()<exponentialTerm, exponentialSlope>();
      break;
    case BlendKind::BlancSchlick: run.template operator()<blancSchlickTerm, blancSchlickSlope>(); break;
    case BlendKind::Elliptical: IMPS_CHECK(false); break;  // not additive: sample() per point instead
  }
}

}  // namespace

void Field::terms(size_t i, size_t first, size_t n, FieldScratch& scratch) const {
  float* t = scratch.term.data() + first;
  const Primitive& p = primitives_[i];
  const float *xs = scratch.xs.data() + first, *ys = scratch.ys.data() + first, *zs = scratch.zs.data() + first;
  switch (p.kind) {
    case PrimitiveKind::Metaball: distanceLoop<metaballDistance>(p, xs, ys, zs, n, t); break;
    case PrimitiveKind::Ellipsoid: distanceLoop<ellipsoidDistance>(p, xs, ys, zs, n, t); break;
    case PrimitiveKind::LineSeg: distanceLoop<lineSegDistance>(p, xs, ys, zs, n, t); break;
  }
  const float param = params_[i];
  switch (blend_.kind) {
    case BlendKind::Exponential:
      if (blend_.fastExp) termLoop<fastExponentialTerm>(param, n, t);
      else termLoop<exponentialTerm>(param, n, t);
      break;
    case BlendKind::BlancSchlick: termLoop<blancSchlickTerm>(param, n, t); break;
    case BlendKind::Elliptical: termLoop<ellipticalTerm>(param, n, t); break;
  }
}

namespace {

// Scratch buffers only grow: resizing down and up again between a block's samples and its root-finding batches
// would zero-fill the regrown part every time.
void atLeast(std::vector<float>& v, size_t size) {
  if (v.size() < size) v.resize(size);
}

// The batched kernels run over whole vectors of points: a batch of n points is evaluated as padded(n), the last
// point repeated. A batch is often short (a block's edges, the few a root-finding step still has): a scalar remainder
// of up to 7 points, each a whole exponential's latency, would cost about as much as the vectors.
constexpr size_t kLanes = 8;
size_t padded(size_t n) { return (n + kLanes - 1) / kLanes * kLanes; }

// The points into scratch.xs, ys and zs (SoA, for the vectorised kernels), padded; returns padded(points.size()).
size_t splitPoints(std::span<const glm::vec3> points, FieldScratch& scratch) {
  const size_t n = padded(points.size());
  atLeast(scratch.xs, n);
  atLeast(scratch.ys, n);
  atLeast(scratch.zs, n);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3& x = points[std::min(i, points.size() - 1)];
    scratch.xs[i] = x.x;
    scratch.ys[i] = x.y;
    scratch.zs[i] = x.z;
  }
  return n;
}

// F at n points from their per-set accumulators (sets x points, `stride` apart): the maximum over the sets.
void maxOverSets(bool additive, size_t sets, size_t n, size_t stride, const float* accs, float* out) {
  if (additive && sets > 0) {  // the first set's pass also clears: max(0, acc) is what max(out = 0, acc) gives
    for (size_t i = 0; i < n; ++i) out[i] = std::max(0.0f, accs[i]);
  } else {
    for (size_t i = 0; i < n; ++i) out[i] = 0.0f;
  }
  for (size_t s = additive && sets > 0 ? 1 : 0; s < sets; ++s) {
    const float* acc = accs + s * stride;
    if (additive) {
      for (size_t i = 0; i < n; ++i) out[i] = std::max(out[i], acc[i]);
    } else {
      for (size_t i = 0; i < n; ++i) out[i] = std::max(out[i], acc[i] > -1.0f ? std::max(1.0f + acc[i], 0.0f) : 0.0f);
    }
  }
}

}  // namespace

namespace {

// The additive blends' sum step of one candidate over a run of points: acc[i] += Term(Distance(x_i)), the very
// arithmetic of terms() then `acc += t`, so the same bits. Two passes, distances into t and then terms into acc: one
// fused loop would be one long dependency chain per point (division, exponential, sum), which runs slower.
template <float (*Term)(float, float)>
IMPS_VECTOR_CLONES void addTermLoop(float param, size_t n, const float* __restrict t, float* __restrict acc) {
  for (size_t i = 0; i < n; ++i) acc[i] += Term(param, t[i]);
}

template <float (*Distance)(const Primitive&, float, float, float)>
void addTermsOfKind(const BlendFunction& blend, const Primitive& p, float param, const float* xs, const float* ys,
                    const float* zs, size_t n, float* t, float* acc) {
  distanceLoop<Distance>(p, xs, ys, zs, n, t);
  switch (blend.kind) {
    case BlendKind::Exponential:
      if (blend.fastExp) addTermLoop<fastExponentialTerm>(param, n, t, acc);
      else addTermLoop<exponentialTerm>(param, n, t, acc);
      break;
    case BlendKind::BlancSchlick: addTermLoop<blancSchlickTerm>(param, n, t, acc); break;
    case BlendKind::Elliptical: IMPS_CHECK(false); break;  // not additive: callers fold instead
  }
}

// t: scratch of n floats (not acc).
void addTerms(const BlendFunction& blend, const Primitive& p, float param, const float* xs, const float* ys,
              const float* zs, size_t n, float* t, float* acc) {
  switch (p.kind) {
    case PrimitiveKind::Metaball: addTermsOfKind<metaballDistance>(blend, p, param, xs, ys, zs, n, t, acc); break;
    case PrimitiveKind::Ellipsoid: addTermsOfKind<ellipsoidDistance>(blend, p, param, xs, ys, zs, n, t, acc); break;
    case PrimitiveKind::LineSeg: addTermsOfKind<lineSegDistance>(blend, p, param, xs, ys, zs, n, t, acc); break;
  }
}

}  // namespace

void Field::accumulate(std::span<const glm::vec3> points, FieldScratch& scratch, bool keepTerms) const {
  if (points.empty()) return;
  const size_t n = splitPoints(points, scratch);
  atLeast(scratch.term, n);
  const bool additive = blend_.additive();
  const size_t sets = scratch.setCount();
  atLeast(scratch.acc, sets * n);
  scratch.setStarted.assign(sets, 0);
  if (keepTerms) atLeast(scratch.terms, scratch.candidates.size() * n);
  // Accumulate each candidate's terms into every local set holding it, candidates in ascending order (the order
  // every region and the point evaluation share). A set's first member is copied rather than added to the empty
  // value (0, or -1 for the elliptical fold): 0 + t and fold(-1, t) are exactly t, so the bits are the same.
  for (size_t k = 0; k < scratch.candidates.size(); ++k) {
    if (scratch.memberOffsets[k] == scratch.memberOffsets[k + 1]) {
      if (keepTerms) std::fill_n(scratch.terms.begin() + long(k * n), n, 0.0f);
      continue;
    }
    if (!keepTerms && additive && scratch.memberOffsets[k + 1] - scratch.memberOffsets[k] == 1) {
      // One set takes the terms: added in one pass (0 + t is exactly t, so a fresh set may start at 0).
      const uint32_t set = scratch.memberSets[scratch.memberOffsets[k]];
      float* acc = scratch.acc.data() + size_t(set) * n;
      if (!scratch.setStarted[set]) std::fill_n(acc, n, 0.0f);
      scratch.setStarted[set] = 1;
      const uint32_t p = scratch.candidates[k];
      addTerms(blend_, primitives_[p], params_[p], scratch.xs.data(), scratch.ys.data(), scratch.zs.data(), n,
               scratch.term.data(), acc);
      continue;
    }
    terms(scratch.candidates[k], 0, n, scratch);
    const float* t = scratch.term.data();
    if (keepTerms) std::copy(t, t + n, scratch.terms.begin() + long(k * n));
    for (uint32_t m = scratch.memberOffsets[k]; m < scratch.memberOffsets[k + 1]; ++m) {
      const uint32_t set = scratch.memberSets[m];
      float* acc = scratch.acc.data() + size_t(set) * n;
      if (!scratch.setStarted[set]) {
        std::copy(t, t + n, acc);
        scratch.setStarted[set] = 1;
      } else if (additive) {
        for (size_t i = 0; i < n; ++i) acc[i] += t[i];
      } else {
        for (size_t i = 0; i < n; ++i) acc[i] = foldElliptical(acc[i], t[i]);
      }
    }
  }
  for (size_t set = 0; set < sets; ++set)  // (every local set has a member, so this is only a safeguard)
    if (!scratch.setStarted[set]) std::fill_n(scratch.acc.begin() + long(set * n), n, additive ? 0.0f : -1.0f);
}

void Field::values(std::span<const glm::vec3> points, std::span<float> out, FieldScratch& scratch) const {
  IMPS_CHECK_EQ(points.size(), out.size());
  accumulate(points, scratch, /*keepTerms=*/false);
  maxOverSets(blend_.additive(), scratch.setCount(), points.size(), padded(points.size()), scratch.acc.data(),
              out.data());
}

namespace {

// Metaballs under the exponential blend with B >= -kSeparableHardness are evaluated on lattices separably: e^{-B} is
// then well inside float's range and no factor of a term above the cutoff is subnormal.
constexpr float kSeparableHardness = 40.0f;

// The products (a[q] * s >= cutoff ? a[q] * s : 0) added to acc[q], q in [0, n): one run of a metaball's terms.
inline void addScaledTerms(const float* __restrict a, float s, size_t n, float* __restrict acc) {
  for (size_t q = 0; q < n; ++q) {
    const float c = a[q] * s;
    acc[q] += c >= kExponentialCutoff ? c : 0.0f;
  }
}

// latticeValues()' pass for one such metaball: its term e^{B (d - 1)}, d = (vx^2 + vy^2 + vz^2) / r^2, is the product
// (ex[i] ey[j]) ez[k] of per-axis exponentials ex = e^{B vx^2 / r^2}, ey likewise (both <= 1; ex is 0 outside
// [i0, i1), where the support box ends) and ez = e^{B vz^2 / r^2 - B}: a multiply per point instead of an exponential.
// Adds the terms (0 below the cutoff, as exponentialTerm() has it) to acc at the rows j in [j0, j1) of the slices k in
// [k0, k1) that `rows` (null: all) wants, a whole slice's rows as one run. Rows whose ey ez is below the cutoff are
// trimmed from both ends: ex ey <= ey, so each of their products is too. exy: scratch of nx ny floats. The result
// depends only on the point and the primitive, never on the lattice around it.
IMPS_VECTOR_CLONES void addSeparableMetaball(const float* ex, const float* ey, size_t j0, size_t j1, const float* ez,
                                             size_t k0, size_t k1, size_t nx, size_t ny, const uint8_t* rows,
                                             const uint8_t* wholeSlice, float* exy, float* acc) {
  for (size_t j = j0; j < j1; ++j)
    for (size_t i = 0; i < nx; ++i) exy[i + nx * j] = ex[i] * ey[j];
  for (size_t k = k0; k < k1; ++k) {
    size_t ja = j0, jb = j1;
    while (ja < jb && ey[ja] * ez[k] < kExponentialCutoff) ++ja;
    while (jb > ja && ey[jb - 1] * ez[k] < kExponentialCutoff) --jb;
    float* slice = acc + nx * ny * k;
    if (!rows || wholeSlice[k]) {
      addScaledTerms(exy + nx * ja, ez[k], nx * (jb - ja), slice + nx * ja);
      continue;
    }
    for (size_t j = ja; j < jb; ++j)
      if (rows[j + ny * k]) addScaledTerms(exy + nx * j, ez[k], nx, slice + nx * j);
  }
}

// e^{a[q]} in place, q in [0, n).
IMPS_VECTOR_CLONES void exponentials(size_t n, float* a) {
  for (size_t q = 0; q < n; ++q) a[q] = expAccurate(a[q]);
}

}  // namespace

bool Field::separableOnLattice(uint32_t p) const {
  return blend_.kind == BlendKind::Exponential && !blend_.fastExp && primitives_[p].kind == PrimitiveKind::Metaball &&
         params_[p] >= -kSeparableHardness;
}

bool Field::separableOnLattice(const FieldScratch& scratch) const {
  return std::ranges::all_of(scratch.candidates, [&](uint32_t p) { return separableOnLattice(p); });
}

void Field::latticeValues(std::span<const float> xs, std::span<const float> ys, std::span<const float> zs,
                          std::span<float> out, FieldScratch& scratch, std::span<const uint8_t> rows) const {
  const size_t nx = xs.size(), ny = ys.size(), nz = zs.size(), n = nx * ny * nz;
  IMPS_CHECK_EQ(out.size(), n);
  IMPS_CHECK(rows.empty() || rows.size() == ny * nz);
  // The points in SoA form, for the candidates not evaluated separably: the first z slice's x and y element by
  // element, then whole slices copied (a few long copies instead of one short copy per row).
  if (!separableOnLattice(scratch)) {
    atLeast(scratch.xs, n);
    atLeast(scratch.ys, n);
    atLeast(scratch.zs, n);
    atLeast(scratch.term, n);
    const size_t slice = nx * ny;
    for (size_t j = 0; j < ny; ++j)
      for (size_t i = 0; i < nx; ++i) {
        scratch.xs[i + nx * j] = xs[i];
        scratch.ys[i + nx * j] = ys[j];
      }
    for (size_t k = 0; k < nz; ++k) {
      if (k > 0) {
        std::copy_n(scratch.xs.begin(), slice, scratch.xs.begin() + long(slice * k));
        std::copy_n(scratch.ys.begin(), slice, scratch.ys.begin() + long(slice * k));
      }
      std::fill_n(scratch.zs.begin() + long(slice * k), slice, zs[k]);
    }
  }
  const bool additive = blend_.additive();
  const size_t sets = scratch.setCount();
  // Every set starts at "nothing" (0, or -1 for the elliptical fold) and takes each term by value()'s arithmetic,
  // candidates ascending; a point a candidate's support box misses would only have taken an exact "nothing" from it.
  // One additive set sums straight into `out`: its sums of terms >= 0 from +0 are what max(0, sum) would give.
  const bool direct = additive && sets == 1;
  if (!direct) atLeast(scratch.acc, sets * n);
  float* accs = direct ? out.data() : scratch.acc.data();
  std::fill_n(accs, sets * n, additive ? 0.0f : -1.0f);
  // The half-open index range of the axis coordinates in [lo, hi] (Box::contains' test).
  auto inside = [](std::span<const float> axis, float lo, float hi) {
    return std::pair{size_t(std::lower_bound(axis.begin(), axis.end(), lo) - axis.begin()),
                     size_t(std::upper_bound(axis.begin(), axis.end(), hi) - axis.begin())};
  };
  // The slices whose every row is wanted.
  auto& wholeSlice = scratch.wholeSlice;
  wholeSlice.assign(nz, 1);
  for (size_t z = 0; z < nz && !rows.empty(); ++z)
    for (size_t j = 0; j < ny; ++j)
      if (rows[j + ny * z] == 0) wholeSlice[z] = 0;
  // The separable candidates' per-axis exponentials e^{scale v^2 + offset} (v: the coordinate less the centre's; see
  // addSeparableMetaball), nx + ny + nz per candidate, all in one vectorised pass: one short call per axis and
  // candidate would wait on each exponential's latency.
  const size_t axisLength = nx + ny + nz, candidates = scratch.candidates.size();
  atLeast(scratch.axisTerms, candidates * axisLength + nx * ny);
  float* const exy = scratch.axisTerms.data() + candidates * axisLength;
  for (size_t k = 0; k < candidates; ++k) {
    float* a = scratch.axisTerms.data() + k * axisLength;
    const uint32_t p = scratch.candidates[k];
    if (scratch.memberOffsets[k] == scratch.memberOffsets[k + 1] || !separableOnLattice(p)) {
      std::fill_n(a, axisLength, 0.0f);
      continue;
    }
    const Primitive& prim = primitives_[p];
    const float scale = params_[p] / (prim.radius * prim.radius);
    auto arguments = [&](std::span<const float> axis, float centre, float offset, float* to) {
      for (size_t q = 0; q < axis.size(); ++q) {
        const float v = axis[q] - centre;
        to[q] = scale * (v * v) + offset;
      }
    };
    arguments(xs, prim.center.x, 0.0f, a);
    arguments(ys, prim.center.y, 0.0f, a + nx);
    arguments(zs, prim.center.z, -params_[p], a + nx + ny);
  }
  exponentials(candidates * axisLength, scratch.axisTerms.data());
  for (size_t k = 0; k < candidates; ++k) {
    const uint32_t first = scratch.memberOffsets[k], last = scratch.memberOffsets[k + 1];
    if (first == last) continue;
    const uint32_t p = scratch.candidates[k];
    const Primitive& prim = primitives_[p];
    const Box& box = supportBoxes_[p];
    const auto [i0, i1] = inside(xs, box.lo.x, box.hi.x);
    const auto [j0, j1] = inside(ys, box.lo.y, box.hi.y);
    const auto [z0, z1] = inside(zs, box.lo.z, box.hi.z);
    if (i0 >= i1 || j0 >= j1 || z0 >= z1) continue;
    const bool single = additive && last - first == 1;
    float* acc0 = accs + size_t(scratch.memberSets[first]) * n;
    if (separableOnLattice(p)) {
      float* ex = scratch.axisTerms.data() + k * axisLength;
      const float* ey = ex + nx;
      const float* ez = ey + ny;
      std::fill(ex, ex + i0, 0.0f);  // ex is 0 beyond the support box
      std::fill(ex + i1, ex + nx, 0.0f);
      for (uint32_t m = first; m < last; ++m)
        addSeparableMetaball(ex, ey, j0, j1, ez, z0, z1, nx, ny, rows.empty() ? nullptr : rows.data(),
                             wholeSlice.data(), exy, accs + size_t(scratch.memberSets[m]) * n);
      continue;
    }
    // Points [begin, end) take the candidate's terms.
    auto evaluate = [&](size_t begin, size_t end) {
      if (single) {  // the common case: one set takes the terms, in one pass
        addTerms(blend_, prim, params_[p], scratch.xs.data() + begin, scratch.ys.data() + begin,
                 scratch.zs.data() + begin, end - begin, scratch.term.data() + begin, acc0 + begin);
        return;
      }
      terms(p, begin, end - begin, scratch);
      const float* t = scratch.term.data() + begin;
      for (uint32_t m = first; m < last; ++m) {
        float* acc = accs + size_t(scratch.memberSets[m]) * n + begin;
        if (additive) {
          for (size_t i = 0; i < end - begin; ++i) acc[i] += t[i];
        } else {
          for (size_t i = 0; i < end - begin; ++i) acc[i] = foldElliptical(acc[i], t[i]);
        }
      }
    };
    // The candidate is evaluated on the rows its support box reaches (a metaball's: its support ball), that the
    // caller wants. Consecutive rows (in memory order: y, then z) make one run of points, from the box's first x in
    // its first row to its last x in its last row, so the loops are long enough to vectorise; points of a run that
    // the support misses take an exact "nothing".
    size_t runFirst = 0, runLast = 0;  // rows j + ny z, inclusive
    bool pending = false;
    auto addRows = [&, i0 = i0, i1 = i1](size_t firstRow, size_t lastRow) {
      if (pending && firstRow == runLast + 1) {
        runLast = lastRow;
        return;
      }
      if (pending) evaluate(i0 + nx * runFirst, i1 + nx * runLast);
      runFirst = firstRow;
      runLast = lastRow;
      pending = true;
    };
    // A metaball whose support ball holds every point of its box's lattice range needs no trimming.
    // A metaball's rows are trimmed to its support ball, unless that holds the box's whole lattice range: row
    // (y, z) is kept while vy^2 <= reach2 - vz^2, a superset (relative margins of 1e-3, far above float rounding) of
    // the rows where metaballDistance() = ((vx^2 + vy^2) + vz^2) / r^2 is at most supportSkip_ anywhere. Beyond it
    // value() skips the point, so the other rows take nothing from the metaball. The kept rows are consecutive.
    const float reach2 = supportSkip_[p] * (prim.radius * prim.radius) * (1.0f + 1e-3f);
    bool trim = false;
    if (prim.kind == PrimitiveKind::Metaball) {
      const glm::vec3 far = glm::max(glm::abs(glm::vec3(xs[i0], ys[j0], zs[z0]) - prim.center),
                                     glm::abs(glm::vec3(xs[i1 - 1], ys[j1 - 1], zs[z1 - 1]) - prim.center));
      trim = glm::dot(far, far) >= reach2 * (1.0f - 3e-3f);
      atLeast(scratch.rowReach, ny);
      for (size_t j = j0; j < j1; ++j) scratch.rowReach[j] = (ys[j] - prim.center.y) * (ys[j] - prim.center.y);
    }
    for (size_t z = z0; z < z1; ++z) {
      auto [ja, jb] = std::pair{j0, j1};
      if (trim) {
        const float vz = zs[z] - prim.center.z;
        const float limit = (reach2 - vz * vz) * (1.0f + 1e-3f) + 1e-12f;
        while (ja < jb && scratch.rowReach[ja] > limit) ++ja;
        while (jb > ja && scratch.rowReach[jb - 1] > limit) --jb;
      }
      if (rows.empty() || wholeSlice[z]) {
        if (ja < jb) addRows(ja + ny * z, jb - 1 + ny * z);
        continue;
      }
      for (size_t j = ja; j < jb; ++j) {
        if (!rows.empty() && !rows[j + ny * z]) continue;
        size_t end = j + 1;
        while (end < jb && (rows.empty() || rows[end + ny * z])) ++end;
        addRows(j + ny * z, end - 1 + ny * z);
        j = end;
      }
    }
    if (pending) evaluate(i0 + nx * runFirst, i1 + nx * runLast);
  }
  if (!direct) maxOverSets(additive, sets, n, n, accs, out.data());
}

float Field::value(const glm::vec3& x, FieldScratch& scratch) const {
  // The scalar twin of values(): same kernels, same order of operations, so the same bits.
  const size_t sets = scratch.setCount();
  const bool additive = blend_.additive();
  float* acc = scratch.acc.size() >= sets ? scratch.acc.data() : (scratch.acc.resize(sets), scratch.acc.data());
  for (size_t s = 0; s < sets; ++s) acc[s] = additive ? 0.0f : -1.0f;
  for (size_t k = 0; k < scratch.candidates.size(); ++k) {
    const uint32_t first = scratch.memberOffsets[k], last = scratch.memberOffsets[k + 1];
    if (first == last) continue;
    const uint32_t i = scratch.candidates[k];
    // Outside the padded support box, or clearly beyond the support, the kernel's term is exactly "nothing" (0, or
    // -1 for the elliptical blend, which the fold ignores): skip it. The margins keep this exact despite rounding.
    if (!supportBoxes_[i].contains(x)) continue;
    const float d = kernelDistance(primitives_[i], x.x, x.y, x.z);
    if (d > supportSkip_[i]) continue;
    const float t = kernelTerm(blend_, params_[i], d);
    for (uint32_t m = first; m < last; ++m) {
      float& a = acc[scratch.memberSets[m]];
      a = additive ? a + t : foldElliptical(a, t);
    }
  }
  float out = 0.0f;
  for (size_t s = 0; s < sets; ++s)
    out = std::max(out, additive ? acc[s] : (acc[s] > -1.0f ? std::max(1.0f + acc[s], 0.0f) : 0.0f));
  return out;
}

FieldSample Field::sample(const glm::vec3& x, FieldScratch& scratch) const {
  FieldSample out;
  const auto& cand = scratch.candidates;
  const size_t sets = scratch.setCount();
  if (sets == 0) return out;
  // Per-candidate terms at x, then each set's value in member order. This is value()'s arithmetic (sums in
  // ascending candidate order, skipped terms being exactly zero), so the maximum is exactly value(x). A candidate
  // whose padded support box misses x has no term there (the padding guarantees it), so it costs a box test only;
  // the additive blends get each distance's gradient in the same pass.
  const bool additive = blend_.additive();
  const float none = additive ? 0.0f : -1.0f;
  auto& t = scratch.pointTerms;
  auto& dist = scratch.pointDistances;
  auto& dGrad = scratch.pointGradients;
  t.resize(cand.size());
  dist.resize(cand.size());
  dGrad.resize(cand.size());
  for (size_t k = 0; k < cand.size(); ++k) {
    const uint32_t i = cand[k];
    t[k] = none;
    if (!supportBoxes_[i].contains(x)) continue;
    const float d =
        additive ? kernelDistanceGradient(primitives_[i], x, dGrad[k]) : kernelDistance(primitives_[i], x.x, x.y, x.z);
    dist[k] = d;
    if (d <= supportSkip_[i]) t[k] = kernelTerm(blend_, params_[i], d);
  }
  int best = 0;
  float bestValue = -1.0f;
  for (size_t s = 0; s < sets; ++s) {
    float v;
    if (blend_.additive()) {
      v = 0.0f;
      for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m) v += t[scratch.setMembers[m]];
    } else {
      float g = -1.0f;
      for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m)
        g = foldElliptical(g, t[scratch.setMembers[m]]);
      v = g > -1.0f ? std::max(1.0f + g, 0.0f) : 0.0f;
    }
    if (v > bestValue) {
      bestValue = v;
      best = static_cast<int>(s);
    }
  }
  out.value = std::max(bestValue, 0.0f);
  scratch.lastWinner = static_cast<uint32_t>(best);
  // Gradient, colour and owner from the winning set.
  glm::vec3 color(0.0f);
  float weightSum = 0.0f, bestWeight = -1.0f;
  for (uint32_t m = scratch.setOffsets[best]; m < scratch.setOffsets[best + 1]; ++m) {
    const uint32_t k = scratch.setMembers[m];
    const uint32_t i = cand[k];
    const float w = blend_.additive() ? t[k] : t[k] + 1.0f;
    if (w <= 0.0f) continue;
    if (additive) out.gradient += kernelTermSlope(blend_, params_[i], dist[k], t[k]) * dGrad[k];
    color += w * colors_[i];
    weightSum += w;
    if (w > bestWeight) {
      bestWeight = w;
      out.owner = static_cast<int>(i);
    }
  }
  if (weightSum > 0.0f) out.color = color / weightSum;
  if (!blend_.additive() && out.owner >= 0) {
    // The folded rounded union has no convenient closed-form gradient: central differences.
    const float h = 1e-3f * primitives_[static_cast<size_t>(out.owner)].minRadius();
    for (int a = 0; a < 3; ++a) {
      glm::vec3 xp = x, xm = x;
      xp[a] += h;
      xm[a] -= h;
      out.gradient[a] = (value(xp, scratch) - value(xm, scratch)) / (2.0f * h);
    }
  }
  return out;
}

void Field::contributions(const glm::vec3& x, FieldScratch& scratch,
                          std::vector<std::pair<uint32_t, float>>& out) const {
  out.clear();
  const auto& cand = scratch.candidates;
  const size_t sets = scratch.setCount();
  if (sets == 0) return;
  // sample()'s terms and winning set (the first maximum), without the gradient.
  const bool additive = blend_.additive();
  auto& t = scratch.pointTerms;
  t.assign(cand.size(), additive ? 0.0f : -1.0f);
  for (size_t k = 0; k < cand.size(); ++k) {
    const uint32_t i = cand[k];
    if (!supportBoxes_[i].contains(x)) continue;
    const float d = kernelDistance(primitives_[i], x.x, x.y, x.z);
    if (d <= supportSkip_[i]) t[k] = kernelTerm(blend_, params_[i], d);
  }
  size_t best = 0;
  float bestValue = -1.0f;
  for (size_t s = 0; s < sets; ++s) {
    float v = additive ? 0.0f : -1.0f;
    for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m)
      v = additive ? v + t[scratch.setMembers[m]] : foldElliptical(v, t[scratch.setMembers[m]]);
    if (!additive) v = v > -1.0f ? std::max(1.0f + v, 0.0f) : 0.0f;
    if (v > bestValue) {
      bestValue = v;
      best = s;
    }
  }
  for (uint32_t m = scratch.setOffsets[best]; m < scratch.setOffsets[best + 1]; ++m) {
    const uint32_t k = scratch.setMembers[m];
    const float w = additive ? t[k] : t[k] + 1.0f;
    if (w > 0.0f) out.emplace_back(cand[k], w);
  }
  std::sort(out.begin(), out.end());
}

void Field::samplesOfOneSet(std::span<const glm::vec3> points, std::span<FieldSample> out,
                            FieldScratch& scratch) const {
  if (points.empty()) return;
  const size_t n = splitPoints(points, scratch);
  FieldScratch::Lanes& l = scratch.lanes;
  for (auto* v : {&l.d, &l.gx, &l.gy, &l.gz, &l.cr, &l.cg, &l.cb, &l.weight, &l.bestWeight}) v->assign(n, 0.0f);
  // (l.d: the value; l.bestWeight from 0: only positive terms own a point)
  l.owner.assign(n, -1);
  const float *xs = scratch.xs.data(), *ys = scratch.ys.data(), *zs = scratch.zs.data();
  // The set's members, ascending, two at a time where two of one kind follow each other.
  auto member = [&](size_t k) { return scratch.memberOffsets[k] != scratch.memberOffsets[k + 1]; };
  auto step = [&]<size_t K>(const std::array<uint32_t, K>& p) {
    std::array<const Primitive*, K> ps;
    std::array<float, K> params;
    std::array<glm::vec3, K> cs;
    std::array<int32_t, K> candidates;
    for (size_t k = 0; k < K; ++k) {
      ps[k] = &primitives_[p[k]];
      params[k] = params_[p[k]];
      cs[k] = colors_[p[k]];
      candidates[k] = int32_t(p[k]);
    }
    switch (ps[0]->kind) {
      case PrimitiveKind::Metaball:
        addSampleTermsOfKind<metaballDistanceGradient, K>(blend_, ps, params, cs, candidates, n, xs, ys, zs, l);
        break;
      case PrimitiveKind::Ellipsoid:
        addSampleTermsOfKind<ellipsoidDistanceGradient, K>(blend_, ps, params, cs, candidates, n, xs, ys, zs, l);
        break;
      case PrimitiveKind::LineSeg:
        addSampleTermsOfKind<lineSegDistanceGradient, K>(blend_, ps, params, cs, candidates, n, xs, ys, zs, l);
        break;
    }
  };
  const size_t nc = scratch.candidates.size();
  for (size_t k = 0; k < nc; ++k) {
    if (!member(k)) continue;
    size_t next = k + 1;
    while (next < nc && !member(next)) ++next;
    const uint32_t p = scratch.candidates[k];
    if (next < nc && primitives_[scratch.candidates[next]].kind == primitives_[p].kind) {
      step(std::array<uint32_t, 2>{p, scratch.candidates[next]});
      k = next;
    } else {
      step(std::array<uint32_t, 1>{p});
    }
  }
  for (size_t i = 0; i < points.size(); ++i) {
    out[i].value = std::max(l.d[i], 0.0f);
    out[i].gradient = glm::vec3(l.gx[i], l.gy[i], l.gz[i]);
    out[i].color = l.weight[i] > 0.0f ? glm::vec3(l.cr[i], l.cg[i], l.cb[i]) / l.weight[i] : glm::vec3(0.8f);
    out[i].owner = l.owner[i];
  }
}

void Field::samples(std::span<const glm::vec3> points, std::span<FieldSample> out, FieldScratch& scratch) const {
  IMPS_CHECK_EQ(points.size(), out.size());
  const size_t n = points.size();
  if (!blend_.additive()) {
    for (size_t i = 0; i < n; ++i) out[i] = sample(points[i], scratch);
    return;
  }
  const auto& cand = scratch.candidates;
  const size_t sets = scratch.setCount();
  for (size_t i = 0; i < n; ++i) out[i] = FieldSample{};
  if (sets == 0) return;
  if (sets == 1) {
    samplesOfOneSet(points, out, scratch);
    return;
  }
  // Pass 1: every candidate's terms, accumulated per set exactly as values() does.
  // (The kernels run over the padded batch, np points; the winners and values of the padding are never read out.)
  accumulate(points, scratch, /*keepTerms=*/true);
  const size_t np = padded(n);
  // The winning set of each point (the first maximum, as sample() picks it) and the value.
  scratch.winner.assign(np, 0);
  for (size_t i = 0; i < np; ++i) {
    float best = -1.0f;
    for (size_t s = 0; s < sets; ++s)
      if (scratch.acc[s * np + i] > best) {
        best = scratch.acc[s * np + i];
        scratch.winner[i] = uint32_t(s);
      }
    if (i < n) out[i].value = std::max(best, 0.0f);
  }
  // Pass 2: gradient, colour and owner from the members of each point's winning set, one candidate at a time over
  // every point (vectorised): its distance gradient everywhere, then the points where it is a member of the
  // winning set with a positive term take its contribution. Per point this is sample()'s arithmetic in sample()'s
  // order (candidates ascending), so the bits are the same.
  auto& [d, dgx, dgy, dgz, gx, gy, gz, cr, cg, cb, weight, bestWeight, owner, use, isMember] = scratch.lanes;
  for (auto* v : {&d, &dgx, &dgy, &dgz}) v->resize(np);
  for (auto* v : {&gx, &gy, &gz, &cr, &cg, &cb, &weight}) v->assign(np, 0.0f);
  bestWeight.assign(np, -1.0f);
  owner.assign(np, -1);
  use.resize(np);
  isMember.resize(sets);
  const float *xs = scratch.xs.data(), *ys = scratch.ys.data(), *zs = scratch.zs.data();  // accumulate()'s SoA copy
  for (size_t k = 0; k < cand.size(); ++k) {
    const uint32_t first = scratch.memberOffsets[k], last = scratch.memberOffsets[k + 1];
    if (first == last) continue;
    const uint32_t p = cand[k];
    const float* t = scratch.terms.data() + k * np;
    std::fill(isMember.begin(), isMember.end(), uint8_t(0));
    for (uint32_t m = first; m < last; ++m) isMember[scratch.memberSets[m]] = 1;
    bool any = false;
    for (size_t i = 0; i < np; ++i) {
      use[i] = t[i] > 0.0f && isMember[scratch.winner[i]];
      any |= use[i] != 0;
    }
    if (!any) continue;
    const Primitive& prim = primitives_[p];
    switch (prim.kind) {
      case PrimitiveKind::Metaball:
        distanceGradientLoop<metaballDistanceGradient>(prim, xs, ys, zs, np, d.data(), dgx.data(), dgy.data(),
                                                       dgz.data());
        break;
      case PrimitiveKind::Ellipsoid:
        distanceGradientLoop<ellipsoidDistanceGradient>(prim, xs, ys, zs, np, d.data(), dgx.data(), dgy.data(),
                                                        dgz.data());
        break;
      case PrimitiveKind::LineSeg:
        distanceGradientLoop<lineSegDistanceGradient>(prim, xs, ys, zs, np, d.data(), dgx.data(), dgy.data(),
                                                      dgz.data());
        break;
    }
    const float param = params_[p];
    const glm::vec3 c = colors_[p];
    if (blend_.kind == BlendKind::Exponential) {
      for (size_t i = 0; i < np; ++i) d[i] = param * t[i];  // kernelTermSlope(): no second exponential
    } else {
      for (size_t i = 0; i < np; ++i) d[i] = kernelTermSlope(blend_, param, d[i], t[i]);
    }
    accumulateGradientColour(np, use.data(), t, d.data(), dgx.data(), dgy.data(), dgz.data(), c, int32_t(p), gx.data(),
                             gy.data(), gz.data(), cr.data(), cg.data(), cb.data(), weight.data(), bestWeight.data(),
                             owner.data());
  }
  for (size_t i = 0; i < n; ++i) {
    out[i].gradient = glm::vec3(gx[i], gy[i], gz[i]);
    out[i].color = weight[i] > 0.0f ? glm::vec3(cr[i], cg[i], cb[i]) / weight[i] : glm::vec3(0.8f);
    out[i].owner = owner[i];
  }
}

namespace {

// The largest over the prepared local sets of the sum of their members' values t[k] (k: candidate position), at
// least 0: the additive blends' bounds from per-candidate bounds on the terms.
float largestSetSum(std::span<const float> t, const FieldScratch& scratch) {
  float best = 0.0f;
  for (size_t s = 0; s < scratch.setCount(); ++s) {
    float sum = 0.0f;
    for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m) sum += t[scratch.setMembers[m]];
    best = std::max(best, sum);
  }
  return best;
}

}  // namespace

float Field::upperBound(std::span<const float> minDistances, FieldScratch& scratch) const {
  const auto& cand = scratch.candidates;
  IMPS_CHECK_EQ(minDistances.size(), cand.size());
  if (!blend_.additive()) {
    for (size_t k = 0; k < cand.size(); ++k)
      if (minDistances[k] < support_[cand[k]]) return INFINITY;
    return 0.0f;
  }
  // Each set's sum is at most the sum of its members' largest terms in the box.
  auto& t = scratch.pointTerms;
  t.resize(cand.size());
  for (size_t k = 0; k < cand.size(); ++k) t[k] = blend_.term(minDistances[k], params_[cand[k]]);
  return largestSetSum(t, scratch);
}

float Field::lowerBound(const Box& box, const FieldScratch& scratch) const {
  // Every candidate is in some set, and a set is at least as large as any one member's term (the rounded union is
  // at least the larger of its arguments).
  float best = 0.0f;
  for (uint32_t i : scratch.candidates) {
    const float t = blend_.term(primitives_[i].maxDistance(box), params_[i]);
    best = std::max(best, blend_.additive() ? t : (t > -1.0f ? 1.0f + t : 0.0f));
  }
  return best;
}

float Field::lowerBound(std::span<const float> maxDistances, FieldScratch& scratch) const {
  const auto& cand = scratch.candidates;
  IMPS_CHECK_EQ(maxDistances.size(), cand.size());
  if (!blend_.additive()) {  // the rounded union is at least the larger of its arguments
    float best = 0.0f;
    for (size_t k = 0; k < cand.size(); ++k) {
      const float t = blend_.term(maxDistances[k], params_[cand[k]]);
      best = std::max(best, t > -1.0f ? 1.0f + t : 0.0f);
    }
    return best;
  }
  // Each set's sum is at least the sum of its members' smallest terms in the box. The distances are grown by a
  // relative 1e-3 first: every term then lies clearly below the evaluated one (float rounding of the distance and
  // the exponential is far smaller), also where the evaluated term is barely above the exponential's cut-off.
  auto& t = scratch.pointTerms;
  t.resize(cand.size());
  for (size_t k = 0; k < cand.size(); ++k)
    t[k] = blend_.term(maxDistances[k] * (1.0f + 1e-3f) + 1e-3f, params_[cand[k]]);
  return largestSetSum(t, scratch);
}

void Field::boxBounds(std::span<const Box> boxes, std::span<float> lower, std::span<float> upper,
                      FieldScratch& scratch) const {
  const auto& cand = scratch.candidates;
  const size_t nb = boxes.size(), nc = cand.size();
  IMPS_CHECK(lower.size() == nb && upper.size() == nb);
  if (!blend_.additive()) {  // rare: one box at a time
    for (size_t b = 0; b < nb; ++b) {
      auto& d = scratch.pointDistances;
      d.resize(nc);
      for (size_t k = 0; k < nc; ++k) d[k] = primitives_[cand[k]].minDistance(boxes[b]);
      upper[b] = upperBound(d, scratch);
      for (size_t k = 0; k < nc; ++k) d[k] = primitives_[cand[k]].maxDistance(boxes[b]);
      lower[b] = lowerBound(d, scratch);
    }
    return;
  }
  // Every candidate's smallest and largest kernel distance in each box (candidate-major: nb smallest, then nb
  // largest), shrunk and grown by a relative 1e-3 so that neither bound depends on the last bits of a distance or of
  // a term near the exponential's cut-off; then their terms, one vectorised pass per candidate.
  atLeast(scratch.term, 2 * nb * nc);
  float* t = scratch.term.data();
  for (size_t k = 0; k < nc; ++k) {
    const Primitive& p = primitives_[cand[k]];
    float* d = t + 2 * nb * k;
    for (size_t b = 0; b < nb; ++b) {
      float lo, hi;
      if (p.kind == PrimitiveKind::Metaball) {  // inline: the common case, and most of the cost
        const glm::vec3 near = glm::max(glm::max(boxes[b].lo - p.center, p.center - boxes[b].hi), glm::vec3(0.0f));
        const glm::vec3 far = glm::max(glm::abs(boxes[b].lo - p.center), glm::abs(boxes[b].hi - p.center));
        const float rr = p.radius * p.radius;
        lo = glm::dot(near, near) / rr;
        hi = glm::dot(far, far) / rr;
      } else {
        lo = p.minDistance(boxes[b], /*tight=*/false);
        hi = p.maxDistance(boxes[b]);
      }
      d[b] = std::max(lo * (1.0f - 1e-3f) - 1e-3f, 0.0f);
      d[nb + b] = hi * (1.0f + 1e-3f) + 1e-3f;
    }
    const float param = params_[cand[k]];
    switch (blend_.kind) {
      case BlendKind::Exponential:
        if (blend_.fastExp) termLoop<fastExponentialTerm>(param, 2 * nb, d);
        else termLoop<exponentialTerm>(param, 2 * nb, d);
        break;
      case BlendKind::BlancSchlick: termLoop<blancSchlickTerm>(param, 2 * nb, d); break;
      case BlendKind::Elliptical: break;
    }
  }
  // Each set's sum lies between the sums of its members' smallest and largest terms; F is the largest set.
  for (size_t b = 0; b < nb; ++b) {
    lower[b] = upper[b] = 0.0f;
    for (size_t s = 0; s < scratch.setCount(); ++s) {
      float lo = 0.0f, hi = 0.0f;
      for (uint32_t m = scratch.setOffsets[s]; m < scratch.setOffsets[s + 1]; ++m) {
        const float* d = t + 2 * nb * scratch.setMembers[m];
        hi += d[b];
        lo += d[nb + b];
      }
      lower[b] = std::max(lower[b], lo);
      upper[b] = std::max(upper[b], hi);
    }
  }
}

float Field::value(const glm::vec3& x) const {
  FieldScratch scratch;
  Box point;
  point.extend(x);
  prepare(point, scratch);
  return value(x, scratch);
}

FieldSample Field::sample(const glm::vec3& x) const {
  FieldScratch scratch;
  Box point;
  point.extend(x);
  prepare(point, scratch);
  return sample(x, scratch);
}

}  // namespace imps
