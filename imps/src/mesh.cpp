// SPDX-License-Identifier: MIT
// Topology checks, volume, bounds and merging of the shared triangle mesh.
#include "imps/mesh.h"

#include <algorithm>
#include <numeric>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "disjoint_sets.h"
#include "imps/check.h"
#include "imps/primitives.h"

namespace imps {
namespace {

// One triangle side, from corner `corner` (3 * triangle + k) to the next corner of the same triangle.
struct HalfEdge {
  uint64_t key;      // (min vertex << 32) | max vertex: equal for both directions of an edge
  uint32_t corner;   // corner the side starts at
  bool increasing;   // true when it runs from the smaller to the larger vertex index
};

uint32_t nextCorner(uint32_t corner) { return corner % 3 == 2 ? corner - 2 : corner + 1; }

}  // namespace

MeshTopology analyzeTopology(const Mesh& mesh) {
  MeshTopology topology;
  const size_t vertexCount = mesh.vertexCount();
  const size_t triangleCount = mesh.triangleCount();
  IMPS_CHECK_EQ(mesh.indices.size() % 3, size_t{0});
  IMPS_CHECK_LE(mesh.indices.size(), size_t{UINT32_MAX});
  const std::vector<uint32_t>& idx = mesh.indices;

  // Pass 1: usage, degenerate triangles and the sides of the others.
  std::vector<bool> referenced(vertexCount, false);
  std::vector<bool> usedByFace(vertexCount, false);
  std::vector<bool> degenerate(triangleCount, false);
  std::vector<HalfEdge> sides;
  sides.reserve(mesh.indices.size());
  for (size_t t = 0; t < triangleCount; ++t) {
    const uint32_t a = idx[3 * t], b = idx[3 * t + 1], c = idx[3 * t + 2];
    IMPS_CHECK_LT(a, vertexCount);
    IMPS_CHECK_LT(b, vertexCount);
    IMPS_CHECK_LT(c, vertexCount);
    referenced[a] = referenced[b] = referenced[c] = true;
    if (a == b || b == c || c == a) {
      degenerate[t] = true;
      ++topology.degenerateTriangles;
      continue;
    }
    usedByFace[a] = usedByFace[b] = usedByFace[c] = true;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t corner = static_cast<uint32_t>(3 * t) + k;
      const uint32_t from = idx[corner], to = idx[nextCorner(corner)];
      const uint64_t lo = std::min(from, to), hi = std::max(from, to);
      sides.push_back({(lo << 32) | hi, corner, from < to});
    }
  }
  topology.unusedVertices = static_cast<size_t>(std::count(referenced.begin(), referenced.end(), false));

  // Pass 2: group the sides by edge. Sorting by (key, corner) keeps the result independent of std::sort's order.
  std::sort(sides.begin(), sides.end(), [](const HalfEdge& l, const HalfEdge& r) {
    return l.key != r.key ? l.key < r.key : l.corner < r.corner;
  });
  DisjointSets triangles(triangleCount);      // joined across every shared edge -> components
  DisjointSets corners(3 * triangleCount);    // joined around a vertex across manifold edges -> vertex fans
  size_t edgeCount = 0;
  for (size_t begin = 0; begin < sides.size();) {
    size_t end = begin + 1;
    while (end < sides.size() && sides[end].key == sides[begin].key) ++end;
    const size_t uses = end - begin;
    ++edgeCount;
    for (size_t s = begin + 1; s < end; ++s) triangles.unite(sides[begin].corner / 3, sides[s].corner / 3);
    if (uses == 1) {
      ++topology.boundaryEdges;
    } else if (uses >= 3) {
      ++topology.nonManifoldEdges;
    } else {
      const HalfEdge& p = sides[begin];
      const HalfEdge& q = sides[begin + 1];
      if (p.increasing == q.increasing) ++topology.orientationConflicts;
      // The two triangles' corners at each end of the edge belong to the same fan. With opposite directions,
      // p's start meets q's end; with a conflict (same direction) p's start meets q's start.
      const uint32_t pStart = p.corner, pEnd = nextCorner(p.corner);
      const uint32_t qStart = q.corner, qEnd = nextCorner(q.corner);
      if (p.increasing != q.increasing) {
        corners.unite(pStart, qEnd);
        corners.unite(pEnd, qStart);
      } else {
        corners.unite(pStart, qStart);
        corners.unite(pEnd, qEnd);
      }
    }
    begin = end;
  }

