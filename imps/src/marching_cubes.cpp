// SPDX-License-Identifier: MIT
// Marching Cubes over blocks of 8^3 cells, as a list of named passes (marching_cubes_passes.h): grid, bin primitives,
// thin features, then per block cull, sample, classify, edge roots and shading; number vertices, triangulate from a
// face-consistent case table, gather in block order.
// Based on: Lorensen & Cline 1987; Nielson & Hamann 1991 (asymptotic decider).
#include "imps/marching_cubes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>

#include "imps/check.h"
#include "imps/parallel.h"
#include "marching_cubes_passes.h"
#include "vector_clones.h"

namespace imps::mc {
namespace {

// ---- The case table ------------------------------------------------------------------------------------------
// Corners: c = x | y << 1 | z << 2. Edge e = axis * 4 + m, starting at the corner with that axis' bit clear, m the
// other two bits (lower axis first). Faces: (axis a, side s), corners cycled counter-clockwise seen from outside.

int edgeId(int startCorner, int axis) {
  const int b0 = (axis + 1) % 3, b1 = (axis + 2) % 3;
  const int lo = std::min(b0, b1), hi = std::max(b0, b1);
  return axis * 4 + ((startCorner >> lo) & 1) + 2 * ((startCorner >> hi) & 1);
}
int edgeStart(int e) {
  const int axis = e / 4, m = e % 4;
  const int b0 = (axis + 1) % 3, b1 = (axis + 2) % 3;
  const int lo = std::min(b0, b1), hi = std::max(b0, b1);
  return ((m & 1) << lo) | (((m >> 1) & 1) << hi);
}

struct Face {
  int axis, side;
  std::array<int, 4> cycle;      // corners, counter-clockwise from outside
  std::array<int, 4> cycleEdge;  // edge between cycle[k] and cycle[k+1]
  std::array<int, 4> canonical;  // corners at (u,v) = (0,0), (1,0), (1,1), (0,1) for the decider
};

std::array<Face, 6> makeFaces() {
  std::array<Face, 6> faces{};
  int f = 0;
  for (int a = 0; a < 3; ++a)
    for (int s = 0; s < 2; ++s, ++f) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      auto corner = [&](int cu, int cv) { return (s << a) | (cu << u) | (cv << v); };
      const std::array<std::array<int, 2>, 4> ccw = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
      Face& face = faces[f];
      face.axis = a;
      face.side = s;
      for (int k = 0; k < 4; ++k) {
        face.canonical[k] = corner(ccw[k][0], ccw[k][1]);
        const int kk = s == 1 ? k : (4 - k) % 4;  // the far side is seen from +a, the near side from -a
        face.cycle[k] = corner(ccw[kk][0], ccw[kk][1]);
      }
      for (int k = 0; k < 4; ++k) {
        const int c0 = face.cycle[k], c1 = face.cycle[(k + 1) % 4];
        const int diff = c0 ^ c1;
        const int axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
        face.cycleEdge[k] = edgeId(std::min(c0, c1), axis);
      }
    }
  return faces;
}

struct CaseTable {
  std::array<Face, 6> faces = makeFaces();
  std::array<uint8_t, 256> ambiguousFaces{};  // bit f: face f has diagonal inside corners
  std::array<uint8_t, 12> edgeStartCorner{};   // edgeStart(e), looked up on the hot path
  std::array<int16_t, 12> ownedEdgeOffset{};   // ownedEdgeIndex() of edge e of the block's cell (0, 0, 0)
  // entries[entry(case, joinedMask)]: triangle count then 3 edge ids per triangle. Only the meaningful masks (subsets
  // of the case's ambiguous faces) have an entry, so the table is dense (656 entries, 25 KB, instead of 256 x 64 with
  // most of them empty, 600 KB) and stays in cache.
  std::vector<std::array<uint8_t, 37>> entries;
  std::vector<uint8_t> centreCount;            // loop-centre vertices of each entry
  std::array<uint16_t, 256> firstEntry{};      // the entry of each case with no face joined

  // A case's entries follow the ascending joined masks: a mask's rank is its bits gathered from the ambiguous faces'
  // positions (bit b of the rank: the b-th ambiguous face is joined).
  size_t entry(int c, int joined) const {
    size_t rank = 0;
    int bit = 0;
    for (uint32_t a = ambiguousFaces[size_t(c)]; a != 0; a &= a - 1, ++bit)
      rank |= size_t((joined >> std::countr_zero(a)) & 1) << bit;
    return firstEntry[size_t(c)] + rank;
  }

  CaseTable() {
    for (int e = 0; e < 12; ++e) {
      const int c = edgeStart(e);
      edgeStartCorner[size_t(e)] = uint8_t(c);
      ownedEdgeOffset[size_t(e)] = int16_t(ownedEdgeIndex(e / 4, c & 1, (c >> 1) & 1, (c >> 2) & 1));
    }
    for (int c = 0; c < 256; ++c) {
      for (int f = 0; f < 6; ++f) {
        int changes = 0;
        for (int k = 0; k < 4; ++k)
          changes += ((c >> faces[f].cycle[k]) & 1) != ((c >> faces[f].cycle[(k + 1) % 4]) & 1);
        if (changes == 4) ambiguousFaces[c] |= uint8_t(1u << f);
      }
      firstEntry[size_t(c)] = uint16_t(entries.size());
      for (int joined = 0; joined < 64; ++joined) {
        if ((joined & ~ambiguousFaces[c]) != 0) continue;  // only meaningful bits
        entries.emplace_back();
        centreCount.push_back(uint8_t(build(c, joined, entries.back())));
      }
    }
  }

  // Two cube edges lie on a common face.
  bool shareFace(int e0, int e1) const {
    for (const Face& f : faces) {
      bool a = false, b = false;
      for (int k = 0; k < 4; ++k) {
        a |= f.cycleEdge[k] == e0;
        b |= f.cycleEdge[k] == e1;
      }
      if (a && b) return true;
    }
    return false;
  }

  // Triangulates a loop of crossing edges without any diagonal between two crossings on a common face: the cell
  // across that face may triangulate the same pair, and the edge would then have four triangles. Dynamic
  // programming over the polygon (n <= 12). A few long loops (e.g. nine crossings) have no such triangulation;
  // they get a vertex of their own at the loop's centre (code kCentre + k for the k-th such loop of the cell),
  // fanned to every loop vertex, which no other cell can share.
  void triangulateLoop(const int* loop, int n, std::array<uint8_t, 37>& out, int& triangles, int& centres) const {
    auto allowed = [&](int i, int j) {
      const int d = (j - i + n) % n;
      return d == 1 || d == n - 1 || !shareFace(loop[i], loop[j]);
    };
    // ok[i][j]: the sub-polygon i..j (i < j) can be triangulated using only allowed diagonals; via[i][j] the apex.
    std::array<std::array<bool, 12>, 12> ok{};
    std::array<std::array<int, 12>, 12> via{};
    for (int i = 0; i + 1 < n; ++i) ok[i][i + 1] = true;
    for (int len = 2; len < n; ++len)
      for (int i = 0; i + len < n; ++i) {
        const int j = i + len;
        if (!allowed(i, j)) continue;
        for (int k = i + 1; k < j && !ok[i][j]; ++k)
          if (ok[i][k] && ok[k][j]) {
            ok[i][j] = true;
            via[i][j] = k;
          }
      }
    auto emit = [&](int a, int b, int c) {
      out[1 + 3 * triangles] = uint8_t(a);
      out[2 + 3 * triangles] = uint8_t(b);
      out[3 + 3 * triangles] = uint8_t(c);
      ++triangles;
    };
    if (!ok[0][n - 1]) {
      const int centre = kCentre + centres++;
      IMPS_CHECK_LE(centres, 2);
      for (int i = 0; i < n; ++i) emit(centre, loop[i], loop[(i + 1) % n]);
      return;
    }
    // Emit triangles (i, k, j) keeping the loop's orientation.
    std::array<std::array<int, 2>, 12> stack;
    int top = 0;
    stack[top++] = {0, n - 1};
    while (top > 0) {
      const auto [i, j] = stack[--top];
      if (j - i < 2) continue;
      const int k = via[i][j];
      emit(loop[i], loop[k], loop[j]);
      stack[top++] = {i, k};
      stack[top++] = {k, j};
    }
  }

