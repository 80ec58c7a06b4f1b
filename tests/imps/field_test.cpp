// SPDX-License-Identifier: MIT
// Field: blend functions, the exponential approximations, batched vs point evaluation, gradients, colours.
#include "imps/field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include <glm/gtc/quaternion.hpp>

namespace imps {
namespace {

Field makeField(std::vector<Primitive> prims, BlendFunction blend, BlendSets sets = {}) {
  const size_t n = prims.size();
  std::vector<float> params(n, blend.defaultParam);
  std::vector<glm::vec3> colors(n);
  for (size_t i = 0; i < n; ++i) colors[i] = glm::vec3(float(i % 2), float((i + 1) % 2), 0.5f);
  if (sets.count() == 0) sets = BlendSets::all(n);
  return Field(std::move(prims), std::move(params), std::move(colors), blend, std::move(sets));
}

// Random primitives: `metaballs` metaballs, then `segments` line segments, then `ellipsoids` ellipsoids; points
// drawn from u, radii from r.
std::vector<Primitive> randomPrimitives(std::mt19937& rng, std::uniform_real_distribution<float>& u,
                                        std::uniform_real_distribution<float>& r, int metaballs, int segments,
                                        int ellipsoids = 0) {
  std::vector<Primitive> prims;
  for (int i = 0; i < metaballs; ++i) prims.push_back(Primitive::metaball({u(rng), u(rng), u(rng)}, r(rng)));
  for (int i = 0; i < segments; ++i)
    prims.push_back(Primitive::lineSeg({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, r(rng), r(rng)));
  for (int i = 0; i < ellipsoids; ++i)
    prims.push_back(Primitive::ellipsoid({u(rng), u(rng), u(rng)},
                                         glm::angleAxis(u(rng) * 3.0f, glm::normalize(glm::vec3(u(rng), u(rng), 1))),
                                         {r(rng), r(rng), r(rng)}));
  return prims;
}

TEST(Field, ExpAccurateIsWithinTwoUlpOfStdExp) {
  for (float x = -80.0f; x < 80.0f; x += 0.0137f) {
    const float exact = std::exp(x), approx = expAccurate(x);
    EXPECT_NEAR(approx, exact, 2.5e-7f * exact) << x;
  }
}

TEST(Field, SchraudolphExpIsWithinFourPercent) {
  for (float x = -20.0f; x < 20.0f; x += 0.01f) EXPECT_NEAR(expFast(x) / std::exp(x), 1.0f, 0.04f) << x;
}

TEST(Field, LoneMetaballSurfaceIsItsRadiusForEveryBlend) {
  for (BlendKind kind : {BlendKind::Exponential, BlendKind::BlancSchlick, BlendKind::Elliptical}) {
    BlendFunction blend;
    blend.kind = kind;
    blend.defaultParam = kind == BlendKind::Exponential ? -2.0f : 0.7f;
    const Field f = makeField({Primitive::metaball({0, 0, 0}, 0.5f)}, blend);
    EXPECT_NEAR(f.value({0.5f, 0, 0}), 1.0f, 1e-5f);
    EXPECT_GT(f.value({0.45f, 0, 0}), 1.0f);
    EXPECT_LT(f.value({0.55f, 0, 0}), 1.0f);
    EXPECT_EQ(f.value({5.0f, 0, 0}), 0.0f) << "finite support";
  }
}

TEST(Field, ExponentialBlendAddsContributions) {
  BlendFunction blend;  // Exponential, B = -1
  const Field two =
      makeField({Primitive::metaball({-0.5f, 0, 0}, 0.6f), Primitive::metaball({0.5f, 0, 0}, 0.6f)}, blend);
  const Field one = makeField({Primitive::metaball({-0.5f, 0, 0}, 0.6f)}, blend);
  const glm::vec3 mid(0, 0, 0);
  EXPECT_NEAR(two.value(mid), 2.0f * one.value(mid), 1e-6f);
  EXPECT_GT(two.value(mid), 1.0f) << "the two balls are joined by a blend";
}

TEST(Field, HardnessReducesBlancSchlickBlending) {
  BlendFunction soft, hard;
  soft.kind = hard.kind = BlendKind::BlancSchlick;
  soft.defaultParam = 0.3f;
  hard.defaultParam = 3.0f;
  const std::vector<Primitive> prims = {Primitive::metaball({-0.55f, 0, 0}, 0.5f),
                                        Primitive::metaball({0.55f, 0, 0}, 0.5f)};
  EXPECT_GT(makeField(prims, soft).value({0, 0, 0}), 1.0f);
  EXPECT_LT(makeField(prims, hard).value({0, 0, 0}), 1.0f);
}

TEST(Field, EllipticalBlendIsAUnionAwayFromTheJoin) {
  BlendFunction blend;
  blend.kind = BlendKind::Elliptical;
  blend.defaultParam = 0.5f;
  const Field f = makeField({Primitive::metaball({-1, 0, 0}, 0.5f), Primitive::metaball({1, 0, 0}, 0.5f)}, blend);
  EXPECT_NEAR(f.value({-1.5f, 0, 0}), 1.0f, 1e-5f);  // far side of the left ball: its own surface
  EXPECT_NEAR(f.value({1, 0.5f, 0}), 1.0f, 1e-5f);
  // Close together, the rounded union fills the crease.
  const Field close =
      makeField({Primitive::metaball({-0.45f, 0, 0}, 0.5f), Primitive::metaball({0.45f, 0, 0}, 0.5f)}, blend);
  EXPECT_GT(close.value({0, 0.25f, 0}), 1.0f);
}

// values() is value() at every point, bit for bit, in batches of every length.
TEST(Field, BatchedValuesAreBitIdenticalToPointValues) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.5f, 1.5f), r(0.1f, 0.3f);
  const std::vector<Primitive> prims = randomPrimitives(rng, u, r, 40, 10);
  BlendFunction blend;
  blend.defaultParam = -3.0f;
  const Field f = makeField(prims, blend);
  FieldScratch scratch;
  for (int n = 0; n < 50; ++n) {
    Box region;
    region.extend({u(rng), u(rng), u(rng)});
    region.extend(region.lo + glm::vec3(0.4f));
    f.prepare(region, scratch);
    std::vector<glm::vec3> points;
    for (int k = 0; k < 64; ++k)
      points.push_back(region.lo +
                       region.size() * glm::vec3(float(k % 4) / 3, float((k / 4) % 4) / 3, float(k / 16) / 3));
    // Batches of every length up to a few vectors (the kernels pad a batch to whole vectors), and empty.
    points.resize(size_t(n) < 20 ? size_t(n) : size_t(7 * n) % 64 + 1);
    std::vector<float> batched(points.size());
    f.values(points, batched, scratch);
    for (size_t k = 0; k < points.size(); ++k) EXPECT_EQ(batched[k], f.value(points[k]));
  }
}

// samples() is sample() at every point, bit for bit (value, gradient, colour, owner): for every additive blend, every
// primitive kind, one blend set (its one-pass path) and several, points inside, outside and beyond every support.
TEST(Field, BatchedSamplesAreBitIdenticalToPointSamples) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), r(0.1f, 0.3f);
  const std::vector<Primitive> prims = randomPrimitives(rng, u, r, 24, 6, 6);
  BlendSets sets;
  for (uint32_t first = 0; first < prims.size(); first += 5) {
    std::vector<uint32_t> members;
    for (uint32_t i = first; i < std::min<uint32_t>(first + 8, uint32_t(prims.size())); ++i) members.push_back(i);
    sets.add(members);
  }
  size_t inside = 0, owned = 0;
  for (BlendKind kind : {BlendKind::Exponential, BlendKind::BlancSchlick})
    for (bool fastExp : {false, true})
      for (bool flat : {true, false}) {
        if (fastExp && kind != BlendKind::Exponential) continue;
        BlendFunction blend;
        blend.kind = kind;
        blend.fastExp = fastExp;
        blend.defaultParam = kind == BlendKind::Exponential ? -3.0f : 0.7f;
        const Field f = makeField(prims, blend, flat ? BlendSets::all(prims.size()) : sets);
        FieldScratch scratch;
        for (int n = 0; n < 20; ++n) {
          Box region;
          region.extend({1.3f * u(rng), 1.3f * u(rng), 1.3f * u(rng)});
          region.extend(region.lo + glm::vec3(0.5f));
          f.prepare(region, scratch);
          std::vector<glm::vec3> points;
          for (int k = 0; k < (n < 10 ? n + 1 : 37); ++k)  // not a multiple of the vector width, and short
            points.push_back(region.lo + region.size() * (glm::vec3(u(rng), u(rng), u(rng)) + 1.0f) / 2.0f);
          std::vector<FieldSample> batched(points.size());
          f.samples(points, batched, scratch);
          for (size_t k = 0; k < points.size(); ++k) {
            const FieldSample one = f.sample(points[k]);
            ASSERT_EQ(batched[k].value, one.value) << int(kind) << flat << " point " << k;
            ASSERT_EQ(batched[k].gradient, one.gradient) << int(kind) << flat << " point " << k;
            ASSERT_EQ(batched[k].color, one.color) << int(kind) << flat << " point " << k;
            ASSERT_EQ(batched[k].owner, one.owner) << int(kind) << flat << " point " << k;
            inside += one.value >= f.iso();
            owned += one.owner >= 0;
          }
        }
      }
  EXPECT_GT(inside, 100u) << "some points are inside";
  EXPECT_GT(owned, inside + 100) << "some points are outside the surface but within a support";
}

