// SPDX-License-Identifier: MIT
// Implicit primitives in world space: metaball, meta-ellipsoid and meta-line segment (thesis 2.2-2.3).
//
// Based on: K. Russell, "IMPS: Implicit Surfaces for Interactive Animated Characters", MIT 1999, chapter 2;
//           J. Blinn, "A Generalization of Algebraic Surface Drawing", 1982.
//
// Convention (thesis 2.2): every primitive has a *normalised squared distance* d(x) >= 0 that is exactly 1 on the
// primitive's own surface, < 1 inside and grows like a squared distance outside. Blend functions (blend.h) map d
// to a field contribution. All quantities are in metres, world space.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cstdint>

namespace imps {

// An axis-aligned box; empty when lo > hi on any axis.
struct Box {
  glm::vec3 lo{1e30f};
  glm::vec3 hi{-1e30f};
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void extend(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Box& b) {
    if (b.empty()) return;
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  bool overlaps(const Box& b) const {
    return lo.x <= b.hi.x && b.lo.x <= hi.x && lo.y <= b.hi.y && b.lo.y <= hi.y && lo.z <= b.hi.z && b.lo.z <= hi.z;
  }
  bool contains(const glm::vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  glm::vec3 center() const { return 0.5f * (lo + hi); }
  glm::vec3 size() const { return hi - lo; }
};

enum class PrimitiveKind : uint8_t { Metaball, Ellipsoid, LineSeg };

// One primitive in world space. Which fields are used depends on `kind`:
//  Metaball:  center, radius.
//  Ellipsoid: center, rotation (local axes -> world), radii (semi-axes a, b, c along local x, y, z).
//  LineSeg:   p1, p2 (endpoints), r1, r2 (radii there). The surface of a lone segment is the tangent
//             cone-sphere hull of the two end spheres (the swept sphere of linearly varying radius).
// Construct with the factory functions; they precompute what evaluation needs.
struct Primitive {
  PrimitiveKind kind = PrimitiveKind::Metaball;
  glm::vec3 center{0.0f};
  float radius = 1.0f;
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 radii{1.0f};
  glm::vec3 p1{0.0f}, p2{0.0f};
  float r1 = 1.0f, r2 = 1.0f;

  // Derived (set by the factories / update()).
  glm::mat3 worldToLocal{1.0f};   // Ellipsoid: rows are the local axes divided by the radii
  glm::vec3 axis{0.0f, 1.0f, 0.0f};  // LineSeg: unit direction p1 -> p2
  float length = 0.0f;               // LineSeg: |p2 - p1|
  float slope = 0.0f;                // LineSeg: (r2 - r1) / length, radius change per metre along the axis

  static Primitive metaball(const glm::vec3& center, float radius);
  static Primitive ellipsoid(const glm::vec3& center, const glm::quat& rotation, const glm::vec3& radii);
  static Primitive lineSeg(const glm::vec3& p1, const glm::vec3& p2, float r1, float r2);

  // Recomputes the derived fields after the defining ones change.
  void update();

  // Normalised squared distance d(x) (see the file comment).
  float distance(const glm::vec3& x) const;
  // d(x) and its gradient.
  float distance(const glm::vec3& x, glm::vec3& gradient) const;

  // The rigidly transformed primitive (rotation then translation), e.g. from joint-local to world space.
  Primitive transformed(const glm::quat& r, const glm::vec3& t) const;

  // Box enclosing every x with d(x) <= dMax (dMax >= 0).
  Box bounds(float dMax) const;
  // Lower and upper bounds of d over `box` (conservative: lower <= d(x) <= upper for every x in box). With
  // tight = false, minDistance skips the line segment's refinement: cheaper, still conservative, looser.
  float minDistance(const Box& box, bool tight = true) const;
  float maxDistance(const Box& box) const;
  // The smallest radius of the primitive (metres): a ball of this radius fits in it wherever its core is.
  float minRadius() const;
  // Its thickness at x (metres): x's distance from its core, at least its radius there, i.e. r sqrt(max(d(x), 1))
  // with r the radius nearest x (a line segment's swept radius at the sphere nearest x, an ellipsoid's smallest).
  float thickness(const glm::vec3& x) const;
};

}  // namespace imps