  // Pass 3: a vertex is manifold when all its corners form one fan; count fans per vertex by their root corners.
  std::vector<uint32_t> fans(vertexCount, 0);
  for (uint32_t corner = 0; corner < 3 * triangleCount; ++corner) {
    if (degenerate[corner / 3]) continue;
    if (corners.find(corner) == corner) ++fans[idx[corner]];
  }
  topology.nonManifoldVertices =
      static_cast<size_t>(std::count_if(fans.begin(), fans.end(), [](uint32_t f) { return f > 1; }));

  for (uint32_t t = 0; t < triangleCount; ++t) {
    if (!degenerate[t] && triangles.find(t) == t) ++topology.components;
  }
  const size_t faceCount = triangleCount - topology.degenerateTriangles;
  const size_t usedVertices = static_cast<size_t>(std::count(usedByFace.begin(), usedByFace.end(), true));
  topology.eulerCharacteristic =
      static_cast<long>(usedVertices) - static_cast<long>(edgeCount) + static_cast<long>(faceCount);
  return topology;
}

namespace {

// Each used vertex's component (triangles joined by shared vertices), numbered from 0 in order of first vertex;
// kUnused for vertices no triangle uses. Returns the component count.
constexpr uint32_t kUnused = ~0u;
size_t vertexComponents(const Mesh& mesh, std::vector<uint32_t>& label) {
  DisjointSets sets(mesh.vertexCount());
  std::vector<uint8_t> used(mesh.vertexCount(), 0);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    used[tri[0]] = used[tri[1]] = used[tri[2]] = 1;
    sets.unite(tri[0], tri[1]);
    sets.unite(tri[0], tri[2]);
  }
  label.assign(mesh.vertexCount(), kUnused);
  size_t count = 0;
  for (uint32_t v = 0; v < label.size(); ++v) {
    if (!used[v]) continue;
    const uint32_t root = sets.find(v);  // the smallest vertex of its component: labelled first
    label[v] = root == v ? uint32_t(count++) : label[root];
  }
  return count;
}

// Each component's signed volume (six times: the tetrahedra to the origin, as signedVolume), by vertexComponents'
// labels.
std::vector<double> componentVolumes(const Mesh& mesh, const std::vector<uint32_t>& label, size_t count) {
  std::vector<double> volume6(count, 0.0);
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const uint32_t* tri = &mesh.indices[3 * t];
    const glm::dvec3 a(mesh.position(tri[0])), b(mesh.position(tri[1])), c(mesh.position(tri[2]));
    volume6[label[tri[0]]] += glm::dot(a, glm::cross(b, c));
  }
  return volume6;
}

}  // namespace

ComponentMatch matchComponents(const Mesh& mesh, const Mesh& reference) {
  ComponentMatch match;
  std::vector<uint32_t> label, referenceLabel;
  match.components = vertexComponents(mesh, label);
  match.referenceComponents = vertexComponents(reference, referenceLabel);
  std::vector<size_t> members(match.referenceComponents, 0), cavities(match.referenceComponents, 0);
  const std::vector<double> volume = componentVolumes(mesh, label, match.components);
  std::vector<uint8_t> seen(match.components, 0);
  for (uint32_t v = 0; v < label.size(); ++v) {
    if (label[v] == kUnused || seen[label[v]]) continue;
    seen[label[v]] = 1;  // v is the component's first vertex
    const glm::vec3 p = mesh.position(v);
    float best = std::numeric_limits<float>::infinity();
    uint32_t nearest = kUnused;
    for (uint32_t r = 0; r < referenceLabel.size(); ++r) {
      if (referenceLabel[r] == kUnused) continue;
      const glm::vec3 d = reference.position(r) - p;
      const float d2 = glm::dot(d, d);
      if (d2 < best) best = d2, nearest = referenceLabel[r];
    }
    if (nearest == kUnused) continue;
    ++members[nearest];
    cavities[nearest] += volume[label[v]] < 0.0;
  }
  const std::vector<double> referenceVolume = componentVolumes(reference, referenceLabel, match.referenceComponents);
  std::vector<Box> boxes(match.referenceComponents);
  for (uint32_t r = 0; r < referenceLabel.size(); ++r)
    if (referenceLabel[r] != kUnused) boxes[referenceLabel[r]].extend(reference.position(r));
  for (size_t c = 0; c < members.size(); ++c) {
    if (members[c] > 1) {
      match.cutOff += members[c] - 1;
      match.cutOffCavities += std::min(cavities[c], members[c] - 1);
    }
    if (members[c] != 0) continue;
    ++match.missing;
    match.missingCavities += referenceVolume[c] < 0.0;
    match.largestMissing = std::max(match.largestMissing, glm::length(boxes[c].hi - boxes[c].lo));
  }
  return match;
}