  // Contour segments on each face go from an entry crossing (outside -> inside along the cycle) to an exit; chained
  // across faces they form loops, each triangulated (triangulateLoop). Orientation: counter-clockwise seen from
  // outside. Returns the number of loop-centre vertices.
  int build(int c, int joined, std::array<uint8_t, 37>& out) const {
    std::array<int, 12> next;
    next.fill(-1);
    for (int f = 0; f < 6; ++f) {
      const Face& face = faces[f];
      std::array<int, 4> kind{};  // 0 none, +1 entry, -1 exit
      int crossings = 0;
      for (int k = 0; k < 4; ++k) {
        const bool in0 = (c >> face.cycle[k]) & 1, in1 = (c >> face.cycle[(k + 1) % 4]) & 1;
        kind[k] = in0 == in1 ? 0 : (in1 ? 1 : -1);
        crossings += kind[k] != 0;
      }
      if (crossings == 2) {
        int entry = -1, exit = -1;
        for (int k = 0; k < 4; ++k) {
          if (kind[k] == 1) entry = k;
          if (kind[k] == -1) exit = k;
        }
        next[face.cycleEdge[entry]] = face.cycleEdge[exit];
      } else if (crossings == 4) {
        const bool join = (joined >> f) & 1;
        for (int k = 0; k < 4; ++k)
          if (kind[k] == 1) next[face.cycleEdge[k]] = face.cycleEdge[join ? (k + 3) % 4 : (k + 1) % 4];
      }
    }
    int triangles = 0, centres = 0;
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (next[start] < 0 || used[start]) continue;
      std::array<int, 12> loop;
      int n = 0;
      for (int e = start; !used[e]; e = next[e]) {
        IMPS_CHECK(next[e] >= 0);
        used[e] = true;
        loop[n++] = e;
      }
      triangulateLoop(loop.data(), n, out, triangles, centres);
    }
    out[0] = uint8_t(triangles);
    return centres;
  }
};

const CaseTable& caseTable() {
  static const CaseTable table;
  return table;
}

// ln x for normal, positive, finite x, branch-free so batches vectorise: x = 2^e m with m in [sqrt(1/2), sqrt(2)),
// then ln m = 2 atanh(s), s = (m - 1) / (m + 1), |s| <= 0.172, by its series to s^9 (error below 1e-9).
inline float lnPositive(float x) {
  const uint32_t bits = std::bit_cast<uint32_t>(x);
  const int32_t e = int32_t(bits - 0x3F3504F3u) >> 23;  // 0x3F3504F3: sqrt(1/2)
  const float m = std::bit_cast<float>(bits - (uint32_t(e) << 23));
  const float s = (m - 1.0f) / (m + 1.0f);
  const float s2 = s * s;
  const float series = 2.0f + s2 * (2.0f / 3.0f + s2 * (2.0f / 5.0f + s2 * (2.0f / 7.0f + s2 * (2.0f / 9.0f))));
  return s * series + float(e) * 0.69314718f;
}

// The most points one primitive's skeleton is sampled at (an accepted grid's diagonal is far below it).
constexpr int kMaxSkeletonPoints = 1 << 20;

// Skeleton points of primitive p at spacing <= step.
void skeletonPoints(const Primitive& p, float step, std::vector<glm::vec3>& out) {
  out.clear();
  glm::vec3 a = p.center, b = p.center;
  if (p.kind == PrimitiveKind::LineSeg) {
    a = p.p1;
    b = p.p2;
  } else if (p.kind == PrimitiveKind::Ellipsoid) {
    const int major = p.radii.x >= p.radii.y && p.radii.x >= p.radii.z ? 0 : p.radii.y >= p.radii.z ? 1 : 2;
    const float minor = std::min({p.radii.x, p.radii.y, p.radii.z});
    glm::vec3 axis(0.0f);
    axis[major] = p.radii[major] - minor;
    axis = p.rotation * axis;
    a = p.center - axis;
    b = p.center + axis;
  }
  // In double: a far endpoint's squared length overflows a float (an infinite count). A grid the planner accepted
  // holds the whole skeleton, so the count is bounded by its cells; the clamp only guards a non-finite step.
  const double count = std::ceil(glm::length(glm::dvec3(b - a)) / double(step));
  const int n = count >= 1.0 ? int(std::min(count, double(kMaxSkeletonPoints))) : 1;
  for (int s = 0; s <= n; ++s) out.push_back(a + (b - a) * (float(s) / float(n)));
}

// Whether options.cancel is set (relaxed: a late view only costs one more block).
bool cancelled(const MarchingCubesOptions& o) { return o.cancel && o.cancel->load(std::memory_order_relaxed); }

// A loop-centre vertex is accepted this close to the surface: |F - iso| / |grad F| in cells.
constexpr float kCentreTolerance = 1e-3f;

// |F - iso| / |grad F| at a sample (the distance to the surface to first order); infinite where the gradient is 0.
float surfaceOffset(const FieldSample& s, float iso) {
  const float g = glm::length(s.gradient);
  return g > 0.0f ? std::abs(s.value - iso) / g : std::numeric_limits<float>::infinity();
}

// The mean of a loop-centre vertex's loop (its `count` vertices at `loop`), moved onto the surface; `reach` is its
// cell grown by a cell on every side, where the block's candidates hold every primitive whose support reaches. Up to
// three Newton steps first, as long as they stay in `reach`: they suffice where F is near linear over the step.
// Where they leave the point more than kCentreTolerance cells off the surface (from deep inside the exponential blend
// Newton creeps, lowering ln F by about 1 a step; near a support's edge, or where the mean lies in the air of a
// saddle, a step leaves the cell), the root nearest the mean is bracketed along lines through it (the outward normal
// there and the loop's mean normal, both ways, then the six axis directions), stepping out to a cell, and found by
// the Illinois method to within that tolerance. Without any bracket, the better of the mean and Newton's point is
// kept. Every point depends only on the loop, so 1 and N threads agree.
FieldSample centreVertex(const Field& field, glm::vec3 mean, const glm::vec3* loop, int count, const Box& reach,
                         FieldScratch& scratch, glm::vec3& x) {
  const glm::vec3 cells = (reach.hi - reach.lo) / 3.0f;
  const float cell = std::max({cells.x, cells.y, cells.z}), side = std::min({cells.x, cells.y, cells.z});
  const float iso = field.iso(), tolerance = kCentreTolerance * cell;
  x = mean;
  const FieldSample atMean = field.sample(x, scratch);
  FieldSample fs = atMean;
  for (int step = 0; step < 3; ++step) {
    const float g2 = glm::dot(fs.gradient, fs.gradient);
    if (g2 <= 0.0f) break;
    const glm::vec3 next = x - (fs.value - iso) / g2 * fs.gradient;
    if (!reach.contains(next)) break;  // beyond the candidates' reach: F there would miss primitives
    x = next;
    fs = field.sample(x, scratch);
  }
  if (surfaceOffset(fs, iso) <= tolerance) return fs;
  if (surfaceOffset(atMean, iso) < surfaceOffset(fs, iso)) x = mean, fs = atMean;
  // The lines to search, as unit directions (each also reversed).
  std::array<glm::vec3, 5> lines{glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0),
                                 glm::vec3(0, 0, 1)};
  if (glm::dot(atMean.gradient, atMean.gradient) > 0.0f) lines[0] = glm::normalize(atMean.gradient);
  for (int v = 0; v < count; ++v)
    if (const glm::vec3 g = field.sample(loop[v], scratch).gradient; glm::dot(g, g) > 0.0f)
      lines[1] += glm::normalize(g);
  if (glm::dot(lines[1], lines[1]) > 1e-12f) lines[1] = glm::normalize(lines[1]);
  // F - iso along mean + t d; inside is F >= iso, as the samples are classified.
  const float f0 = atMean.value - iso;
  glm::vec3 d(0.0f);
  float ta = 0.0f, fa = f0, tb = 0.0f, fb = 0.0f;
  bool bracketed = false;
  for (float reachOut = 0.0f, step = 0.125f; step <= 1.0f && !bracketed; reachOut = step, step *= 2.0f)
    for (const glm::vec3& line : lines) {
      if (glm::dot(line, line) == 0.0f) continue;
      for (const float sign : {1.0f, -1.0f}) {
        const float f = field.sample(mean + sign * step * side * line, scratch).value - iso;
        if ((f >= 0.0f) == (f0 >= 0.0f)) continue;
        // The inner end, sampled in the round before on this line, had the mean's side.
        d = sign * line, ta = reachOut * side, tb = step * side, fb = f;
        fa = ta > 0.0f ? field.sample(mean + ta * d, scratch).value - iso : f0;
        bracketed = true;
        break;
      }
      if (bracketed) break;
    }
  if (!bracketed) return fs;
  float bestOffset = surfaceOffset(fs, iso);
  int kept = 0;  // which end the last step kept (Illinois: halve the other end's value on a repeat)
  for (int step = 0; step < 40 && std::abs(tb - ta) > tolerance; ++step) {
    const float t = fb != fa ? (ta * fb - tb * fa) / (fb - fa) : 0.5f * (ta + tb);
    const FieldSample s = field.sample(mean + t * d, scratch);
    if (const float offset = surfaceOffset(s, iso); offset < bestOffset) {
      x = mean + t * d, bestOffset = offset, fs = s;
      if (offset <= tolerance) break;
    }
    const float f = s.value - iso;
    if ((f >= 0.0f) == (fa >= 0.0f)) {
      ta = t, fa = f;
      if (kept == 1) fb *= 0.5f;
      kept = 1;
    } else {
      tb = t, fb = f;
      if (kept == -1) fa *= 0.5f;
      kept = -1;
    }
  }
  return fs;
}