// latticeValues() skips each candidate where its support misses the lattice and is value() at every lattice point,
// for every blend and with several blend sets (sums, folds and the maximum over sets): bit for bit, but for metaballs
// under the exponential blend, which are evaluated separably (within a relative 1e-5 and one cutoff term). And it is
// a function of the point alone: two lattices that share points, prepared for different regions (so with different
// candidates), agree on them bit for bit, which is what lets blocks agree on their shared faces.
TEST(Field, LatticeValuesArePointValuesAndAFunctionOfThePointAlone) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), r(0.05f, 0.3f);
  const std::vector<Primitive> prims = randomPrimitives(rng, u, r, 20, 6);
  BlendSets sets;
  for (uint32_t first = 0; first < prims.size(); first += 4) {
    std::vector<uint32_t> members;
    for (uint32_t i = first; i < std::min<uint32_t>(first + 6, uint32_t(prims.size())); ++i) members.push_back(i);
    sets.add(members);  // overlapping sets of six
  }
  size_t separableDiffers = 0, compared = 0;
  for (BlendKind kind : {BlendKind::Exponential, BlendKind::BlancSchlick, BlendKind::Elliptical}) {
    for (bool flat : {false, true}) {
      BlendFunction blend;
      blend.kind = kind;
      blend.defaultParam = kind == BlendKind::Exponential ? -3.0f : 0.7f;
      const Field f = makeField(prims, blend, flat ? BlendSets::all(prims.size()) : sets);
      const bool exact = kind != BlendKind::Exponential;
      FieldScratch scratch;
      for (int n = 0; n < 20; ++n) {
        const glm::vec3 lo(u(rng), u(rng), u(rng));
        // Lattice a, and lattice b four samples further along every axis: they share 5^3 points.
        auto lattice = [&](int shift, std::span<const uint8_t> rows, std::vector<float> (&axes)[3]) {
          for (int a = 0; a < 3; ++a) {
            axes[a].clear();
            for (int v = 0; v < 9; ++v) axes[a].push_back(lo[a] + 0.05f * float(v + shift));
          }
          Box region;
          region.extend({axes[0].front(), axes[1].front(), axes[2].front()});
          region.extend({axes[0].back(), axes[1].back(), axes[2].back()});
          f.prepare(region, scratch);
          std::vector<float> out(9 * 9 * 9);
          f.latticeValues(axes[0], axes[1], axes[2], out, scratch, rows);
          return out;
        };
        std::vector<float> axes[3], axesB[3];
        const std::vector<float> a = lattice(0, {}, axes);
        // Some rows left out: the others keep their values, those are 0.
        std::vector<uint8_t> rows(9 * 9);
        for (uint8_t& row : rows) row = u(rng) > -0.4f ? 1 : 0;
        const std::vector<float> some = lattice(0, rows, axes);
        const std::vector<float> b = lattice(4, {}, axesB);
        for (int k = 0; k < 9; ++k)
          for (int j = 0; j < 9; ++j)
            for (int i = 0; i < 9; ++i) {
              const float v = f.value({axes[0][size_t(i)], axes[1][size_t(j)], axes[2][size_t(k)]});
              const float got = a[size_t(i + 9 * (j + 9 * k))];
              if (exact) {
                ASSERT_EQ(got, v) << int(kind) << " lattice " << n << " point " << i << " " << j << " " << k;
              } else {
                ASSERT_NEAR(got, v, 1e-5f * v + 1.5f * kExponentialCutoff) << "lattice " << n << " point " << i;
                separableDiffers += got != v;
                ++compared;
              }
              ASSERT_EQ(some[size_t(i + 9 * (j + 9 * k))], rows[size_t(j + 9 * k)] ? got : 0.0f)
                  << int(kind) << " lattice " << n << " rows, point " << i << " " << j << " " << k;
              if (i >= 4 && j >= 4 && k >= 4) {
                ASSERT_EQ(b[size_t(i - 4 + 9 * (j - 4 + 9 * (k - 4)))], got)
                    << int(kind) << " lattice " << n << " shared point " << i << " " << j << " " << k;
              }
            }
      }
    }
  }
  EXPECT_GT(separableDiffers, 0u) << "the exponential blend's metaballs took the separable path (of " << compared
                                  << " points)";
}

