// SPDX-License-Identifier: MIT
// Texture-coordinate generators (thesis 3.9): a sphere or a plane around a primitive whose well-known mapping gives
// the (u, v) of every point the primitive owns — the coordinates of the closest point on the generator.
//
// Based on: K. Russell, "IMPS: Implicit Surfaces for Interactive Animated Characters", MIT 1999, section 3.9
//           (ImTexGenSphere, ImTexGenPlane).
//
// Convention: u grows to the right of the image and v upwards (OpenGL's and OBJ's; glTF's v is 1 - v), one image
// per unit square; values outside [0, 1] repeat the image. All positions are in metres, in the generator's space
// (world space once the skeleton cache has posed it).
#pragma once

#include <glm/gtc/quaternion.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>

namespace imps {

enum class TexGenType : uint8_t { Sphere, Plane };

struct TexGen {
  TexGenType type = TexGenType::Sphere;
  glm::vec3 origin{0.0f};                          // the generator's centre
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};      // generator-local axes -> space
  float width = 2.0f, height = 2.0f;               // Plane: the slide's size along local x and y (metres, > 0)

  // The texture coordinates of x.
  //  Sphere: longitude and latitude about the local y axis, seen from the centre: with q = x in local coordinates,
  //          u = 1/2 + atan2(q.x, q.z) / 2pi (u = 1/2 straight ahead on +z, the seam u = 0 ~ 1 behind, on -z),
  //          v = 1/2 + asin(q.y / |q|) / pi (0 at the south pole, 1 at the north pole). The centre itself maps to
  //          (1/2, 1/2).
  //  Plane:  a slide projector looking down local -z: u = 1/2 + q.x / width, v = 1/2 + q.y / height (the slide
  //          covers the width x height rectangle centred on the origin; depth q.z does not matter).
  glm::vec2 map(const glm::vec3& x) const;

  // The generator moved by the rigid transform x -> r x + t (e.g. joint-local -> world).
  TexGen transformed(const glm::quat& r, const glm::vec3& t) const;

  bool operator==(const TexGen&) const = default;
};

}  // namespace imps