// The faces of cell (i, j, k) (case code cs) whose inside corners are joined, as bits: each ambiguous face decided
// by its bilinear saddle value (the asymptotic decider), from the face's four samples only.
int joinedFaces(const CaseTable& table, const BlockResult& r, int i, int j, int k, int cs, float iso) {
  int joined = 0;
  const uint8_t ambiguous = table.ambiguousFaces[size_t(cs)];
  if (!ambiguous) return 0;
  float f[8];
  for (int c = 0; c < 8; ++c) f[c] = r.samples[sampleIndex(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
  for (int face = 0; face < 6; ++face) {
    if (!((ambiguous >> face) & 1)) continue;
    const auto& cc = table.faces[size_t(face)].canonical;
    const float a = f[cc[0]] - iso, bb = f[cc[1]] - iso, c2 = f[cc[2]] - iso, d = f[cc[3]] - iso;
    // Bilinear saddle value: inside corners are joined when it is inside.
    const float denom = a + c2 - bb - d;
    const float saddle = denom != 0.0f ? (a * c2 - bb * d) / denom : 0.0f;
    if (saddle >= 0.0f) joined |= 1 << face;
  }
  return joined;
}

// The block owning a cube edge of one of block b's cells, and the edge vertex's local number in it.
struct EdgeRef {
  const BlockResult* owner;
  uint32_t local;
};

// Resolves the cube edges of block b's cells to their vertices (the block itself or a +x, +y, +z neighbour).
struct EdgeResolver {
  const CaseTable& table;
  const Grid& g;
  const BlockResult& r;
  glm::ivec3 block;
  std::array<const BlockResult*, 8> owners{};  // owners[ox | oy << 1 | oz << 2]: the block (0) and its neighbours

  EdgeResolver(const CaseTable& t, const Grid& grid, const std::vector<BlockResult>& blocks, const BlockResult& self,
               glm::ivec3 blockCoords)
      : table(t), g(grid), r(self), block(blockCoords) {
    for (int o = 0; o < 8; ++o) {
      const glm::ivec3 n = block + glm::ivec3(o & 1, (o >> 1) & 1, o >> 2);
      if (n.x < g.blocks.x && n.y < g.blocks.y && n.z < g.blocks.z)
        owners[size_t(o)] = &blocks[g.blockIndex(n.x, n.y, n.z)];
    }
  }

  // Cell (i, j, k)'s cube edge e, wherever it is owned.
  EdgeRef any(int i, int j, int k, int e) const {
    const int corner = table.edgeStartCorner[size_t(e)], axis = e / 4;
    const int vi = i + (corner & 1), vj = j + ((corner >> 1) & 1), vk = k + ((corner >> 2) & 1);
    const int ox = vi / kBlock, oy = vj / kBlock, oz = vk / kBlock;  // 1 on the far faces: the next block owns it
    const BlockResult& owner = *owners[size_t(ox | oy << 1 | oz << 2)];
    IMPS_DCHECK(owner.hasSurface);
    const int32_t local = owner.edgeVertex[size_t(ownedEdgeIndex(axis, vi - ox * kBlock, vj - oy * kBlock,
                                                                 vk - oz * kBlock))];
    IMPS_DCHECK_GE(local, 0);
    return {&owner, uint32_t(local)};
  }
  // The same for a cell off the block's far faces (every edge owned by this block): a table offset finds it.
  uint32_t interior(uint32_t cellIndex, int e) const {
    const int32_t local = r.edgeVertex[size_t(int(cellIndex) + table.ownedEdgeOffset[size_t(e)])];
    IMPS_DCHECK_GE(local, 0);
    return uint32_t(local);
  }
  EdgeRef of(uint32_t cellIndex, bool inside, int i, int j, int k, int e) const {
    return inside ? EdgeRef{&r, interior(cellIndex, e)} : any(i, j, k, e);
  }
};

// Appends cell `cell`'s loop-centre vertices (table entry entryIndex) to r, their provisional indices to centreIndex.
// The field is prepared (block b's candidates) the first time one is needed.
void centreVertices(const Field& field, const MarchingCubesOptions& options, const EdgeResolver& edges, uint32_t cell,
                    size_t entryIndex, std::span<const uint32_t> candidates, bool& prepared, FieldScratch& scratch,
                    BlockResult& r, uint32_t (&centreIndex)[2]) {
  const CaseTable& table = edges.table;
  const auto& entry = table.entries[entryIndex];
  const uint32_t index = cell & 0xFFFFu;
  const int i = int(index) % kBlock, j = int(index) / kBlock % kBlock, k = int(index) / (kBlock * kBlock);
  const bool inside = i < kBlock - 1 && j < kBlock - 1 && k < kBlock - 1;
  const int centres = table.centreCount[entryIndex];
  // The cell grown by a cell on every side: the block's candidates hold every primitive whose support reaches it.
  const glm::ivec3 v = edges.block * kBlock + glm::ivec3(i, j, k);
  const Box reach{edges.g.vertex(v.x - 1, v.y - 1, v.z - 1), edges.g.vertex(v.x + 2, v.y + 2, v.z + 2)};
  for (int centre = 0; centre < centres; ++centre) {
    glm::vec3 sum(0.0f), loop[12];
    int count = 0;
    for (int t = 0; t < entry[0]; ++t) {
      if (entry[size_t(1 + 3 * t)] != kCentre + centre) continue;
      const auto [owner, local] = edges.of(index, inside, i, j, k, entry[size_t(2 + 3 * t)]);
      loop[count] =
          glm::vec3(owner->positions[3 * local], owner->positions[3 * local + 1], owner->positions[3 * local + 2]);
      sum += loop[count++];
    }
    if (count == 0) break;
    if (!prepared) {
      field.prepare(candidates, scratch);
      prepared = true;
    }
    glm::vec3 x;
    const FieldSample fs = centreVertex(field, sum / float(count), loop, count, reach, scratch, x);
    centreIndex[centre] = kProvisional | uint32_t(r.centrePositions.size() / 3);
    r.centrePositions.insert(r.centrePositions.end(), {x.x, x.y, x.z});
    const float len = glm::length(fs.gradient);
    const glm::vec3 n = len > 0.0f ? -fs.gradient / len : glm::vec3(0, 0, 1);
    if (options.computeNormals) r.centreNormals.insert(r.centreNormals.end(), {n.x, n.y, n.z});
    if (options.computeColors) r.centreColors.insert(r.centreColors.end(), {fs.color.x, fs.color.y, fs.color.z});
  }
}

}  // namespace

// ---- 1. Grid -------------------------------------------------------------------------------------------------

// The cell size and the cells needed along each axis (one cell of margin on each side so no surface touches the
// grid boundary, rounded up to whole blocks), counted in floating point so that no cell size overflows an int; or
// why the grid is refused.
struct GridPlan {
  glm::vec3 cell{1.0f};
  glm::dvec3 cells{0.0};
  std::string error;
};

GridPlan planGridCells(const Field& field, const MarchingCubesOptions& o) {
  GridPlan p;
  Box bounds = field.surfaceBounds();
  if (bounds.empty()) return p;
  const glm::vec3 size = glm::max(bounds.size(), glm::vec3(1e-6f));
  if (o.cellSize > 0.0f) {
    p.cell = glm::vec3(o.cellSize);
  } else if (o.gridResolution.x > 0 && o.gridResolution.y > 0 && o.gridResolution.z > 0) {
    p.cell = size / glm::vec3(o.gridResolution);
  } else {
    p.cell = glm::vec3(std::max({size.x, size.y, size.z}) / float(std::max(o.resolution, 1)));
  }
  const glm::dvec3 need = glm::dvec3(glm::ceil(size / p.cell)) + 2.0;  // float division, as ever; no int yet
  p.cells = glm::ceil(need / double(kBlock)) * double(kBlock);
  const double count = p.cells.x * p.cells.y * p.cells.z;
  if (!(count <= double(o.maxCells))) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "a grid of %.0f x %.0f x %.0f cells (%.3g) for a surface of %.3g x %.3g x %.3g m at cell %.3g m is "
                  "more than the limit of %zu cells",
                  p.cells.x, p.cells.y, p.cells.z, count, double(size.x), double(size.y), double(size.z),
                  double(p.cell.x), o.maxCells);
    p.error = text;
  }
  return p;
}

