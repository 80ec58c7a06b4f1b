// SPDX-License-Identifier: MIT
// Texture-coordinate generators: the sphere's and the plane's mappings.
#include "imps/texgen.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <glm/geometric.hpp>

namespace imps {

glm::vec2 TexGen::map(const glm::vec3& x) const {
  const glm::vec3 q = glm::conjugate(rotation) * (x - origin);
  if (type == TexGenType::Plane) return {0.5f + q.x / width, 0.5f + q.y / height};
  const float r = glm::length(q);
  if (!(r > 0.0f)) return {0.5f, 0.5f};
  constexpr float kPi = std::numbers::pi_v<float>;
  const float u = 0.5f + std::atan2(q.x, q.z) / (2.0f * kPi);
  const float v = 0.5f + std::asin(std::clamp(q.y / r, -1.0f, 1.0f)) / kPi;
  return {u, v};
}

TexGen TexGen::transformed(const glm::quat& r, const glm::vec3& t) const {
  TexGen g = *this;
  g.origin = r * origin + t;
  g.rotation = r * rotation;
  return g;
}

}  // namespace imps
