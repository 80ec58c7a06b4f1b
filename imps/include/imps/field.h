// SPDX-License-Identifier: MIT
// The field of a posed character: world-space primitives, their blend and the blend sets that encode which
// primitives may blend (the unwanted-blending rule of thesis 3.7). Evaluates value, gradient and colour.
//
// F(x) = max over blend sets S of blend(S)(x). A flat scene has one set holding every primitive. A hierarchical one
// has the maximal cliques of its blend graph (blend_graph.h), so two primitives blend only if they are blend
// neighbours: a hand that touches a hip is unioned with it, never blended. The field convention (F >= 0, surface at
// iso, inside larger) is in blend.h.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "imps/blend.h"
#include "imps/primitives.h"

namespace imps {

// Sets of primitive indices in compressed form: set s is members[offsets[s] .. offsets[s+1]), ascending.
struct BlendSets {
  std::vector<uint32_t> offsets{0};
  std::vector<uint32_t> members;
  size_t count() const { return offsets.size() - 1; }
  std::span<const uint32_t> set(size_t s) const {
    return {members.data() + offsets[s], members.data() + offsets[s + 1]};
  }
  void add(std::span<const uint32_t> sortedMembers);
  // One set with primitives 0..n-1.
  static BlendSets all(size_t n);
};

// Value, gradient, colour and owner at one point.
struct FieldSample {
  float value = 0.0f;
  glm::vec3 gradient{0.0f};
  glm::vec3 color{0.8f};
  int owner = -1;  // the primitive contributing most in the winning set (the thesis's particle owner), -1 if none
};

// Reusable per-thread scratch for batched evaluation: the candidate primitives of a region and the blend sets
// restricted to them (Field::prepare). No allocation on the hot path once warmed up.
struct FieldScratch {
  std::vector<uint32_t> candidates;             // ascending primitive indices
  std::vector<uint32_t> setOffsets, setMembers;  // local sets (CSR over candidate positions), deduplicated
  std::vector<uint32_t> memberOffsets, memberSets;  // for each candidate, the local sets holding it (CSR)
  std::vector<float> xs, ys, zs, term, acc;      // points (SoA), one primitive's terms, per-set accumulators
  std::vector<float> terms;                       // samples(): every candidate's terms
  std::vector<uint32_t> winner;                  // samples(): each point's winning set
  uint32_t lastWinner = 0;                        // sample(): the winning local set of the last call
  std::vector<uint8_t> setStarted;               // accumulate(): which sets hold a value yet
  std::vector<uint8_t> wholeSlice;               // latticeValues(): the slices whose every row is wanted
  std::vector<float> rowReach;                   // latticeValues(): a metaball's squared y offset of each row
  std::vector<float> axisTerms;                  // latticeValues(): a metaball's per-axis exponentials
  std::vector<int32_t> globalToLocal;
  // Working storage of single calls, kept here so a worker reuses it from call to call (no allocation once grown)
  // and no two workers share it. Each belongs to one function: calls that nest (samples() -> sample()) never alias.
  std::vector<uint32_t> restrictOffsets, restrictMembers, fill;  // prepareSets()
  std::vector<float> pointTerms, pointDistances;                 // sample(), contributions(), the bounds
  std::vector<glm::vec3> pointGradients;                         // sample()
  struct Lanes {                                                 // samples(): one value per point
    std::vector<float> d, dgx, dgy, dgz, gx, gy, gz, cr, cg, cb, weight, bestWeight;
    std::vector<int32_t> owner;
    std::vector<uint8_t> use, isMember;
  } lanes;
  size_t setCount() const { return setOffsets.size() - 1; }
};

class Field {
 public:
  Field() = default;
  // `params`: per-primitive blend parameter; `colors`: per-primitive diffuse colour. Sizes must match.
  Field(std::vector<Primitive> primitives, std::vector<float> params, std::vector<glm::vec3> colors,
        BlendFunction blend, BlendSets sets, float iso = 1.0f);

  size_t size() const { return primitives_.size(); }
  float iso() const { return iso_; }
  const BlendFunction& blend() const { return blend_; }
  const BlendSets& sets() const { return sets_; }
  const std::vector<Primitive>& primitives() const { return primitives_; }
  const Primitive& primitive(size_t i) const { return primitives_[i]; }
  float param(size_t i) const { return params_[i]; }
  glm::vec3 color(size_t i) const { return colors_[i]; }
  // Replaces the world-space primitives (same count and order), e.g. after a new pose.
  void setPrimitives(std::vector<Primitive> primitives);

  // Support of primitive i: where it can affect F (d < supportDistance(i)), and its box.
  float supportDistance(size_t i) const { return support_[i]; }
  const Box& supportBox(size_t i) const { return supportBoxes_[i]; }
  // Union of every support box: F is exactly 0 outside it.
  Box bounds() const;
  // A box enclosing every point with F >= iso (conservative, much tighter than bounds()).
  Box surfaceBounds() const;

  // Point evaluation over every primitive (culled by support boxes).
  float value(const glm::vec3& x) const;
  FieldSample sample(const glm::vec3& x) const;