Grid makeGrid(const Field& field, const MarchingCubesOptions& o) {
  Grid g;
  const GridPlan p = planGridCells(field, o);
  if (!p.error.empty() || p.cells.x == 0.0) return g;  // nothing to mesh, or refused: an empty grid, an empty mesh
  g.cell = p.cell;
  g.cells = glm::ivec3(p.cells);
  g.blocks = g.cells / kBlock;
  g.origin = field.surfaceBounds().center() - 0.5f * glm::vec3(g.cells) * g.cell;
  return g;
}

BlockAxes::BlockAxes(const Grid& g, glm::ivec3 block) {
  for (int v = 0; v < kBlockVerts; ++v) {
    const glm::vec3 p = g.vertex(block.x * kBlock + v, block.y * kBlock + v, block.z * kBlock + v);
    xs[size_t(v)] = p.x;
    ys[size_t(v)] = p.y;
    zs[size_t(v)] = p.z;
  }
}

// ---- 2. Bin primitives ---------------------------------------------------------------------------------------

void binPrimitives(const Field& field, const Grid& g, Bins& bins) {
  const size_t blockCount = g.blockCount();
  bins.offsets.assign(blockCount + 1, 0);
  auto blockRange = [&](const Box& b, glm::ivec3& lo, glm::ivec3& hi) {
    lo = glm::clamp(glm::ivec3(glm::floor((b.lo - g.cell - g.origin) / (g.cell * float(kBlock)))), glm::ivec3(0),
                    g.blocks - 1);
    hi = glm::clamp(glm::ivec3(glm::floor((b.hi + g.cell - g.origin) / (g.cell * float(kBlock)))), glm::ivec3(0),
                    g.blocks - 1);
  };
  // Two passes over the same ranges: count, then (after the prefix sum) fill.
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) {
      for (size_t b = 0; b < blockCount; ++b) bins.offsets[b + 1] += bins.offsets[b];
      bins.members.resize(bins.offsets[blockCount]);
      bins.cursor.assign(bins.offsets.begin(), bins.offsets.end() - 1);
    }
    for (size_t i = 0; i < field.size() && blockCount > 0; ++i) {
      glm::ivec3 lo, hi;
      blockRange(field.supportBox(i), lo, hi);
      for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
          for (int x = lo.x; x <= hi.x; ++x) {
            const size_t b = g.blockIndex(x, y, z);
            if (pass == 0) ++bins.offsets[b + 1];
            else bins.members[bins.cursor[b]++] = uint32_t(i);
          }
    }
  }
}

// ---- 3. Thin features ----------------------------------------------------------------------------------------

namespace {

// The grid vertices moved onto skeleton points, one per vertex (the deepest point wins), sorted by key.
void thinFeatureSnaps(const Field& field, const Grid& g, std::vector<glm::vec3>& points, FieldScratch& scratch,
                      std::vector<Snap>& snaps) {
  snaps.clear();
  const float iso = field.iso();
  const float step = 0.5f * std::min({g.cell.x, g.cell.y, g.cell.z});
  auto nearest = [&](const glm::vec3& p) { return glm::ivec3(glm::round((p - g.origin) / g.cell)); };
  auto valueAt = [&](const glm::vec3& x) { return field.value(x, scratch); };
  auto consider = [&](const glm::ivec3& v, const glm::vec3& p, float fp) {
    if (glm::any(glm::lessThan(v, glm::ivec3(1))) || glm::any(glm::greaterThan(v, g.cells - 1))) return;
    const glm::vec3 gv = g.vertex(v.x, v.y, v.z);
    if (valueAt(gv) >= iso) return;  // already inside: nothing to preserve
    snaps.push_back({g.vertexKey(v.x, v.y, v.z), p, fp});
  };
  // A primitive thicker than half a cell diagonal cannot be missed: for the additive blends with iso <= 1 every
  // point within its own radius of its skeleton is inside (F >= its own term >= 1 >= iso), and the grid vertex
  // nearest any skeleton point is within half a diagonal.
  const float halfDiagonal = 0.5f * glm::length(g.cell);
  const bool ownRadiusInside = field.blend().additive() && iso <= 1.0f;
  for (size_t i = 0; i < field.size(); ++i) {
    if (ownRadiusInside && field.primitive(i).minRadius() > halfDiagonal) continue;
    skeletonPoints(field.primitive(i), step, points);
    // One candidate list for the skeleton and the grid vertices around it (values do not depend on the region).
    Box region;
    for (const glm::vec3& p : points) region.extend(p);
    region.lo -= 2.0f * g.cell;
    region.hi += 2.0f * g.cell;
    field.prepare(region, scratch);
    glm::ivec3 previous(-1);
    glm::vec3 previousPoint(0.0f);
    float previousValue = 0.0f;
    for (const glm::vec3& p : points) {
      const float fp = valueAt(p);
      if (fp < iso) {
        previous = glm::ivec3(-1);
        continue;
      }
      const glm::ivec3 v = nearest(p);
      consider(v, p, fp);
      // 6-connect to the previous skeleton vertex: step one axis at a time through grid vertices, each moved onto
      // whichever of the two skeleton points is nearer.
      if (previous.x >= 0) {
        glm::ivec3 w = previous;
        for (int axis = 0; axis < 3; ++axis)
          while (w[axis] != v[axis]) {
            w[axis] += v[axis] > w[axis] ? 1 : -1;
            if (w == v) break;
            const glm::vec3 gw = g.vertex(w.x, w.y, w.z);
            const bool nearPrev = glm::length(gw - previousPoint) < glm::length(gw - p);
            consider(w, nearPrev ? previousPoint : p, nearPrev ? previousValue : fp);
          }
      }
      previous = v;
      previousPoint = p;
      previousValue = fp;
    }
  }
  std::sort(snaps.begin(), snaps.end(), [](const Snap& a, const Snap& b) {
    return a.key != b.key ? a.key < b.key : a.value > b.value;
  });
  snaps.erase(std::unique(snaps.begin(), snaps.end(), [](const Snap& a, const Snap& b) { return a.key == b.key; }),
              snaps.end());
}

// forced[b] = 1 for every block whose closed vertex range holds a snapped vertex.
void markForcedBlocks(std::span<const Snap> snaps, const Grid& g, std::vector<uint8_t>& forced) {
  forced.assign(g.blockCount(), 0);
  for (const Snap& s : snaps) {
    const int64_t vx = s.key % g.verts().x, vy = (s.key / g.verts().x) % g.verts().y,
                  vz = s.key / (int64_t(g.verts().x) * g.verts().y);
    for (int dz = -1; dz <= 0; ++dz)
      for (int dy = -1; dy <= 0; ++dy)
        for (int dx = -1; dx <= 0; ++dx) {
          // The block whose closed vertex range holds (vx, vy, vz): floor(v / B) and, on a block boundary, the one
          // below.
          const int64_t bx = (vx + dx * (vx % kBlock == 0 ? 1 : 0)) / kBlock;
          const int64_t by = (vy + dy * (vy % kBlock == 0 ? 1 : 0)) / kBlock;
          const int64_t bz = (vz + dz * (vz % kBlock == 0 ? 1 : 0)) / kBlock;
          if (bx >= 0 && by >= 0 && bz >= 0 && bx < g.blocks.x && by < g.blocks.y && bz < g.blocks.z)
            forced[g.blockIndex(int(bx), int(by), int(bz))] = 1;
        }
  }
}

}  // namespace

void findThinFeatures(const Field& field, const Grid& g, MarchingCubes::State& st) {
  thinFeatureSnaps(field, g, st.skeleton, st.workers.at(0).field, st.snaps);
  markForcedBlocks(st.snaps, g, st.forced);
}

// ---- 4. Per block: cull, sample, classify, edge roots, shading -----------------------------------------------