double signedVolume(const Mesh& mesh) {
  // Divergence theorem: sum of the signed volumes of the tetrahedra (origin, a, b, c), in double to keep
  // cancellation error small for meshes far from the origin.
  double volume6 = 0.0;
  for (size_t t = 0; t < mesh.triangleCount(); ++t) {
    const glm::dvec3 a(mesh.position(mesh.indices[3 * t]));
    const glm::dvec3 b(mesh.position(mesh.indices[3 * t + 1]));
    const glm::dvec3 c(mesh.position(mesh.indices[3 * t + 2]));
    volume6 += a.x * (b.y * c.z - b.z * c.y) + a.y * (b.z * c.x - b.x * c.z) + a.z * (b.x * c.y - b.y * c.x);
  }
  return volume6 / 6.0;
}

MeshBounds bounds(const Mesh& mesh) {
  MeshBounds box;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) {
    const glm::vec3 p = mesh.position(v);
    box.min = glm::min(box.min, p);
    box.max = glm::max(box.max, p);
  }
  return box;
}

void appendMesh(Mesh& target, const Mesh& source) {
  if (target.positions.empty() && target.indices.empty()) {
    target = source;
    return;
  }
  const size_t offset = target.vertexCount();
  IMPS_CHECK_LE(offset + source.vertexCount(), size_t{UINT32_MAX});
  const bool keepNormals = !target.normals.empty() && !source.normals.empty();
  const bool keepColors = !target.colors.empty() && !source.colors.empty();
  target.positions.insert(target.positions.end(), source.positions.begin(), source.positions.end());
  if (keepNormals) {
    target.normals.insert(target.normals.end(), source.normals.begin(), source.normals.end());
  } else {
    target.normals.clear();
  }
  if (keepColors) {
    target.colors.insert(target.colors.end(), source.colors.begin(), source.colors.end());
  } else {
    target.colors.clear();
  }
  target.indices.reserve(target.indices.size() + source.indices.size());
  for (const uint32_t i : source.indices) target.indices.push_back(i + static_cast<uint32_t>(offset));
  if (!target.textured() && !source.textured()) return;
  // Texture layers: an untextured side gets "no layer" per vertex; the source's layers follow the target's.
  const size_t targetVertices = offset, sourceVertices = source.vertexCount();
  // Carried coordinates survive when either side has them; the other side's slots get their generators' mapping
  // (the same coordinates layerUv() would have read).
  const bool carried = !target.layerTexcoords.empty() || !source.layerTexcoords.empty();
  if (carried && target.layerTexcoords.empty()) target.layerTexcoords.assign(4 * targetVertices, 0.0f);
  if (!target.textured()) {
    target.layers.assign(2 * targetVertices, -1);
    target.layerWeights.assign(2 * targetVertices, 0.0f);
    target.texcoords.assign(2 * targetVertices, 0.0f);
  }
  if (!source.textured()) {
    target.layers.insert(target.layers.end(), 2 * sourceVertices, -1);
    target.layerWeights.insert(target.layerWeights.end(), 2 * sourceVertices, 0.0f);
    target.texcoords.insert(target.texcoords.end(), 2 * sourceVertices, 0.0f);
    if (carried) target.layerTexcoords.insert(target.layerTexcoords.end(), 4 * sourceVertices, 0.0f);
    return;
  }
  const bool sameLayers = target.layerGens == source.layerGens && target.layerImages == source.layerImages;
  const auto layerOffset = static_cast<int32_t>(sameLayers ? 0 : target.layerGens.size());
  if (!sameLayers) {
    target.layerGens.insert(target.layerGens.end(), source.layerGens.begin(), source.layerGens.end());
    target.layerImages.insert(target.layerImages.end(), source.layerImages.begin(), source.layerImages.end());
  }
  for (const int32_t l : source.layers) target.layers.push_back(l < 0 ? l : l + layerOffset);
  target.layerWeights.insert(target.layerWeights.end(), source.layerWeights.begin(), source.layerWeights.end());
  target.texcoords.insert(target.texcoords.end(), source.texcoords.begin(), source.texcoords.end());
  if (!carried) return;
  for (size_t v = 0; v < sourceVertices; ++v)
    for (size_t k = 0; k < 2; ++k) {
      const int32_t l = source.layers[2 * v + k];
      const glm::vec2 uv = l >= 0 ? source.layerUv(v, l) : glm::vec2(0.0f);
      target.layerTexcoords.insert(target.layerTexcoords.end(), {uv.x, uv.y});
    }
}

}  // namespace imps