  // Batched evaluation over a region. prepare() collects the primitives whose support box overlaps `region`;
  // the other calls then evaluate points inside `region` using only those. Values are bit-identical to value(x)
  // for every point in the region, whatever the region (latticeValues(): a function of the point alone, see there):
  // this is what lets polygonizers split space into blocks and threads and still agree exactly on shared samples.
  void prepare(const Box& region, FieldScratch& scratch) const;
  void prepare(std::span<const uint32_t> candidates, FieldScratch& scratch) const;
  void values(std::span<const glm::vec3> points, std::span<float> out, FieldScratch& scratch) const;
  // values() at the points of a lattice inside the prepared region: out[i + nx (j + ny k)] is F at
  // (xs[i], ys[j], zs[k]), the axis coordinates ascending, out.size() == nx ny nz. Each candidate is evaluated only
  // on the lattice rows its support box (a metaball's: its support ball) reaches (its term is exactly nothing
  // elsewhere), which is much cheaper than values() when the primitives are small against the lattice.
  // Bit-identical to value(), but for metaballs under the exponential blend (B >= -40): their terms are products of
  // per-axis exponentials, within a relative 1e-5 of value()'s and the same where the cutoff falls, to rounding.
  // Either way each value is a function of the point alone (its coordinates and the primitives whose support reaches
  // it), so lattices that share points agree on them bit for bit, whatever their extent and candidates.
  // `rows`, when not empty (ny nz entries), says which rows along x are wanted: rows[j + ny k] == 0 leaves row
  // (ys[j], zs[k]) out, its values 0 (not F), for callers that know the field there by other means.
  void latticeValues(std::span<const float> xs, std::span<const float> ys, std::span<const float> zs,
                     std::span<float> out, FieldScratch& scratch, std::span<const uint8_t> rows = {}) const;
  // Whether latticeValues() evaluates every prepared candidate separably: a lattice then costs a multiply per point
  // and candidate, about what bounding parts of it would.
  bool separableOnLattice(const FieldScratch& scratch) const;
  float value(const glm::vec3& x, FieldScratch& scratch) const;
  FieldSample sample(const glm::vec3& x, FieldScratch& scratch) const;
  // The blend weights at x that sample() blends colours with: every member of the winning set with a positive
  // weight (its term; the term + 1 under the elliptical fold), as (primitive, weight) pairs, primitives ascending,
  // into `out` (cleared first). Empty where F is nothing. x must be inside the prepared region.
  void contributions(const glm::vec3& x, FieldScratch& scratch, std::vector<std::pair<uint32_t, float>>& out) const;
  // sample() at many points at once, vectorised; identical results.
  void samples(std::span<const glm::vec3> points, std::span<FieldSample> out, FieldScratch& scratch) const;

  // Conservative bounds of F over a box inside the prepared region: lower <= F(x) <= upper for all x in box.
  // upperBound() takes what it needs of the box, minDistances[k] <= the smallest kernel distance of candidate k
  // (scratch.candidates[k]) in the box, e.g. its Primitive::minDistance(box), which callers often have already.
  float upperBound(std::span<const float> minDistances, FieldScratch& scratch) const;
  float lowerBound(const Box& box, const FieldScratch& scratch) const;
  // A tighter lower bound for the additive blends: each set's sum of its members' smallest terms, the largest over
  // the sets (the elliptical blend: the largest single term, as above). maxDistances[k] >= the largest kernel
  // distance of candidate k in the box, e.g. its Primitive::maxDistance(box).
  float lowerBound(std::span<const float> maxDistances, FieldScratch& scratch) const;
  // lower[b] <= F(x) <= upper[b] for every x in boxes[b] (inside the prepared region), for many boxes at once:
  // lowerBound(maxDistances) and upperBound() with a relative 1e-3 margin on every distance, vectorised.
  void boxBounds(std::span<const Box> boxes, std::span<float> lower, std::span<float> upper,
                 FieldScratch& scratch) const;

 private:
  void prepareSets(FieldScratch& scratch) const;
  bool separableOnLattice(uint32_t primitive) const;
  // samples() for an additive blend with one local set (a flat scene): one pass per candidate over the points.
  void samplesOfOneSet(std::span<const glm::vec3> points, std::span<FieldSample> out, FieldScratch& scratch) const;
  // Terms of primitive i at scratch.xs/ys/zs[first, first + n) into scratch.term[first, first + n).
  void terms(size_t i, size_t first, size_t n, FieldScratch& scratch) const;
  // Every candidate's terms at the points, combined per local set into scratch.acc (sets x points); with
  // keepTerms, each candidate's terms are also kept in scratch.terms (candidates x points).
  void accumulate(std::span<const glm::vec3> points, FieldScratch& scratch, bool keepTerms) const;

  std::vector<Primitive> primitives_;
  std::vector<float> params_;
  std::vector<glm::vec3> colors_;
  std::vector<float> support_;
  std::vector<float> supportSkip_;  // d beyond which a term is certainly nothing (support plus a rounding margin)
  std::vector<Box> supportBoxes_;
  BlendFunction blend_;
  BlendSets sets_;
  float iso_ = 1.0f;
};

}  // namespace imps