bool cullBlock(const Field& field, const Grid& g, size_t b, std::span<const uint32_t> cand, bool forced,
               WorkerScratch& ws) {
  if (cand.empty() && !forced) return false;
  if (forced) {
    field.prepare(cand, ws.field);
    return true;
  }
  const glm::ivec3 bc = g.blockCoords(b);
  const Box box = g.blockBox(bc.x, bc.y, bc.z);
  const float iso = field.iso();
  // Binning used support *boxes*; drop the candidates whose support cannot reach this block at all. Their terms
  // are exactly zero here, so every value stays bit-identical (x + 0 = x) with fewer primitives to evaluate.
  ws.reaching.clear();
  ws.reachingDistances.clear();
  // For the additive blends, the sum of every reaching candidate's largest term in the block bounds each blend
  // set's sum from above (float addition of non-negative terms is monotone): most empty blocks stop here,
  // before the blend sets are prepared for the tighter upperBound().
  float largestTermsSum = 0.0f;
  for (uint32_t i : cand) {
    const Primitive& p = field.primitive(i);
    const float skip = field.supportDistance(i) * (1.0f + 1e-3f) + 1e-3f;
    // A line segment's cheap bound (never above the tight one) already puts most candidates beyond the support;
    // only the others pay for the refinement. (The other kinds have only the one bound.)
    float d = p.minDistance(box, /*tight=*/false);
    if (d > skip) continue;
    if (p.kind == PrimitiveKind::LineSeg) d = p.minDistance(box);
    if (d > skip) continue;
    ws.reaching.push_back(i);
    ws.reachingDistances.push_back(d);
    largestTermsSum += field.blend().term(d, field.param(i));
  }
  if (ws.reaching.empty()) return false;
  const bool additive = field.blend().additive();
  if (additive && largestTermsSum < iso * (1.0f - 1e-3f)) return false;
  field.prepare(ws.reaching, ws.field);
  // With one blend set that sum is upperBound() itself (the same terms added in the same order).
  const bool oneSet = additive && ws.field.setCount() == 1;
  if (!oneSet && field.upperBound(ws.reachingDistances, ws.field) < iso * (1.0f - 1e-3f)) return false;
  // Wholly inside? For the additive blends each set's sum of its members' smallest terms in the block (far tighter
  // than the largest single one where many overlap, as deep inside a crowd of blobs), never above the sum of the
  // largest terms, so only asked when that is above iso.
  if (!additive) return field.lowerBound(box, ws.field) <= iso * (1.0f + 1e-3f);
  if (largestTermsSum <= iso * (1.0f + 1e-3f)) return true;
  ws.reachingDistances.clear();  // now the largest distances
  for (uint32_t i : ws.reaching) ws.reachingDistances.push_back(field.primitive(i).maxDistance(box));
  return field.lowerBound(ws.reachingDistances, ws.field) <= iso * (1.0f + 1e-3f);
}

bool cullSubBlocks(const Field& field, const Grid& g, glm::ivec3 block, bool forced, WorkerScratch& ws) {
  const float iso = field.iso();
  std::array<Box, kSubBlocks> boxes;
  for (int s = 0; s < kSubBlocks; ++s) {
    const glm::ivec3 lo = block * kBlock + glm::ivec3(s & 1, (s >> 1) & 1, s >> 2) * kSubBlock;
    boxes[size_t(s)].lo = g.vertex(lo.x, lo.y, lo.z);
    boxes[size_t(s)].hi = g.vertex(lo.x + kSubBlock, lo.y + kSubBlock, lo.z + kSubBlock);
  }
  // With few candidates the samples are cheaper than the bounds (the biped: about three per block), and so they are
  // when every candidate is separable on the lattice (metaballs under the exponential blend).
  forced |= ws.field.candidates.size() < kSubBlockMinCandidates || field.separableOnLattice(ws.field);
  std::array<float, kSubBlocks> lower, upper;
  if (!forced) field.boxBounds(boxes, lower, upper, ws.field);
  bool anyLive = false;
  for (size_t s = 0; s < kSubBlocks; ++s) {
    ws.subBlocks[s] = forced                            ? kLive
                      : upper[s] < iso * (1.0f - 1e-3f) ? kOutside
                      : lower[s] > iso * (1.0f + 1e-3f) ? kInside
                                                        : kLive;
    anyLive |= ws.subBlocks[s] == kLive;
  }
  // Row (j, k) is needed when a live sub-block's closed vertex range [lo, lo + kSubBlock] holds j and k.
  ws.rows.fill(0);
  for (int s = 0; s < kSubBlocks; ++s) {
    if (ws.subBlocks[size_t(s)] != kLive) continue;
    const int j0 = ((s >> 1) & 1) * kSubBlock, k0 = (s >> 2) * kSubBlock;
    for (int k = k0; k <= k0 + kSubBlock; ++k)
      for (int j = j0; j <= j0 + kSubBlock; ++j) ws.rows[size_t(j + kBlockVerts * k)] = 1;
  }
  return anyLive;
}

void sampleBlock(const Field& field, const Grid& g, glm::ivec3 block, const BlockAxes& axes,
                 std::span<const Snap> snaps, BlockResult& r, WorkerScratch& ws) {
  r.samples.resize(kBlockSamples);
  field.latticeValues(axes.xs, axes.ys, axes.zs, r.samples, ws.field, ws.rows);
  // The rows left out lie in culled sub-blocks only: their side from the sub-block's class (the sub-blocks that
  // share a sample agree, their bounds being conservative).
  auto half = [](int v) { return std::min(v / kSubBlock, 1); };
  for (int k = 0; k < kBlockVerts; ++k)
    for (int j = 0; j < kBlockVerts; ++j) {
      if (ws.rows[size_t(j + kBlockVerts * k)]) continue;
      for (int i = 0; i < kBlockVerts; ++i) {
        const uint8_t c = ws.subBlocks[size_t(half(i) + 2 * half(j) + 4 * half(k))];
        IMPS_DCHECK(c != kLive);
        r.samples[size_t(sampleIndex(i, j, k))] = c == kInside ? FLT_MAX : 0.0f;
      }
    }
  if (snaps.empty()) return;
  for (int k = 0; k < kBlockVerts; ++k)
    for (int j = 0; j < kBlockVerts; ++j) {
      const int64_t rowKey = g.vertexKey(block.x * kBlock, block.y * kBlock + j, block.z * kBlock + k);
      auto it = std::lower_bound(snaps.begin(), snaps.end(), rowKey,
                                 [](const Snap& s, int64_t key) { return s.key < key; });
      for (; it != snaps.end() && it->key <= rowKey + kBlock; ++it) {
        const int s = sampleIndex(int(it->key - rowKey), j, k);
        r.samples[size_t(s)] = it->value;
        r.moved.emplace_back(s, it->position);
      }
    }
}

namespace {

// Fewer candidates than this in a block: root finding starts from the line's root, an evaluation of the field
// costing less than the cubic estimate would save (the biped's blocks); classifyBlock then keeps no outer samples.
constexpr size_t kCubicMinCandidates = 6;

// Inside bits, one 9-bit mask per row of samples: rows[j + 9k] bit i is sample (i, j, k) >= iso.
// The comparisons run as one vectorised pass into bytes (0 or 1); a row's first eight bytes, read as a
// little-endian word, become bits by one multiplication: byte i (bit 8i) times 2^(56 - 7i) lands on bit 56 + i,
// and no two products share a bit, so nothing carries.
std::array<uint32_t, kBlockVerts * kBlockVerts> insideRows(std::span<const float> samples, float iso) {
  static_assert(std::endian::native == std::endian::little);
  std::array<uint8_t, kBlockSamples + 7> inside{};  // padded so the last row's 8-byte read stays inside
  for (int s = 0; s < kBlockSamples; ++s) inside[size_t(s)] = samples[size_t(s)] >= iso;
  std::array<uint32_t, kBlockVerts * kBlockVerts> rows;
  for (int row = 0; row < kBlockVerts * kBlockVerts; ++row) {
    uint64_t bytes;
    std::memcpy(&bytes, inside.data() + row * kBlockVerts, sizeof bytes);
    rows[size_t(row)] =
        uint32_t((bytes * 0x0102040810204080ull) >> 56) | uint32_t(inside[size_t(row * kBlockVerts + 8)]) << 8;
  }
  return rows;
}

}  // namespace

