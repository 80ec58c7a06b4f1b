// SPDX-License-Identifier: MIT
// Blend functions: how primitives' normalised squared distances d combine into one field (thesis 2.2, A.3).
//
// Based on: J. Blinn, "A Generalization of Algebraic Surface Drawing", 1982 (exponential blend, eq. 2.2 of the
//           thesis); C. Blanc and C. Schlick, "Extended Field Functions for Soft Objects", 1995 (finite support with
//           a hardness parameter); A. Rockwood, "The Displacement Method for Implicit Blending Surfaces", 1989, as
//           presented in Bloomenthal et al., "Introduction to Implicit Surfaces", 1997 (elliptical pairwise blend);
//           N. Schraudolph, "A Fast, Compact Approximation of the Exponential Function", 1999.
//
// THE FIELD CONVENTION, stated once for the whole library: the field F(x) is >= 0, larger inside; the surface is
// F = iso (default 1, the thesis's isoValue); inside is F > iso. A lone primitive's surface is exactly its d = 1
// surface for iso 1 with every blend below.
//
//  Exponential  c(d) = exp(B (d - 1)), B < 0 the per-primitive blobbiness (closer to 0 = blobbier). Contributions
//               below kExponentialCutoff are dropped (exactly 0), which gives every primitive a finite support
//               d < 1 + ln(kExponentialCutoff) / B. F = sum of c over blending primitives.
//  BlancSchlick c(d) = ((D - d) / (D - 1))^2 for d < D, else 0, with support D = 1 + 1 / hardness. Harder
//               primitives have smaller support and blend less. C1 at the support boundary. F = sum of c.
//  Elliptical   pairwise rounded union of f_i = (1 - d_i) / range_i with a quarter-ellipse blend of width range_i
//               in each primitive's own units; F = 1 + union. A primitive with f_i <= -1 cannot affect the union
//               and is dropped (support d < 1 + range). Only exact for pairs: larger groups fold in primitive order.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "imps/scene.h"

namespace imps {

inline constexpr float kExponentialCutoff = 1e-4f;

// exp(x) to within 2 ulp of std::exp for x in [-87, 88], as a branch-free polynomial so that loops over it
// vectorise and every code path (vector lane, scalar tail, block, thread) gives bit-identical values.
inline float expAccurate(float x) {
  x = std::min(88.0f, std::max(-87.0f, x));  // (in this order a NaN, from a degenerate primitive, becomes -87)
  // Round x / ln 2 to the nearest integer with the 1.5 * 2^23 trick (exact for |x| < 2^22; no libm call).
  const float n = (x * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
  // Cody-Waite reduction: r = x - n ln2 with ln2 split in two for accuracy.
  float r = x - n * 0.693145751953125f;
  r = r - n * 1.42860682030941723212e-6f;
  // exp(r) on [-ln2/2, ln2/2]: degree-7 Taylor polynomial (truncation error < 1e-8).
  float p = 1.9841270e-4f;
  p = p * r + 1.3888889e-3f;
  p = p * r + 8.3333333e-3f;
  p = p * r + 4.1666667e-2f;
  p = p * r + 1.6666667e-1f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const int32_t bits = (static_cast<int32_t>(n) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

// Schraudolph's approximation: writes a*x + b straight into a float's exponent and mantissa bits. About 4% maximum
// relative error; the thesis's fast exponential.
inline float expFast(float x) {
  x = std::min(88.0f, std::max(-87.0f, x));  // (a NaN becomes -87, as in expAccurate)
  const int32_t bits =
      static_cast<int32_t>(12102203.0f * x) + 1064866808;  // 2^23/ln2; 127*2^23 - 486408 (Schraudolph's c)
  float y;
  std::memcpy(&y, &bits, sizeof y);
  return y;
}

// A blend function with its per-primitive default parameter. See the file comment for the formulas.
struct BlendFunction {
  BlendKind kind = BlendKind::Exponential;
  float defaultParam = -1.0f;  // B (< 0), hardness (> 0) or range (> 0), for primitives without their own
  bool fastExp = false;        // Exponential: use expFast instead of expAccurate

  // From a scene blend node (defaultParam = -1/variance, hardness or blendRange).
  static BlendFunction fromNode(const BlendNode& node);

  bool additive() const { return kind != BlendKind::Elliptical; }

  // The normalised squared distance beyond which a primitive with parameter `param` has no effect.
  float support(float param) const {
    switch (kind) {
      case BlendKind::Exponential: return 1.0f + std::log(kExponentialCutoff) / param;
      case BlendKind::BlancSchlick: return 1.0f + 1.0f / param;
      case BlendKind::Elliptical: return 1.0f + param;
    }
    return 1.0f;
  }

  // Additive kinds: the contribution c(d) and dc/dd. Elliptical: the primitive's scaled function f = (1 - d)/range
  // (and df/dd). Both are 0 (resp. -1 with f <= -1) beyond the support: callers treat that as "absent".
  float term(float d, float param) const {
    switch (kind) {
      case BlendKind::Exponential: {
        const float c = fastExp ? expFast(param * (d - 1.0f)) : expAccurate(param * (d - 1.0f));
        return c >= kExponentialCutoff ? c : 0.0f;
      }
      case BlendKind::BlancSchlick: {
        const float dMax = 1.0f + 1.0f / param;
        const float u = std::max(dMax - d, 0.0f) * param;  // (D - d) / (D - 1)
        return u * u;
      }
      case BlendKind::Elliptical: return std::max((1.0f - d) / param, -1.0f);
    }
    return 0.0f;
  }
  float termDerivative(float d, float param) const {
    switch (kind) {
      case BlendKind::Exponential: {
        const float c = term(d, param);
        return param * c;
      }
      case BlendKind::BlancSchlick: {
        const float dMax = 1.0f + 1.0f / param;
        const float u = std::max(dMax - d, 0.0f) * param;
        return -2.0f * u * param;
      }
      case BlendKind::Elliptical: return d < 1.0f + param ? -1.0f / param : 0.0f;
    }
    return 0.0f;
  }

  // Elliptical: the rounded union of two scaled functions (positive inside, blend width 1).
  static float roundedUnion(float x, float y) {
    const float ux = std::max(1.0f + x, 0.0f), uy = std::max(1.0f + y, 0.0f);
    return std::sqrt(ux * ux + uy * uy) - std::max(1.0f, -std::max(x, y));
  }
};

}  // namespace imps