// boxBounds() brackets F at every point of each box, for every blend, several blend sets and every primitive kind,
// and is not trivial (some boxes wholly inside or outside).
TEST(Field, BoxBoundsHoldAtEveryPointOfTheirBox) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), r(0.1f, 0.4f), unit(0.0f, 1.0f);
  std::vector<Primitive> prims = randomPrimitives(rng, u, r, 12, 3);
  const glm::vec3 axis = glm::normalize(glm::vec3(1, 2, 3));
  for (int i = 0; i < 3; ++i)
    prims.push_back(
        Primitive::ellipsoid({u(rng), u(rng), u(rng)}, glm::angleAxis(u(rng), axis), {r(rng), r(rng), r(rng)}));
  BlendSets sets;
  for (uint32_t first = 0; first < prims.size(); first += 5) {
    std::vector<uint32_t> members;
    for (uint32_t i = first; i < std::min<uint32_t>(first + 7, uint32_t(prims.size())); ++i) members.push_back(i);
    sets.add(members);
  }
  for (BlendKind kind : {BlendKind::Exponential, BlendKind::BlancSchlick, BlendKind::Elliptical}) {
    BlendFunction blend;
    blend.kind = kind;
    blend.defaultParam = kind == BlendKind::Exponential ? -2.0f : 0.7f;
    const Field f = makeField(prims, blend, sets);
    FieldScratch scratch;
    int inside = 0, outside = 0;
    for (int n = 0; n < 200; ++n) {
      std::vector<Box> boxes(4);
      Box region;
      for (Box& b : boxes) {
        b.lo = glm::vec3(u(rng), u(rng), u(rng));
        b.hi = b.lo + 0.1f * glm::vec3(unit(rng), unit(rng), unit(rng));
        region.extend(b);
      }
      f.prepare(region, scratch);
      std::vector<float> lower(boxes.size()), upper(boxes.size());
      f.boxBounds(boxes, lower, upper, scratch);
      for (size_t b = 0; b < boxes.size(); ++b) {
        inside += lower[b] > f.iso();
        outside += upper[b] < f.iso();
        for (int q = 0; q < 30; ++q) {
          const glm::vec3 x = boxes[b].lo + (boxes[b].hi - boxes[b].lo) * glm::vec3(unit(rng), unit(rng), unit(rng));
          const float v = f.value(x, scratch);
          ASSERT_LE(lower[b], v) << int(kind) << " box " << n << "." << b;
          ASSERT_GE(upper[b], v) << int(kind) << " box " << n << "." << b;
        }
      }
    }
    EXPECT_GT(inside, 0) << int(kind);
    if (kind != BlendKind::Elliptical) {
      EXPECT_GT(outside, 0) << int(kind);
    }
  }
}

