// SPDX-License-Identifier: MIT
// Normalised squared distances of the three primitives, their gradients and conservative bounds.
// Based on: K. Russell, "IMPS", MIT 1999, 2.3; the meta-line segment's three regions (2.3.3) fall out of the
// swept-sphere form below: the minimising sphere sits at an endpoint (regions 1 and 3) or between (region 2), and the
// region boundaries on the surface are at r1 sin(theta) and r2 sin(theta) from the endpoints, as in the thesis.
#include "imps/primitives.h"

#include <algorithm>
#include <cmath>

namespace imps {

Primitive Primitive::metaball(const glm::vec3& center, float radius) {
  Primitive p;
  p.kind = PrimitiveKind::Metaball;
  p.center = center;
  p.radius = radius;
  p.update();
  return p;
}

Primitive Primitive::ellipsoid(const glm::vec3& center, const glm::quat& rotation, const glm::vec3& radii) {
  Primitive p;
  p.kind = PrimitiveKind::Ellipsoid;
  p.center = center;
  p.rotation = glm::normalize(rotation);
  p.radii = radii;
  p.update();
  return p;
}

Primitive Primitive::lineSeg(const glm::vec3& p1, const glm::vec3& p2, float r1, float r2) {
  Primitive p;
  p.kind = PrimitiveKind::LineSeg;
  p.p1 = p1;
  p.p2 = p2;
  p.r1 = r1;
  p.r2 = r2;
  p.update();
  return p;
}

void Primitive::update() {
  switch (kind) {
    case PrimitiveKind::Metaball: break;
    case PrimitiveKind::Ellipsoid: {
      const glm::mat3 localToWorld = glm::mat3_cast(rotation);  // columns: local axes in world space
      const glm::mat3 worldToLocalRotation = glm::transpose(localToWorld);
      glm::mat3 scale(1.0f);
      scale[0][0] = 1.0f / radii.x;
      scale[1][1] = 1.0f / radii.y;
      scale[2][2] = 1.0f / radii.z;
      worldToLocal = scale * worldToLocalRotation;
      break;
    }
    case PrimitiveKind::LineSeg: {
      const glm::vec3 d = p2 - p1;
      length = glm::length(d);
      axis = length > 0.0f ? d / length : glm::vec3(0.0f, 1.0f, 0.0f);
      slope = length > 0.0f ? (r2 - r1) / length : 0.0f;
      center = 0.5f * (p1 + p2);
      radius = std::max(r1, r2);
      break;
    }
  }
}

namespace {

// LineSeg: the sphere of the swept family (centre p1 + s axis, radius r1 + slope s, s in [0, length]) that
// minimises |x - c(s)|^2 / r(s)^2. Setting the derivative to zero gives a single stationary point
// s = t + slope rho^2 / a, with t the axial and rho the radial coordinate of x and a = r1 + slope t the swept radius
// extrapolated to x's axial position. For a > 0 it is the minimum (clamped to the segment when outside it); for
// a <= 0 (beyond the apex of the cone through both end spheres) it is a maximum and the minimum is at an end.
inline float lineSegParameter(const Primitive& p, const glm::vec3& x) {
  const glm::vec3 v = x - p.p1;
  const float t = glm::dot(v, p.axis);
  const float rho2 = std::max(0.0f, glm::dot(v, v) - t * t);
  const float a = p.r1 + p.slope * t;
  if (a > 0.0f) return std::clamp(t + p.slope * rho2 / a, 0.0f, p.length);
  const glm::vec3 w = x - p.p2;
  return glm::dot(v, v) / (p.r1 * p.r1) <= glm::dot(w, w) / (p.r2 * p.r2) ? 0.0f : p.length;
}

}  // namespace

float Primitive::distance(const glm::vec3& x) const {
  switch (kind) {
    case PrimitiveKind::Metaball: {
      const glm::vec3 v = x - center;
      return glm::dot(v, v) / (radius * radius);
    }
    case PrimitiveKind::Ellipsoid: {
      const glm::vec3 q = worldToLocal * (x - center);
      return glm::dot(q, q);
    }
    case PrimitiveKind::LineSeg: {
      const float s = lineSegParameter(*this, x);
      const glm::vec3 v = x - (p1 + s * axis);
      const float r = r1 + slope * s;
      return glm::dot(v, v) / (r * r);
    }
  }
  return 0.0f;
}

float Primitive::distance(const glm::vec3& x, glm::vec3& gradient) const {
  switch (kind) {
    case PrimitiveKind::Metaball: {
      const glm::vec3 v = x - center;
      const float inv = 1.0f / (radius * radius);
      gradient = 2.0f * inv * v;
      return glm::dot(v, v) * inv;
    }
    case PrimitiveKind::Ellipsoid: {
      const glm::vec3 q = worldToLocal * (x - center);
      gradient = 2.0f * (glm::transpose(worldToLocal) * q);
      return glm::dot(q, q);
    }
    case PrimitiveKind::LineSeg: {
      // Envelope theorem: at the minimising s the derivative in s vanishes (or s is clamped, fixed), so the
      // gradient is that of the single sphere |x - c(s)|^2 / r(s)^2. Value and gradient are continuous.
      const float s = lineSegParameter(*this, x);
      const glm::vec3 v = x - (p1 + s * axis);
      const float r = r1 + slope * s;
      const float inv = 1.0f / (r * r);
      gradient = 2.0f * inv * v;
      return glm::dot(v, v) * inv;
    }
  }
  gradient = glm::vec3(0.0f);
  return 0.0f;
}

Primitive Primitive::transformed(const glm::quat& r, const glm::vec3& t) const {
  Primitive out = *this;
  switch (kind) {
    case PrimitiveKind::Metaball: out.center = r * center + t; break;
    case PrimitiveKind::Ellipsoid:
      out.center = r * center + t;
      out.rotation = glm::normalize(r * rotation);
      break;
    case PrimitiveKind::LineSeg:
      out.p1 = r * p1 + t;
      out.p2 = r * p2 + t;
      break;
  }
  out.update();
  return out;
}

Box Primitive::bounds(float dMax) const {
  const float s = std::sqrt(std::max(0.0f, dMax));
  Box b;
  switch (kind) {
    case PrimitiveKind::Metaball:
      b.lo = center - glm::vec3(radius * s);
      b.hi = center + glm::vec3(radius * s);
      break;
    case PrimitiveKind::Ellipsoid: {
      const glm::mat3 m = glm::mat3_cast(rotation);
      glm::vec3 half;
      for (int j = 0; j < 3; ++j) {
        const float ex = m[0][j] * radii.x, ey = m[1][j] * radii.y, ez = m[2][j] * radii.z;
        half[j] = s * std::sqrt(ex * ex + ey * ey + ez * ez);
      }
      b.lo = center - half;
      b.hi = center + half;
      break;
    }
    case PrimitiveKind::LineSeg:
      // The swept spheres lie in the convex hull of the two end spheres.
      b.extend(p1 - glm::vec3(r1 * s));
      b.extend(p1 + glm::vec3(r1 * s));
      b.extend(p2 - glm::vec3(r2 * s));
      b.extend(p2 + glm::vec3(r2 * s));
      break;
  }
  return b;
}

namespace {
float squaredDistanceToBox(const glm::vec3& p, const Box& box) {
  const glm::vec3 q = glm::clamp(p, box.lo, box.hi);
  const glm::vec3 v = p - q;
  return glm::dot(v, v);
}
float squaredFarthestInBox(const glm::vec3& p, const Box& box) {
  const glm::vec3 a = glm::abs(box.lo - p), b = glm::abs(box.hi - p);
  const glm::vec3 m = glm::max(a, b);
  return glm::dot(m, m);
}
}  // namespace

float Primitive::minDistance(const Box& box, bool tight) const {
  switch (kind) {
    case PrimitiveKind::Metaball: return squaredDistanceToBox(center, box) / (radius * radius);
    case PrimitiveKind::Ellipsoid: {
      const float a = std::max({radii.x, radii.y, radii.z});
      return squaredDistanceToBox(center, box) / (a * a);
    }
    case PrimitiveKind::LineSeg: {
      // d(x) >= |x - segment|^2 / max radius^2. First the cheap bound |centre - segment| - half diagonal; when
      // that does not already put the box beyond any support, refine: the distance from c(s) to a box is convex in
      // s, so a golden-section search (one distance per step) brackets the segment's nearest point to the box; the
      // distance is 1-Lipschitz in s, so subtracting the bracket's width keeps the bound conservative.
      const float rMax = std::max(r1, r2);
      const glm::vec3 c = box.center();
      const float tc = std::clamp(glm::dot(c - p1, axis), 0.0f, length);
      const float cheap = std::max(0.0f, glm::length(c - (p1 + tc * axis)) - 0.5f * glm::length(box.size()));
      if (!tight || cheap > 8.0f * rMax) return cheap * cheap / (rMax * rMax);
      constexpr float kInvPhi = 0.618034f;
      auto at = [&](float s) { return squaredDistanceToBox(p1 + s * axis, box); };
      float lo = 0.0f, hi = length;
      float a = hi - kInvPhi * (hi - lo), b = lo + kInvPhi * (hi - lo);
      float fa = at(a), fb = at(b);
      for (int it = 0; it < 10; ++it) {
        if (fa <= fb) {
          hi = b;
          b = a;
          fb = fa;
          a = hi - kInvPhi * (hi - lo);
          fa = at(a);
        } else {
          lo = a;
          a = b;
          fa = fb;
          b = lo + kInvPhi * (hi - lo);
          fb = at(b);
        }
      }
      const float slack = (hi - lo) + 1e-6f * (length + glm::length(box.size()));
      const float dist = std::max(cheap, std::sqrt(squaredDistanceToBox(p1 + 0.5f * (lo + hi) * axis, box)) - slack);
      return dist * dist / (rMax * rMax);
    }
  }
  return 0.0f;
}

float Primitive::maxDistance(const Box& box) const {
  switch (kind) {
    case PrimitiveKind::Metaball: return squaredFarthestInBox(center, box) / (radius * radius);
    case PrimitiveKind::Ellipsoid: {
      const float a = std::min({radii.x, radii.y, radii.z});
      return squaredFarthestInBox(center, box) / (a * a);
    }
    case PrimitiveKind::LineSeg: {
      // d(x) <= |x - c(s)|^2 / r(s)^2 for any fixed s; take the sphere nearest the box centre.
      const glm::vec3 c = box.center();
      const float s = lineSegParameter(*this, c);
      const float r = r1 + slope * s;
      const float dist = glm::length(c - (p1 + s * axis)) + 0.5f * glm::length(box.size());
      return dist * dist / (r * r);
    }
  }
  return 0.0f;
}

float Primitive::thickness(const glm::vec3& x) const {
  // distance()'s arithmetic, the segment's parameter found once.
  float r = minRadius(), d = 0.0f;
  switch (kind) {
    case PrimitiveKind::Metaball: {
      const glm::vec3 v = x - center;
      d = glm::dot(v, v) / (radius * radius);
      break;
    }
    case PrimitiveKind::Ellipsoid: {
      const glm::vec3 q = worldToLocal * (x - center);
      d = glm::dot(q, q);
      break;
    }
    case PrimitiveKind::LineSeg: {
      const float s = lineSegParameter(*this, x);
      const glm::vec3 v = x - (p1 + s * axis);
      r = r1 + slope * s;
      d = glm::dot(v, v) / (r * r);
      break;
    }
  }
  return r * std::sqrt(std::max(d, 1.0f));
}

float Primitive::minRadius() const {
  switch (kind) {
    case PrimitiveKind::Metaball: return radius;
    case PrimitiveKind::Ellipsoid: return std::min({radii.x, radii.y, radii.z});
    case PrimitiveKind::LineSeg: return std::min(r1, r2);
  }
  return 0.0f;
}

}  // namespace imps