bool classifyBlock(float iso, int rootIterations, const BlockAxes& axes, BlockResult& r, WorkerScratch& ws) {
  const auto rows = insideRows(r.samples, iso);
  auto rowMask = [&](int j, int k) { return rows[size_t(j + kBlockVerts * k)]; };
  // Sample (i, j, k)'s position, and whether it was moved onto a skeleton point.
  auto samplePosition = [&](int i, int j, int k, bool& moved) -> glm::vec3 {
    for (const auto& [s, p] : r.moved)
      if (s == sampleIndex(i, j, k)) {
        moved = true;
        return p;
      }
    return {axes.xs[size_t(i)], axes.ys[size_t(j)], axes.zs[size_t(k)]};
  };
  // F at the sample `step` samples along `axis` from (i, j, k) (-1 or 2: just outside an edge's ends), or -1 where
  // that is no sample of the field on the edge's line: off the block, on a row left out, or in a block with moved
  // vertices.
  auto outerSample = [&](int i, int j, int k, int axis, int step) -> float {
    glm::ivec3 v(i, j, k);
    v[axis] += step;
    if (v[axis] < 0 || v[axis] > kBlock || !ws.rows[size_t(v.y + kBlockVerts * v.z)]) return -1.0f;
    return r.samples[size_t(sampleIndex(v.x, v.y, v.z))];
  };
  // Only findEdgeRoots' cubic estimate reads them (see there), and not in a block with moved vertices.
  const bool cubic = ws.field.candidates.size() >= kCubicMinCandidates && r.moved.empty();
  ws.edges.clear();
  ws.ends.clear();
  ws.outer.clear();
  r.cells.clear();
  r.edgeVertex.assign(kBlockEdges, -1);
  for (int k = 0; k < kBlock; ++k)
    for (int j = 0; j < kBlock; ++j) {
      const uint32_t r00 = rowMask(j, k), r10 = rowMask(j + 1, k), r01 = rowMask(j, k + 1),
                     r11 = rowMask(j + 1, k + 1);
      const uint32_t anyIn = r00 | r10 | r01 | r11, allIn = r00 & r10 & r01 & r11;
      for (uint32_t mixed = (anyIn | anyIn >> 1) & ~(allIn & allIn >> 1) & kCellBits; mixed != 0;
           mixed &= mixed - 1) {
        const int i = std::countr_zero(mixed);
        const uint32_t cs =
            ((r00 >> i) & 3u) | ((r10 >> i) & 3u) << 2 | ((r01 >> i) & 3u) << 4 | ((r11 >> i) & 3u) << 6;
        r.cells.push_back(uint32_t(i + kBlock * (j + kBlock * k)) | cs << 16);
      }
      const std::array<uint32_t, 3> crossing = {(r00 ^ r00 >> 1) & kCellBits, (r00 ^ r10) & kCellBits,
                                                (r00 ^ r01) & kCellBits};
      for (uint32_t any = crossing[0] | crossing[1] | crossing[2]; any != 0; any &= any - 1) {
        const int i = std::countr_zero(any);
        const int s0 = sampleIndex(i, j, k);
        for (int axis = 0; axis < 3; ++axis) {
          if (!((crossing[size_t(axis)] >> i) & 1u)) continue;
          const int s1 = s0 + (axis == 0 ? 1 : axis == 1 ? kBlockVerts : kBlockVerts * kBlockVerts);
          r.edgeVertex[size_t(ownedEdgeIndex(axis, i, j, k))] = int16_t(ws.edges.size());
          EdgeRoot e;
          bool moved = false;
          e.pa = samplePosition(i, j, k, moved);
          e.pb = samplePosition(i + (axis == 0), j + (axis == 1), k + (axis == 2), moved);
          ws.ends.push_back(r.samples[size_t(s0)]);
          ws.ends.push_back(r.samples[size_t(s1)]);
          if (cubic) {
            ws.outer.push_back(outerSample(i, j, k, axis, -1));
            ws.outer.push_back(outerSample(i, j, k, axis, 2));
          }
          // Edges from a vertex moved onto a thin limb span a much steeper field: give them more steps.
          e.iterations = moved ? std::max(rootIterations, 10) : rootIterations;
          ws.edges.push_back(e);
        }
      }
    }
  return !r.cells.empty();
}

// Root finding runs on a distance-like g for the exponential blend, so that the first interpolation is already
// near the root. One term is F = exp(B (d - 1)) with d the squared normalised distance to the skeleton, so
// d = 1 + ln F / B and g = (ln F - ln iso) / (sqrt(d_iso) + sqrt(d)) = B (sqrt(d) - sqrt(d_iso)) is linear in the
// distance (ln F alone is quadratic in it). Written as a quotient, g has exactly the sign of ln F - ln iso and
// its full precision near the root; the floor only guards the denominator where both roots are 0 (F and iso both
// at least exp(-B)). F is exactly 0 beyond every support; clamping at the smallest non-zero term keeps ln F finite.
RootTransform::RootTransform(const Field& field)
    : logSpace(field.blend().kind == BlendKind::Exponential), iso(field.iso()), logIso(lnPositive(iso)),
      invB(logSpace ? 1.0f / field.blend().defaultParam : 0.0f),
      rootIso(std::sqrt(std::max(1.0f + logIso * invB, 0.0f))) {}

[[gnu::always_inline]] inline float RootTransform::operator()(float v) const {
  if (!logSpace) return v - iso;
  const float lnF = lnPositive(std::max(v, kExponentialCutoff));
  return (lnF - logIso) / std::max(rootIso + std::sqrt(std::max(1.0f + lnF * invB, 0.0f)), 1e-6f);
}

namespace {

// Outer samples below this (near the cutoff, where the transform clamps) say nothing about g's shape.
constexpr float kOuterMin = 4.0f * kExponentialCutoff;

// Each edge's first root estimate from g at its ends (ga at 0, gb at 1: ends[2q], ends[2q + 1]) and, where known (not
// NaN), just outside them (gm at -1, gp at 2: outer[2q], outer[2q + 1]): the root in (0, 1) of the polynomial through
// the known values (cubic, quadratic or the line), by Newton steps from the line's root; the line's root if those
// leave (0, 1). Curvature costs a cubic little, so the first evaluation is mostly already within tolerance. Every
// case's coefficients are computed and the edge's chosen without branches, so the loop vectorises; each lane's
// arithmetic is its case's alone (a case without gm or gp has c3 = 0, and no coefficient of an unknown value is
// chosen), so the bits do not depend on the neighbours.
IMPS_VECTOR_CLONES void firstEstimates(size_t n, const float* __restrict ends, const float* __restrict outer,
                                       float* __restrict t) {
  for (size_t q = 0; q < n; ++q) {
    const float gm = outer[2 * q], ga = ends[2 * q], gb = ends[2 * q + 1], gp = outer[2 * q + 1];
    const float linear = ga / (ga - gb);
    const bool before = gm == gm, after = gp == gp;
    const float c2After = (ga - 2.0f * gb + gp) / 2.0f;
    const float c1 = before && after ? -gm / 3.0f - ga / 2.0f + gb - gp / 6.0f
                     : before        ? (gb - gm) / 2.0f
                                     : gb - ga - c2After;
    const float c2 = before && after ? gm / 2.0f - ga + gb / 2.0f : before ? (gb + gm) / 2.0f - ga : c2After;
    const float c3 = before && after ? -gm / 6.0f + ga / 2.0f - gb / 2.0f + gp / 6.0f : 0.0f;
    float u = linear;
    for (int step = 0; step < 3; ++step) {
      const float p = ga + u * (c1 + u * (c2 + u * c3)), slope = c1 + u * (2.0f * c2 + u * 3.0f * c3);
      u -= p / slope;
    }
    // (the line's also where a step divided by 0: NaN fails both tests)
    t[q] = (before || after) && u > 0.0f && u < 1.0f ? u : linear;
  }
}

}  // namespace