TEST(Field, GradientMatchesFiniteDifferencesAndColoursBlend) {
  BlendFunction blend;
  blend.defaultParam = -2.0f;
  const Field f = makeField(
      {Primitive::metaball({-0.4f, 0, 0}, 0.5f), Primitive::lineSeg({0.3f, 0, 0}, {1, 0.4f, 0}, 0.3f, 0.2f)}, blend);
  const glm::vec3 x(0.05f, 0.3f, 0.1f);
  const FieldSample s = f.sample(x);
  const float h = 1e-3f;
  for (int a = 0; a < 3; ++a) {
    glm::vec3 xp = x, xm = x;
    xp[a] += h;
    xm[a] -= h;
    EXPECT_NEAR(s.gradient[a], (f.value(xp) - f.value(xm)) / (2 * h), 2e-2f);
  }
  // Colour is a convex combination of the two materials (0,1,.5) and (1,0,.5), nearer the bigger contribution.
  EXPECT_NEAR(s.color.r + s.color.g, 1.0f, 1e-5f);
  EXPECT_GT(s.color.r, 0.0f);
  EXPECT_GT(s.color.g, 0.0f);
}

// With blend sets, a primitive is unioned (max) with primitives it does not blend with.
TEST(Field, BlendSetsPreventUnwantedBlending) {
  BlendFunction blend;
  blend.defaultParam = -1.0f;
  const std::vector<Primitive> prims = {Primitive::metaball({-0.6f, 0, 0}, 0.5f),
                                        Primitive::metaball({0.6f, 0, 0}, 0.5f)};
  BlendSets separate;
  separate.add(std::vector<uint32_t>{0});
  separate.add(std::vector<uint32_t>{1});
  const Field blended = makeField(prims, blend), apart = makeField(prims, blend, separate);
  EXPECT_GT(blended.value({0, 0, 0}), 1.0f);
  EXPECT_LT(apart.value({0, 0, 0}), 1.0f);
  EXPECT_NEAR(apart.value({-1.1f, 0, 0}), 1.0f, 0.02f);
}

TEST(Field, SurfaceBoundsEncloseTheSurface) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1, 1), r(0.1f, 0.3f);
  const std::vector<Primitive> prims = randomPrimitives(rng, u, r, 30, 0);
  BlendFunction blend;
  blend.defaultParam = -0.8f;  // very blobby: the surface reaches well beyond the radii
  const Field f = makeField(prims, blend);
  const Box sb = f.surfaceBounds();
  std::uniform_real_distribution<float> w(-4, 4);
  for (int n = 0; n < 20000; ++n) {
    const glm::vec3 x(w(rng), w(rng), w(rng));
    if (f.value(x) >= 1.0f) {
      EXPECT_TRUE(sb.contains(x));
    }
  }
  EXPECT_LT(sb.size().x, f.bounds().size().x) << "tighter than the supports";
}

}  // namespace
}  // namespace imps
