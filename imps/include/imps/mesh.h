// SPDX-License-Identifier: MIT
// The triangle mesh every polygonizer produces: flat arrays ready for GL upload and export, plus topology checks.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/vec3.hpp>

#include "imps/texgen.h"

namespace imps {

// An indexed triangle mesh. Vertex attributes are interleaved per attribute, not per vertex:
// positions[3i..3i+2] (metres, world space), normals[3i..] (unit, pointing out of the surface, i.e. down the field
// gradient), colors[3i..] (linear RGB in [0, 1]). Triangles are indices[3t..3t+2], counter-clockwise seen from
// outside. normals and colors are either empty or as long as positions.
struct Mesh {
  std::vector<float> positions;
  std::vector<float> normals;
  std::vector<float> colors;
  std::vector<uint32_t> indices;
  // Textures (filled by textureMesh, imps/texturing.h; all empty when no primitive has a generator). A *layer* is
  // one textured primitive: layerGens[l] is its generator in the mesh's space and layerImages[l] its image (an index
  // into Character::textures(); -1: a generator without an image, which renders white). Each vertex blends up to
  // two layers: layers[2v], layers[2v+1] (-1: unused) with weights layerWeights[2v], layerWeights[2v+1] >= 0 whose
  // sum is at most 1 (the rest is untextured: the colour alone). texcoords[2v..2v+1] is the (u, v) of the vertex's
  // first layer (0, 0 without one). A renderer gets any layer's coordinates anywhere from its generator
  // (layerGens[l].map(position)), which is how a triangle whose corners name different layers is drawn seamlessly.
  // layerTexcoords is empty (projective texturing: every coordinate comes from the generator) or, for a mesh whose
  // coordinates were carried by the particle tesselator (TextureMode::Carried, Tesselator::carryTexcoords), 4 per
  // vertex: the (u, v) of layers[2v] then of layers[2v+1] (0 where the slot is unused). Read coordinates through
  // layerUv(), which falls back to the generator for a layer the vertex does not carry.
  std::vector<TexGen> layerGens;
  std::vector<int32_t> layerImages;
  std::vector<int32_t> layers;
  std::vector<float> layerWeights;
  std::vector<float> texcoords;
  std::vector<float> layerTexcoords;

  size_t vertexCount() const { return positions.size() / 3; }
  size_t triangleCount() const { return indices.size() / 3; }
  glm::vec3 position(size_t v) const { return {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]}; }
  glm::vec3 normal(size_t v) const { return {normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]}; }
  glm::vec3 color(size_t v) const { return {colors[3 * v], colors[3 * v + 1], colors[3 * v + 2]}; }
  void clear() {
    positions.clear();
    normals.clear();
    colors.clear();
    indices.clear();
    clearTextures();
  }
  void clearTextures() {
    layerGens.clear();
    layerImages.clear();
    layers.clear();
    layerWeights.clear();
    texcoords.clear();
    layerTexcoords.clear();
  }
  bool textured() const { return !layers.empty(); }
  // The (u, v) of layer `layer` (< layerGens.size()) at vertex v: the carried coordinate when v carries that layer
  // (layerTexcoords), else its generator's mapping of the vertex's position.
  glm::vec2 layerUv(size_t v, int32_t layer) const {
    if (!layerTexcoords.empty())
      for (size_t k = 0; k < 2; ++k)
        if (layers[2 * v + k] == layer) return {layerTexcoords[4 * v + 2 * k], layerTexcoords[4 * v + 2 * k + 1]};
    return layerGens[size_t(layer)].map(position(v));
  }
  bool operator==(const Mesh&) const = default;
};

// What the topology of a mesh is. A closed 2-manifold has boundaryEdges == 0, nonManifoldEdges == 0,
// nonManifoldVertices == 0 and orientationConflicts == 0.
struct MeshTopology {
  size_t boundaryEdges = 0;         // edges used by exactly one triangle (holes)
  size_t nonManifoldEdges = 0;      // edges used by three or more triangles
  size_t nonManifoldVertices = 0;   // vertices whose triangle fan is not a single disk or half-disk
  size_t orientationConflicts = 0;  // interior edges traversed in the same direction by both triangles
  size_t degenerateTriangles = 0;   // triangles repeating a vertex index
  size_t unusedVertices = 0;        // vertices no triangle references
  size_t components = 0;            // connected components (by shared edges)
  long eulerCharacteristic = 0;     // V - E + F over used vertices
  bool closedManifold() const {
    return boundaryEdges == 0 && nonManifoldEdges == 0 && nonManifoldVertices == 0 && orientationConflicts == 0 &&
           degenerateTriangles == 0;
  }
};

// Counts the topological defects of `mesh` (O(triangles log triangles)). Degenerate triangles are counted and then
// ignored: they add no edges, faces or connections. A vertex on a non-manifold edge is also a non-manifold vertex
// (its fan falls apart into several pieces once the non-manifold edge is cut). eulerCharacteristic counts the
// vertices, edges and faces of the non-degenerate triangles. Every index must be < mesh.vertexCount() (checked;
// a bad index is a bug in whoever built the mesh).
MeshTopology analyzeTopology(const Mesh& mesh);

// How the connected components of `mesh` match those of `reference`, another mesh of the same surface (the particle
// tesselator's against Marching Cubes at a finer cell): each component of `mesh` (triangles joined by shared
// vertices) belongs to the reference component holding the reference vertex nearest to the component's first
// vertex. Counts alone can hide both defects at once (a part cut off and a part missing give the same number).
struct ComponentMatch {
  size_t components = 0;           // of `mesh`
  size_t referenceComponents = 0;  // of `reference`
  size_t missing = 0;  // reference components no component of `mesh` belongs to: parts of the surface not meshed
  size_t cutOff = 0;   // components of `mesh` beyond the first in one reference component: parts meshed apart
  size_t cutOffCavities = 0;    // of those, cavities: air pockets closed where the reference finds them open
  size_t missingCavities = 0;   // of the missing, those that are cavities (facing inward: negative signed volume), air
                                // enclosed by the solid, as where a limb presses into the body; not seen from outside
  float largestMissing = 0.0f;  // the diagonal of the largest missing component's bounding box (0: none missing)
};
// O(mesh vertices + components of `mesh` x reference vertices).
ComponentMatch matchComponents(const Mesh& mesh, const Mesh& reference);

// Signed volume enclosed by the mesh (positive when triangles face outward); meaningful for closed meshes.
double signedVolume(const Mesh& mesh);

// Axis-aligned bounding box of all vertices (used or not), in the mesh's space. For an empty mesh min > max
// (min = +inf, max = -inf), so `empty()` is true.
struct MeshBounds {
  glm::vec3 min{std::numeric_limits<float>::infinity()};
  glm::vec3 max{-std::numeric_limits<float>::infinity()};
  bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
};
MeshBounds bounds(const Mesh& mesh);

// Appends `source` to `target`, offsetting its indices. normals (and colors) of the result are kept only if both
// meshes have them, or if `target` is empty; otherwise they are dropped so the Mesh invariant holds. Texture
// layers are kept: the vertices of an untextured side get no layer (weights 0), and the source's layers are added
// after the target's unless both have the same ones (a character's mesh keeps its textures when props join it).
void appendMesh(Mesh& target, const Mesh& source);

}  // namespace imps
