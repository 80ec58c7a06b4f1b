// SPDX-License-Identifier: MIT
// Polygonal props from VRML 97 files (imps/vrml_file.h): every Shape's IndexedFaceSet, Box, Sphere, Cylinder or Cone
// as a triangle mesh in the file's coordinates, with its Material's colour. docs/world-format.md ("Props").
#pragma once

#include <string>
#include <vector>

#include <glm/mat4x4.hpp>

#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/mesh.h"
#include "imps/vrml_file.h"

namespace imps {

// One Shape of a world.
struct Prop {
  std::string name;      // the DEF name of the Shape, else of its geometry, else of the nearest Transform; or "propN"
  std::string geometry;  // "IndexedFaceSet", "Box", "Sphere", "Cylinder", "Cone"
  // Triangles in the file's coordinates (every Transform above the Shape applied): three vertices of its own per
  // triangle, counter-clockwise seen from outside (an IndexedFaceSet with `ccw FALSE` is turned round). Normals:
  // the face's for primitives; an IndexedFaceSet's Normal node (normalPerVertex,
  // normalIndex) when it has one, else each corner's average over the faces around its point that meet this face
  // at no more than creaseAngle (0, the default: flat). colors: an IndexedFaceSet's Color node (colorPerVertex,
  // colorIndex) when it has one, else the Material's diffuseColor (0.8 grey without one).
  Mesh mesh;
  SourceLoc loc;  // the Shape
};

// Every Shape under the file's top-level nodes, depth first (a USE'd subtree once per use). Geometry of other types
// (IndexedLineSet, Text, …) and Shapes without geometry are skipped with a warning. Bad IndexedFaceSet data — an
// index outside the Coordinate's points, a face of fewer than three points, a point count that is not a multiple
// of 3 — gives a warning at the field and that face (or the Shape) is left out; bad primitive sizes (not > 0) too.
// At most 10,000,000 triangles in all (more: a warning and the rest is left out). Thread-safe.
std::vector<Prop> readProps(const VrmlFile& file, Diagnostics* warnings = nullptr);

// The triangles of a VRML primitive centred at the origin, as readProps makes them (Box: `size`; Sphere: `radius`;
// Cylinder: `radius`, `height`; Cone: `bottomRadius`, `height`; y is the axis). Closed and outward-facing.
Mesh boxMesh(const glm::vec3& size);
Mesh sphereMesh(float radius);
Mesh cylinderMesh(float radius, float height);
Mesh coneMesh(float bottomRadius, float height);

// `mesh` moved by the rigid transform `pose` (positions and normals).
Mesh transformed(const Mesh& mesh, const Rigid& pose);
// `mesh` moved by an affine `matrix` (normals by its inverse transpose, renormalised; a mirroring matrix turns the
// triangles round so they keep facing outwards).
Mesh transformed(const Mesh& mesh, const glm::mat4& matrix);

}  // namespace imps