void findEdgeRoots(const Field& field, RootTransform tf, bool shade, WorkerScratch& ws) {
  // (tf is a by-value copy: a reference could alias the values it transforms, which would keep its loops scalar.)
  std::vector<EdgeRoot>& edges = ws.edges;
  // The ends' (and outer samples') transformed values in one vectorised pass, then each edge's first estimate. With
  // few candidates an evaluation of the field costs less than the cubic would save: the line's root then.
  const bool cubic = ws.outer.size() == ws.ends.size();  // classifyBlock kept the outer samples
  for (float& v : ws.ends) v = tf(v);
  if (cubic)
    for (float& v : ws.outer) v = v > kOuterMin && v < FLT_MAX ? tf(v) : NAN;
  ws.values.resize(edges.size());
  if (cubic) firstEstimates(edges.size(), ws.ends.data(), ws.outer.data(), ws.values.data());
  for (size_t q = 0; q < edges.size(); ++q) {
    EdgeRoot& e = edges[q];
    e.ga = ws.ends[2 * q];
    e.gb = ws.ends[2 * q + 1];
    e.t = cubic ? ws.values[q] : e.ga / (e.ga - e.gb);
    // Scale-free stopping rule: |g| below 5e-4 of its change along the edge puts the vertex within about
    // 5e-4 of an edge of the root where g is near linear, which the transform makes it.
    e.tolerance = 5e-4f * std::abs(e.ga - e.gb);
  }
  // Regula falsi on the true field, every unfinished edge of the block evaluated in one batch per step. With `shade`
  // and the cubic estimate every evaluation is a whole sample: a vertex is where the step that met the tolerance
  // evaluated, so that sample is its shading (most edges stop at the first step, and the separate evaluation shading
  // would need costs more than the gradients of the steps that do not stop). From the line's root most edges take
  // two or three steps: there the one separate evaluation costs less.
  shade &= cubic;
  ws.samples.resize(edges.size());
  ws.shaded.assign(edges.size(), 0);
  ws.active.clear();
  for (uint32_t e = 0; e < edges.size(); ++e)
    if (edges[e].iterations > 0) ws.active.push_back(e);
  for (int it = 0; !ws.active.empty(); ++it) {
    ws.at.resize(ws.active.size());
    ws.values.resize(ws.active.size());
    for (size_t q = 0; q < ws.active.size(); ++q) {
      const EdgeRoot& e = edges[ws.active[q]];
      ws.at[q] = e.pa + e.t * (e.pb - e.pa);
    }
    if (shade) {
      ws.batch.resize(ws.active.size());
      field.samples(ws.at, ws.batch, ws.field);
      for (size_t q = 0; q < ws.active.size(); ++q) ws.values[q] = ws.batch[q].value;
    } else {
      field.values(ws.at, ws.values, ws.field);
    }
    for (float& v : ws.values) v = tf(v);  // one vectorised pass
    ws.stillActive.clear();
    for (size_t q = 0; q < ws.active.size(); ++q) {
      EdgeRoot& e = edges[ws.active[q]];
      const float gt = ws.values[q];
      if (std::abs(gt) <= e.tolerance) {
        if (shade) {
          ws.samples[ws.active[q]] = ws.batch[q];
          ws.shaded[ws.active[q]] = 1;
        }
        continue;
      }
      // Anderson-Bjorck: when the same end moves twice in a row, scale the stale end's value by
      // m = 1 - g(new) / g(old end), or halve it (Illinois) when m <= 0.
      if ((gt > 0.0f) == (e.ga > 0.0f)) {
        const float m = 1.0f - gt / e.ga;
        e.ta = e.t;
        e.ga = gt;
        if (e.side == -1) e.gb *= m > 0.0f ? m : 0.5f;
        e.side = -1;
      } else {
        const float m = 1.0f - gt / e.gb;
        e.tb = e.t;
        e.gb = gt;
        if (e.side == 1) e.ga *= m > 0.0f ? m : 0.5f;
        e.side = 1;
      }
      // Past its regula falsi steps an edge whose bracket is still wide (F not monotonic along it: a dip between
      // two blobs, a hard blend's clamped tail) is bisected until the bracket is narrow: the vertex is then on the
      // root the bracket holds, never between.
      const bool steps = it + 1 < e.iterations,
                 bisect = !steps && e.tb - e.ta > kRootBracket && it < e.iterations + kMaxBisections;
      e.t = bisect ? 0.5f * (e.ta + e.tb) : e.ta + (e.tb - e.ta) * e.ga / (e.ga - e.gb);
      if (steps || bisect) ws.stillActive.push_back(ws.active[q]);
    }
    ws.active.swap(ws.stillActive);
  }
}

void shadeEdgeVertices(const Field& field, const MarchingCubesOptions& options, BlockResult& r, WorkerScratch& ws) {
  const std::vector<EdgeRoot>& edges = ws.edges;
  r.positions.resize(3 * edges.size());
  for (size_t q = 0; q < edges.size(); ++q) {
    const glm::vec3 x = edges[q].pa + edges[q].t * (edges[q].pb - edges[q].pa);
    r.positions[3 * q] = x.x;
    r.positions[3 * q + 1] = x.y;
    r.positions[3 * q + 2] = x.z;
  }
  if (!options.computeNormals && !options.computeColors) return;
  // The vertices root finding left without a sample (it ran out of steps): one batched evaluation.
  ws.active.clear();
  ws.at.clear();
  for (uint32_t q = 0; q < edges.size(); ++q)
    if (!ws.shaded[q]) {
      ws.active.push_back(q);
      ws.at.push_back(edges[q].pa + edges[q].t * (edges[q].pb - edges[q].pa));
    }
  ws.batch.resize(ws.at.size());
  field.samples(ws.at, ws.batch, ws.field);
  for (size_t q = 0; q < ws.active.size(); ++q) ws.samples[ws.active[q]] = ws.batch[q];
  if (options.computeNormals) r.normals.resize(3 * edges.size());
  if (options.computeColors) r.colors.resize(3 * edges.size());
  for (size_t q = 0; q < edges.size(); ++q) {
    const FieldSample& fs = ws.samples[q];
    const float len = glm::length(fs.gradient);
    const glm::vec3 n = len > 0.0f ? -fs.gradient / len
                                   : glm::normalize(edges[q].pb - edges[q].pa) * (edges[q].ga >= 0.0f ? 1.0f : -1.0f);
    if (options.computeNormals) {
      r.normals[3 * q] = n.x;
      r.normals[3 * q + 1] = n.y;
      r.normals[3 * q + 2] = n.z;
    }
    if (options.computeColors) {
      r.colors[3 * q] = fs.color.x;
      r.colors[3 * q + 1] = fs.color.y;
      r.colors[3 * q + 2] = fs.color.z;
    }
  }
}

namespace {

// Passes 4a-4f for block b: whether it was sampled and has surface, its edge vertices.
void processBlock(const Field& field, const Grid& g, size_t b, const MarchingCubesOptions& options,
                  RootTransform tf, MarchingCubes::State& st, WorkerScratch& ws) {
  BlockResult& r = st.blocks[b];
  r.sampled = r.hasSurface = false;
  r.positions.clear();
  r.normals.clear();
  r.colors.clear();
  r.triangles.clear();
  r.moved.clear();
  if (cancelled(options)) return;
  if (!cullBlock(field, g, b, st.bins.of(b), st.forced[b] != 0, ws)) return;
  const glm::ivec3 block = g.blockCoords(b);
  if (!cullSubBlocks(field, g, block, st.forced[b] != 0, ws)) return;
  r.sampled = true;
  const BlockAxes axes(g, block);
  sampleBlock(field, g, block, axes, st.snaps, r, ws);
  r.hasSurface = classifyBlock(field.iso(), options.rootIterations, axes, r, ws);
  if (!r.hasSurface) return;
  findEdgeRoots(field, tf, options.computeNormals || options.computeColors, ws);
  shadeEdgeVertices(field, options, r, ws);
}

}  // namespace

// ---- 5. Number vertices --------------------------------------------------------------------------------------

uint32_t numberVertices(std::span<BlockResult> blocks, std::vector<uint32_t>& surfaceBlocks) {
  uint32_t total = 0;
  surfaceBlocks.clear();
  for (size_t b = 0; b < blocks.size(); ++b) {
    BlockResult& r = blocks[b];
    r.base = total;
    if (!r.hasSurface) continue;
    total += uint32_t(r.positions.size() / 3);
    surfaceBlocks.push_back(uint32_t(b));
  }
  return total;
}

// ---- 6. Triangulate ------------------------------------------------------------------------------------------

void triangulateBlock(const Field& field, const Grid& g, size_t b, const MarchingCubesOptions& options,
                      MarchingCubes::State& st, FieldScratch& scratch) {
  const CaseTable& table = caseTable();
  const float iso = field.iso();
  BlockResult& r = st.blocks[b];
  r.centrePositions.clear();
  r.centreNormals.clear();
  r.centreColors.clear();
  bool prepared = false;
  const EdgeResolver edges{table, g, st.blocks, r, g.blockCoords(b)};
  for (const uint32_t cell : r.cells) {
    const uint32_t index = cell & 0xFFFFu;
    const int i = int(index) % kBlock, j = int(index) / kBlock % kBlock, k = int(index) / (kBlock * kBlock);
    const int cs = int(cell >> 16);
    // A cell off the block's far faces has every edge owned by this block.
    const bool inside = i < kBlock - 1 && j < kBlock - 1 && k < kBlock - 1;
    const size_t entryIndex = table.entry(cs, joinedFaces(table, r, i, j, k, cs, iso));
    const auto& entry = table.entries[entryIndex];
    uint32_t centreIndex[2] = {0, 0};
    const int centres = table.centreCount[entryIndex];
    if (centres > 0)
      centreVertices(field, options, edges, cell, entryIndex, st.bins.of(b), prepared, scratch, r, centreIndex);
    // The cell's triangles written in place (one size check per cell, not per index).
    const int count = 3 * entry[0];
    const size_t first = r.triangles.size();
    r.triangles.resize(first + size_t(count));
    uint32_t* indices = r.triangles.data() + first;
    if (inside && centres == 0) {  // the common case: every index from this block's table offsets
      for (int v = 0; v < count; ++v) indices[v] = r.base + edges.interior(index, entry[size_t(1 + v)]);
      continue;
    }
    // Each cube edge resolved once (a cell's triangles name most of them twice or more).
    std::array<uint32_t, 12> resolved;
    resolved.fill(UINT32_MAX);
    for (int v = 0; v < count; ++v) {
      const int code = entry[size_t(1 + v)];
      if (code >= kCentre) {
        indices[v] = centreIndex[code - kCentre];
        continue;
      }
      uint32_t& global = resolved[size_t(code)];
      if (global == UINT32_MAX) {
        const auto [owner, local] = edges.of(index, inside, i, j, k, code);
        global = owner->base + local;
      }
      indices[v] = global;
    }
  }
}

