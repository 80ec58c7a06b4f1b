// SPDX-License-Identifier: MIT
// The regular octahedron: a small closed mesh whose distances, areas and topology are known by hand. Vertices
// centre ± radius along the axes, in the order +x -x +y -y +z -z; eight faces, counter-clockwise seen from outside.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "imps/mesh.h"

namespace imps::test {

// The unit axis directions, in vertex order.
inline std::vector<glm::vec3> octahedronAxes() {
  return {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
}

// The faces over the vertices above: in each octant the corners on its x, y and z axes, turned round when the
// octant has an odd number of negative axes.
inline std::vector<uint32_t> octahedronFaces() {
  std::vector<uint32_t> tris;
  for (int sx : {1, -1})
    for (int sy : {1, -1})
      for (int sz : {1, -1}) {
        const uint32_t x = sx > 0 ? 0 : 1, y = sy > 0 ? 2 : 3, z = sz > 0 ? 4 : 5;
        if (sx * sy * sz > 0) {
          tris.insert(tris.end(), {x, y, z});
        } else {
          tris.insert(tris.end(), {x, z, y});
        }
      }
  return tris;
}

// The octahedron as a mesh (positions and indices only).
inline Mesh octahedronMesh(const glm::vec3& centre = glm::vec3(0.0f), float radius = 1.0f) {
  Mesh mesh;
  for (const glm::vec3& axis : octahedronAxes()) {
    const glm::vec3 p = centre + radius * axis;
    mesh.positions.insert(mesh.positions.end(), {p.x, p.y, p.z});
  }
  mesh.indices = octahedronFaces();
  return mesh;
}

}  // namespace imps::test
