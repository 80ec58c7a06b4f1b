// Field evaluation: terms per primitive, combined per blend set, maximum over sets.
#include "imps/field.h"

#include <algorithm>
#include <cmath>

#include "imps/check.h"

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
  for (size_t i = 0; i < primitives_.size(); ++i) support_[i] = blend_.support(params_[i]);
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
  // Keep the cells of a coarse grid over the supports where F might reach iso.
  const Box all = bounds();
  if (all.empty()) return all;
  constexpr int kCells = 24;
  const glm::vec3 cell = all.size() / float(kCells);
  Box result;
  FieldScratch scratch;
  for (int k = 0; k < kCells; ++k)
    for (int j = 0; j < kCells; ++j)
      for (int i = 0; i < kCells; ++i) {
        Box c;
        c.lo = all.lo + cell * glm::vec3(i, j, k);
        c.hi = c.lo + cell;
        prepare(c, scratch);
        if (scratch.candidates.empty()) continue;
        if (upperBound(c, scratch) >= iso_) result.extend(c);
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

void Field::prepareSets(FieldScratch& scratch) const {
  const auto& cand = scratch.candidates;
  scratch.localSetOffsets.assign(1, 0);
  scratch.localSetMembers.clear();
  scratch.singleSet = sets_.count() == 1 && sets_.members.size() == primitives_.size();
  if (scratch.singleSet) {
    for (size_t k = 0; k < cand.size(); ++k) scratch.localSetMembers.push_back(static_cast<uint32_t>(k));
    scratch.localSetOffsets.push_back(static_cast<uint32_t>(cand.size()));
    return;
  }
  scratch.globalToLocal.resize(primitives_.size(), -1);
  for (size_t k = 0; k < cand.size(); ++k) scratch.globalToLocal[cand[k]] = static_cast<int32_t>(k);
  for (size_t s = 0; s < sets_.count(); ++s) {
    const size_t before = scratch.localSetMembers.size();
    for (uint32_t m : sets_.set(s))
      if (scratch.globalToLocal[m] >= 0) scratch.localSetMembers.push_back(static_cast<uint32_t>(scratch.globalToLocal[m]));
    if (scratch.localSetMembers.size() > before)
      scratch.localSetOffsets.push_back(static_cast<uint32_t>(scratch.localSetMembers.size()));
  }
  for (uint32_t c : cand) scratch.globalToLocal[c] = -1;
}

float Field::combine(const float* terms, size_t stride, size_t point, const FieldScratch& scratch,
                     int* winningSet) const {
  float best = 0.0f;
  const size_t setCount = scratch.localSetOffsets.size() - 1;
  for (size_t s = 0; s < setCount; ++s) {
    float v;
    if (blend_.additive()) {
      float sum = 0.0f;
      for (uint32_t m = scratch.localSetOffsets[s]; m < scratch.localSetOffsets[s + 1]; ++m)
        sum += terms[scratch.localSetMembers[m] * stride + point];
      v = sum;
    } else {
      bool present = false;
      float g = 0.0f;
      for (uint32_t m = scratch.localSetOffsets[s]; m < scratch.localSetOffsets[s + 1]; ++m) {
        const float x = terms[scratch.localSetMembers[m] * stride + point];
        if (x <= -1.0f) continue;
        g = present ? BlendFunction::roundedUnion(g, x) : x;
        present = true;
      }
      v = present ? std::fmax(1.0f + g, 0.0f) : 0.0f;
    }
    if (v > best) {
      best = v;
      if (winningSet) *winningSet = static_cast<int>(s);
    }
  }
  return best;
}

namespace {
// Terms of one primitive at many points. Kind and blend are hoisted out of the loop so it vectorises.
void primitiveTerms(const Primitive& p, const BlendFunction& blend, float param, std::span<const glm::vec3> points,
                    float* out) {
  const size_t n = points.size();
  switch (p.kind) {
    case PrimitiveKind::Metaball: {
      const float inv = 1.0f / (p.radius * p.radius);
      for (size_t i = 0; i < n; ++i) {
        const glm::vec3 v = points[i] - p.center;
        out[i] = (v.x * v.x + v.y * v.y + v.z * v.z) * inv;
      }
      break;
    }
    default:
      for (size_t i = 0; i < n; ++i) out[i] = p.distance(points[i]);
      break;
  }
  for (size_t i = 0; i < n; ++i) out[i] = blend.term(out[i], param);
}
}  // namespace

void Field::values(std::span<const glm::vec3> points, std::span<float> out, FieldScratch& scratch) const {
  IMPS_CHECK_EQ(points.size(), out.size());
  const auto& cand = scratch.candidates;
  const size_t n = points.size();
  scratch.terms.resize(cand.size() * n);
  for (size_t k = 0; k < cand.size(); ++k)
    primitiveTerms(primitives_[cand[k]], blend_, params_[cand[k]], points, scratch.terms.data() + k * n);
  for (size_t i = 0; i < n; ++i) out[i] = combine(scratch.terms.data(), n, i, scratch, nullptr);
}

float Field::value(const glm::vec3& x, FieldScratch& scratch) const {
  float v = 0.0f;
  values(std::span<const glm::vec3>(&x, 1), std::span<float>(&v, 1), scratch);
  return v;
}

FieldSample Field::sample(const glm::vec3& x, FieldScratch& scratch) const {
  FieldSample out;
  const auto& cand = scratch.candidates;
  scratch.terms.resize(cand.size());
  for (size_t k = 0; k < cand.size(); ++k)
    primitiveTerms(primitives_[cand[k]], blend_, params_[cand[k]], std::span<const glm::vec3>(&x, 1),
                   scratch.terms.data() + k);
  int set = -1;
  out.value = combine(scratch.terms.data(), 1, 0, scratch, &set);
  if (set < 0) return out;

  // Gradient, colour and owner from the winning set.
  glm::vec3 color(0.0f);
  float weightSum = 0.0f, bestWeight = -1.0f;
  for (uint32_t m = scratch.localSetOffsets[set]; m < scratch.localSetOffsets[set + 1]; ++m) {
    const uint32_t k = scratch.localSetMembers[m];
    const uint32_t i = cand[k];
    const float t = scratch.terms[k];
    const float w = blend_.additive() ? t : t + 1.0f;
    if (w <= 0.0f) continue;
    if (blend_.additive()) {
      glm::vec3 gd;
      const float d = primitives_[i].distance(x, gd);
      out.gradient += blend_.termDerivative(d, params_[i]) * gd;
    }
    color += w * colors_[i];
    weightSum += w;
    if (w > bestWeight) {
      bestWeight = w;
      out.owner = static_cast<int>(i);
    }
  }
  if (weightSum > 0.0f) out.color = color / weightSum;
  if (!blend_.additive()) {
    // The folded rounded union has no convenient closed-form gradient: central differences on the same set.
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

float Field::upperBound(const Box& box, const FieldScratch& scratch) const {
  if (!blend_.additive()) {
    for (uint32_t i : scratch.candidates)
      if (primitives_[i].minDistance(box) < support_[i]) return INFINITY;
    return 0.0f;
  }
  // Every set's sum is at most the sum over all candidates of each one's largest term in the box.
  float sum = 0.0f;
  for (uint32_t i : scratch.candidates) sum += blend_.term(primitives_[i].minDistance(box), params_[i]);
  return sum;
}

float Field::lowerBound(const Box& box, const FieldScratch& scratch) const {
  // Every primitive is in some set, and a set is at least as large as any one member's term (the rounded union is
  // at least the larger of its arguments).
  float best = 0.0f;
  for (uint32_t i : scratch.candidates) {
    const float t = blend_.term(primitives_[i].maxDistance(box), params_[i]);
    best = std::max(best, blend_.additive() ? t : (t > -1.0f ? 1.0f + t : 0.0f));
  }
  return best;
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