// ---- 7. Gather -----------------------------------------------------------------------------------------------

void gatherMesh(uint32_t edgeVertices, int threads, MarchingCubes::State& st, Mesh& out) {
  const size_t blockCount = st.blocks.size();
  uint32_t centreBase = edgeVertices;
  st.centreBases.assign(blockCount, 0);
  for (size_t b = 0; b < blockCount; ++b) {
    st.centreBases[b] = centreBase;
    if (st.blocks[b].hasSurface) centreBase += uint32_t(st.blocks[b].centrePositions.size() / 3);
  }
  // Four independent streams, one task each: positions, normals, colours (edge vertices in block order, then the
  // loop-centre vertices), and the triangles.
  using Stream = std::pair<std::vector<float> BlockResult::*, std::vector<float> BlockResult::*>;
  const std::array<std::pair<std::vector<float>*, Stream>, 3> streams = {{
      {&out.positions, {&BlockResult::positions, &BlockResult::centrePositions}},
      {&out.normals, {&BlockResult::normals, &BlockResult::centreNormals}},
      {&out.colors, {&BlockResult::colors, &BlockResult::centreColors}},
  }};
  parallelForWorkers(4, threads, [&](size_t task, int) {
    if (task < 3) {
      auto& [to, from] = streams[task];
      if (std::ranges::any_of(st.blocks, [&](const BlockResult& r) { return !(r.*from.first).empty(); }))
        to->reserve(size_t(centreBase) * 3);  // (normals and colours may not be asked for)
      for (const BlockResult& r : st.blocks)
        if (r.hasSurface) to->insert(to->end(), (r.*from.first).begin(), (r.*from.first).end());
      for (const BlockResult& r : st.blocks)
        if (r.hasSurface) to->insert(to->end(), (r.*from.second).begin(), (r.*from.second).end());
      return;
    }
    for (size_t b = 0; b < blockCount; ++b) {
      const BlockResult& r = st.blocks[b];
      if (!r.hasSurface) continue;
      if (r.centrePositions.empty()) {  // no provisional indices
        out.indices.insert(out.indices.end(), r.triangles.begin(), r.triangles.end());
        continue;
      }
      const size_t at = out.indices.size();
      out.indices.resize(at + r.triangles.size());
      for (size_t q = 0; q < r.triangles.size(); ++q) {
        const uint32_t v = r.triangles[q];
        out.indices[at + q] = v & kProvisional ? st.centreBases[b] + (v & ~kProvisional) : v;
      }
    }
  });
}

}  // namespace imps::mc

// ---- The polygonizer -----------------------------------------------------------------------------------------

namespace imps {

std::expected<glm::ivec3, Diagnostics> planGrid(const Field& field, const MarchingCubesOptions& options) {
  const mc::GridPlan p = mc::planGridCells(field, options);
  if (!p.error.empty()) return std::unexpected(singleError({}, p.error));
  return glm::ivec3(p.cells);
}

MarchingCubes::MarchingCubes() : state_(std::make_unique<State>()) {}
MarchingCubes::~MarchingCubes() = default;

Mesh polygonize(const Field& field, const MarchingCubesOptions& options, MarchingCubesStats* stats) {
  MarchingCubes mc;
  Mesh mesh;
  mc.polygonize(field, options, mesh, stats);
  return mesh;
}

namespace {

using Clock = std::chrono::steady_clock;

// The phase timer, cancel flag and progress reports of one polygonize() call.
class Run {
 public:
  explicit Run(const MarchingCubesOptions& o) : options_(o), start_(Clock::now()), last_(start_) {}
  // Milliseconds since the previous lap.
  double lap() {
    const auto now = Clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }
  double totalMs() const { return std::chrono::duration<double, std::milli>(Clock::now() - start_).count(); }
  // Reports `fraction` (on the calling thread) and says whether to go on.
  bool proceed(float fraction) {
    if (options_.progress && !mc::cancelled(options_)) options_.progress(fraction);
    return !mc::cancelled(options_);
  }
  // body(w, worker) for w in [0, count) in parallel. With a progress callback, in slices, reporting the fractions
  // from `from` to `to` between them; stops after a slice once cancelled. Returns whether the pass completed.
  bool forEach(size_t count, float from, float to, const std::function<void(size_t, int)>& body) {
    const size_t slices = options_.progress ? std::min<size_t>(count, 16) : 1;
    for (size_t s = 0; s < slices; ++s) {
      const size_t begin = count * s / slices, end = count * (s + 1) / slices;
      parallelForWorkers(end - begin, options_.threads, [&](size_t w, int worker) { body(begin + w, worker); });
      if (!proceed(from + (to - from) * float(s + 1) / float(slices))) return false;
    }
    return slices > 0 || proceed(to);
  }

 private:
  const MarchingCubesOptions& options_;
  Clock::time_point start_, last_;
};

void fillStats(const mc::Grid& g, const MarchingCubes::State& st, const double (&phaseMs)[5], double totalMs,
               MarchingCubesStats& stats) {
  stats.setupMs = phaseMs[0];
  stats.thinFeaturesMs = phaseMs[1];
  stats.sampleMs = phaseMs[2];
  stats.triangulateMs = phaseMs[3];
  stats.gatherMs = phaseMs[4];
  stats.cells = g.cells;
  stats.cellSize = g.cell;
  stats.origin = g.origin;
  stats.blocks = g.blockCount();
  stats.blocksSampled = stats.blocksWithSurface = 0;
  for (const mc::BlockResult& r : st.blocks) {
    stats.blocksSampled += r.sampled;
    stats.blocksWithSurface += r.hasSurface;
  }
  stats.thinFeatureVertices = st.snaps.size();
  stats.milliseconds = totalMs;
  stats.cancelled = false;
}

}  // namespace

bool MarchingCubes::polygonize(const Field& field, const MarchingCubesOptions& options, Mesh& out,
                               MarchingCubesStats* stats) {
  Run run(options);
  double phaseMs[5] = {};
  out.clear();
  State& st = *state_;
  st.workers.resize(size_t(resolveThreads(options.threads)));
  auto stop = [&] {
    out.clear();
    if (stats) {
      *stats = MarchingCubesStats{};
      stats->cancelled = true;
    }
    return false;
  };
  if (!run.proceed(0.0f)) return stop();
  const mc::Grid g = mc::makeGrid(field, options);
  const size_t blockCount = g.blockCount();
  st.blocks.resize(blockCount);
  mc::binPrimitives(field, g, st.bins);
  phaseMs[0] = run.lap();
  st.snaps.clear();
  st.forced.assign(blockCount, 0);
  if (options.preserveThinFeatures && blockCount > 0) mc::findThinFeatures(field, g, st);
  phaseMs[1] = run.lap();
  if (!run.proceed(0.05f)) return stop();

  // Only blocks with candidates (or thin-feature vertices) can hold surface; spreading just those over the threads
  // balances the load (surface blocks cluster in index order).
  st.work.clear();
  for (size_t b = 0; b < blockCount; ++b) {
    if (st.bins.offsets[b + 1] > st.bins.offsets[b] || st.forced[b]) st.work.push_back(uint32_t(b));
    else st.blocks[b].sampled = st.blocks[b].hasSurface = false;
  }
  const mc::RootTransform transform(field);
  if (!run.forEach(st.work.size(), 0.05f, 0.8f, [&](size_t w, int worker) {
        mc::processBlock(field, g, st.work[w], options, transform, st, st.workers[size_t(worker)]);
      }))
    return stop();
  phaseMs[2] = run.lap();

  const uint32_t edgeVertices = mc::numberVertices(st.blocks, st.work);  // st.work: now the blocks with surface
  if (!run.forEach(st.work.size(), 0.8f, 0.95f, [&](size_t w, int worker) {
        if (!mc::cancelled(options))
          mc::triangulateBlock(field, g, st.work[w], options, st, st.workers[size_t(worker)].field);
      }))
    return stop();
  phaseMs[3] = run.lap();

  mc::gatherMesh(edgeVertices, options.threads, st, out);
  phaseMs[4] = run.lap();
  if (stats) fillStats(g, st, phaseMs, run.totalMs(), *stats);
  run.proceed(1.0f);
  return true;
}

}  // namespace imps
