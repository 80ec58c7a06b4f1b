// Marching Cubes over blocks of 8^3 cells: bin primitives to blocks, skip blocks by field bounds, sample, find edge
// vertices, triangulate from a face-consistent case table, concatenate in block order.
// Based on: Lorensen & Cline 1987; Nielson & Hamann 1991 (asymptotic decider).
#include "imps/marching_cubes.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "imps/check.h"
#include "imps/parallel.h"

namespace imps {
namespace {

constexpr int kBlock = 8;                          // cells per block side
constexpr int kBlockVerts = kBlock + 1;            // samples per block side
constexpr int kBlockSamples = kBlockVerts * kBlockVerts * kBlockVerts;
constexpr int kBlockEdges = 3 * kBlock * kBlock * kBlock;  // edges owned by a block (start vertex in [0, B)^3)
static_assert(kBlockEdges <= INT16_MAX, "a block's local vertex indices fit BlockResult::edgeVertex");
constexpr uint32_t kCellBits = (1u << kBlock) - 1;  // the cells (or owned edges) of one row, as bits
constexpr int kCentre = 12;                        // table code of a cell's first loop-centre vertex
constexpr uint32_t kProvisional = 0x80000000u;     // triangle index of a centre vertex before final numbering

inline int sampleIndex(int i, int j, int k) { return i + kBlockVerts * (j + kBlockVerts * k); }
inline int ownedEdgeIndex(int axis, int i, int j, int k) { return axis * kBlock * kBlock * kBlock + i + kBlock * (j + kBlock * k); }

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
  // across faces they form loops, each triangulated (triangulateLoop). Orientation: counter-clockwise seen from outside.
  // Returns the number of loop-centre vertices.
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

// ---- Grid and blocks -----------------------------------------------------------------------------------------

struct Grid {
  glm::vec3 origin{0.0f}, cell{1.0f};
  glm::ivec3 cells{0};   // multiple of kBlock
  glm::ivec3 blocks{0};
  glm::vec3 vertex(int i, int j, int k) const {
    return {origin.x + float(i) * cell.x, origin.y + float(j) * cell.y, origin.z + float(k) * cell.z};
  }
  glm::ivec3 verts() const { return cells + 1; }
  size_t blockIndex(int bx, int by, int bz) const { return size_t(bx) + size_t(blocks.x) * (size_t(by) + size_t(blocks.y) * size_t(bz)); }
  Box blockBox(int bx, int by, int bz) const {
    Box b;
    b.lo = vertex(bx * kBlock, by * kBlock, bz * kBlock);
    b.hi = vertex((bx + 1) * kBlock, (by + 1) * kBlock, (bz + 1) * kBlock);
    return b;
  }
  int64_t vertexKey(int i, int j, int k) const {
    return int64_t(i) + int64_t(verts().x) * (int64_t(j) + int64_t(verts().y) * int64_t(k));
  }
};

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

// A grid vertex moved onto a skeleton point.
struct Snap {
  int64_t key;
  glm::vec3 position;
  float value;
};

struct BlockResult {
  bool sampled = false, hasSurface = false;
  std::vector<float> samples;                   // kBlockSamples
  std::vector<int16_t> edgeVertex;              // kBlockEdges: local vertex index or -1 (16 bits: half the cache
                                                // lines for the triangles' lookups, often from the other core)
  std::vector<uint32_t> cells;                  // surface cells: index i + B (j + B k), case code << 16
  std::vector<float> positions, normals, colors;
  std::vector<uint32_t> triangles;              // global indices (centre vertices provisional until step 6)
  std::vector<float> centrePositions, centreNormals, centreColors;  // loop-centre vertices of this block
  std::vector<std::pair<int, glm::vec3>> moved;  // sample index -> moved position
  uint32_t base = 0;
};

// Root finding state of one crossing edge: the bracket [ta, tb] along pa -> pb with transformed values ga, gb.
struct EdgeRoot {
  glm::vec3 pa, pb;
  float ta = 0.0f, tb = 1.0f, ga = 0.0f, gb = 0.0f, t = 0.0f, tolerance = 0.0f;
  int side = 0, iterations = 0;
};

}  // namespace

struct MarchingCubes::State {
  std::vector<BlockResult> blocks;
  std::vector<uint32_t> binOffsets, binMembers;
  std::vector<uint32_t> work;  // the blocks a parallel phase visits
};

MarchingCubes::MarchingCubes() : state_(std::make_unique<State>()) {}
MarchingCubes::~MarchingCubes() = default;

std::expected<glm::ivec3, std::string> planGrid(const Field& field, const MarchingCubesOptions& options) {
  const GridPlan p = planGridCells(field, options);
  if (!p.error.empty()) return std::unexpected(p.error);
  return glm::ivec3(p.cells);
}

Mesh polygonize(const Field& field, const MarchingCubesOptions& options, MarchingCubesStats* stats) {
  MarchingCubes mc;
  Mesh mesh;
  mc.polygonize(field, options, mesh, stats);
  return mesh;
}

namespace {

// Skeleton points of primitive i at spacing <= step.
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
  const int n = std::max(1, int(std::ceil(glm::length(b - a) / step)));
  for (int s = 0; s <= n; ++s) out.push_back(a + (b - a) * (float(s) / float(n)));
}

std::vector<Snap> thinFeatureSnaps(const Field& field, const Grid& g) {
  std::vector<Snap> snaps;
  const float iso = field.iso();
  const float step = 0.5f * std::min({g.cell.x, g.cell.y, g.cell.z});
  std::vector<glm::vec3> points;
  FieldScratch scratch;
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
  // One snap per vertex: the deepest skeleton point wins.
  std::sort(snaps.begin(), snaps.end(), [](const Snap& a, const Snap& b) {
    return a.key != b.key ? a.key < b.key : a.value > b.value;
  });
  snaps.erase(std::unique(snaps.begin(), snaps.end(), [](const Snap& a, const Snap& b) { return a.key == b.key; }),
              snaps.end());
  return snaps;
}

}  // namespace

void MarchingCubes::polygonize(const Field& field, const MarchingCubesOptions& options, Mesh& out,
                               MarchingCubesStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  auto lap = [last = start]() mutable {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last).count();
    last = now;
    return ms;
  };
  double phaseMs[5] = {};
  out.clear();
  const CaseTable& table = caseTable();
  const Grid g = makeGrid(field, options);
  const float iso = field.iso();
  const size_t blockCount = size_t(g.blocks.x) * size_t(g.blocks.y) * size_t(g.blocks.z);
  State& st = *state_;
  st.blocks.resize(blockCount);

  // 1. Bin primitives into the blocks their support boxes overlap (grown by a cell for moved vertices).
  st.binOffsets.assign(blockCount + 1, 0);
  auto blockRange = [&](const Box& b, glm::ivec3& lo, glm::ivec3& hi) {
    lo = glm::clamp(glm::ivec3(glm::floor((b.lo - g.cell - g.origin) / (g.cell * float(kBlock)))), glm::ivec3(0), g.blocks - 1);
    hi = glm::clamp(glm::ivec3(glm::floor((b.hi + g.cell - g.origin) / (g.cell * float(kBlock)))), glm::ivec3(0), g.blocks - 1);
  };
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<uint32_t> cursor;
    if (pass == 1) {
      for (size_t b = 0; b < blockCount; ++b) st.binOffsets[b + 1] += st.binOffsets[b];
      st.binMembers.resize(st.binOffsets[blockCount]);
      cursor.assign(st.binOffsets.begin(), st.binOffsets.end() - 1);
    }
    for (size_t i = 0; i < field.size() && blockCount > 0; ++i) {
      glm::ivec3 lo, hi;
      blockRange(field.supportBox(i), lo, hi);
      for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
          for (int x = lo.x; x <= hi.x; ++x) {
            const size_t b = g.blockIndex(x, y, z);
            if (pass == 0) ++st.binOffsets[b + 1];
            else st.binMembers[cursor[b]++] = uint32_t(i);
          }
    }
  }

  phaseMs[0] = lap();
  // 2. Thin features: grid vertices moved onto skeleton points. Blocks holding one must be sampled.
  const std::vector<Snap> snaps = options.preserveThinFeatures && blockCount > 0 ? thinFeatureSnaps(field, g)
                                                                                 : std::vector<Snap>{};
  std::vector<uint8_t> forced(blockCount, 0);
  for (const Snap& s : snaps) {
    const int64_t vx = s.key % g.verts().x, vy = (s.key / g.verts().x) % g.verts().y, vz = s.key / (int64_t(g.verts().x) * g.verts().y);
    for (int dz = -1; dz <= 0; ++dz)
      for (int dy = -1; dy <= 0; ++dy)
        for (int dx = -1; dx <= 0; ++dx) {
          // The block whose closed vertex range holds (vx, vy, vz): floor(v / B) and, on a block boundary, the one below.
          const int64_t bx = (vx + dx * (vx % kBlock == 0 ? 1 : 0)) / kBlock;
          const int64_t by = (vy + dy * (vy % kBlock == 0 ? 1 : 0)) / kBlock;
          const int64_t bz = (vz + dz * (vz % kBlock == 0 ? 1 : 0)) / kBlock;
          if (bx >= 0 && by >= 0 && bz >= 0 && bx < g.blocks.x && by < g.blocks.y && bz < g.blocks.z)
            forced[g.blockIndex(int(bx), int(by), int(bz))] = 1;
        }
  }

  phaseMs[1] = lap();
  // 3. Per block: bound test, samples, owned edge vertices.
  const int threads = options.threads;
  const bool logSpace = field.blend().kind == BlendKind::Exponential;
  const float logIso = lnPositive(iso);
  // Root finding runs on a distance-like g for the exponential blend, so that the first interpolation is already
  // near the root. One term is F = exp(B (d - 1)) with d the squared normalised distance to the skeleton, so
  // d = 1 + ln F / B and g = (ln F - ln iso) / (sqrt(d_iso) + sqrt(d)) = B (sqrt(d) - sqrt(d_iso)) is linear in the
  // distance (ln F alone is quadratic in it). Written as a quotient, g has exactly the sign of ln F - ln iso and
  // its full precision near the root; the floor only guards the denominator where both roots are 0 (F and iso both
  // at least exp(-B)).
  // F is exactly 0 beyond every support; clamping at the smallest non-zero term keeps ln F finite.
  const float invB = logSpace ? 1.0f / field.blend().defaultParam : 0.0f;
  const float rootIso = std::sqrt(std::max(1.0f + logIso * invB, 0.0f));
  // (Captured by value: a reference could alias the values it transforms, which would keep its loops scalar.)
  auto transform = [logSpace, logIso, invB, rootIso, iso](float v) {
    if (!logSpace) return v - iso;
    const float lnF = lnPositive(std::max(v, kExponentialCutoff));
    return (lnF - logIso) / std::max(rootIso + std::sqrt(std::max(1.0f + lnF * invB, 0.0f)), 1e-6f);
  };
  // Only blocks with candidates (or thin-feature vertices) can hold surface; spreading just those over the threads
  // balances the load (surface blocks cluster in index order).
  std::vector<uint32_t>& work = st.work;
  work.clear();
  for (size_t b = 0; b < blockCount; ++b) {
    if (st.binOffsets[b + 1] > st.binOffsets[b] || forced[b]) work.push_back(uint32_t(b));
    else st.blocks[b].sampled = st.blocks[b].hasSurface = false;
  }
  parallelFor(work.size(), threads, [&](size_t w) {
    thread_local FieldScratch scratch;
    const size_t b = work[w];
    BlockResult& r = st.blocks[b];
    r.sampled = r.hasSurface = false;
    r.positions.clear();
    r.normals.clear();
    r.colors.clear();
    r.triangles.clear();
    r.moved.clear();
    const int bx = int(b % size_t(g.blocks.x)), by = int((b / size_t(g.blocks.x)) % size_t(g.blocks.y)),
              bz = int(b / (size_t(g.blocks.x) * size_t(g.blocks.y)));
    const Box box = g.blockBox(bx, by, bz);
    const std::span<const uint32_t> cand(st.binMembers.data() + st.binOffsets[b], st.binOffsets[b + 1] - st.binOffsets[b]);
    if (cand.empty() && !forced[b]) return;
    if (forced[b]) {
      field.prepare(cand, scratch);
    } else {
      // Binning used support *boxes*; drop the candidates whose support cannot reach this block at all. Their terms
      // are exactly zero here, so every value stays bit-identical (x + 0 = x) with fewer primitives to evaluate.
      thread_local std::vector<uint32_t> reaching;
      thread_local std::vector<float> reachingDistances;  // each reaching candidate's minDistance() to the block
      reaching.clear();
      reachingDistances.clear();
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
        reaching.push_back(i);
        reachingDistances.push_back(d);
        largestTermsSum += field.blend().term(d, field.param(i));
      }
      if (reaching.empty()) return;
      if (field.blend().additive() && largestTermsSum < iso * (1.0f - 1e-3f)) return;
      field.prepare(reaching, scratch);
      if (field.upperBound(reachingDistances, scratch) < iso * (1.0f - 1e-3f)) return;
      if (field.lowerBound(box, scratch) > iso * (1.0f + 1e-3f)) return;
    }
    r.sampled = true;
    std::array<float, kBlockVerts> xs, ys, zs;  // the samples' coordinates along each axis (g.vertex()'s)
    for (int v = 0; v < kBlockVerts; ++v) {
      const glm::vec3 p = g.vertex(bx * kBlock + v, by * kBlock + v, bz * kBlock + v);
      xs[size_t(v)] = p.x;
      ys[size_t(v)] = p.y;
      zs[size_t(v)] = p.z;
    }
    r.samples.resize(kBlockSamples);
    field.latticeValues(xs, ys, zs, r.samples, scratch);
    if (!snaps.empty()) {
      for (int k = 0; k < kBlockVerts; ++k)
        for (int j = 0; j < kBlockVerts; ++j) {
          const int64_t rowKey = g.vertexKey(bx * kBlock, by * kBlock + j, bz * kBlock + k);
          auto it = std::lower_bound(snaps.begin(), snaps.end(), rowKey, [](const Snap& s, int64_t key) { return s.key < key; });
          for (; it != snaps.end() && it->key <= rowKey + kBlock; ++it) {
            const int s = sampleIndex(int(it->key - rowKey), j, k);
            r.samples[s] = it->value;
            r.moved.emplace_back(s, it->position);
          }
        }
    }

    // Inside bits, one 9-bit mask per row of samples: rows[j + 9k] bit i is sample (i, j, k).
    // The comparisons run as one vectorised pass into bytes (0 or 1); a row's first eight bytes, read as a
    // little-endian word, become bits by one multiplication: byte i (bit 8i) times 2^(56 - 7i) lands on bit 56 + i,
    // and no two products share a bit, so nothing carries.
    static_assert(std::endian::native == std::endian::little);
    std::array<uint8_t, kBlockSamples + 7> inside{};  // padded so the last row's 8-byte read stays inside
    for (int s = 0; s < kBlockSamples; ++s) inside[size_t(s)] = r.samples[size_t(s)] >= iso;
    std::array<uint32_t, kBlockVerts * kBlockVerts> rows;
    for (int row = 0; row < kBlockVerts * kBlockVerts; ++row) {
      uint64_t bytes;
      std::memcpy(&bytes, inside.data() + row * kBlockVerts, sizeof bytes);
      rows[size_t(row)] =
          uint32_t((bytes * 0x0102040810204080ull) >> 56) | uint32_t(inside[size_t(row * kBlockVerts + 8)]) << 8;
    }
    auto rowMask = [&](int j, int k) { return rows[size_t(j + kBlockVerts * k)]; };
    // Sample (i, j, k)'s position, and whether it was moved onto a skeleton point.
    auto samplePosition = [&](int i, int j, int k, bool& moved) -> glm::vec3 {
      for (const auto& [s, p] : r.moved)
        if (s == sampleIndex(i, j, k)) {
          moved = true;
          return p;
        }
      return {xs[size_t(i)], ys[size_t(j)], zs[size_t(k)]};
    };

    // Surface cells (case code and cell index) and the crossing edges this block owns, in the order that numbers
    // their vertices: cells (i, j, k) ascending with i fastest, axes x, y, z within a cell.
    thread_local std::vector<EdgeRoot> edges;
    thread_local std::vector<float> ends;  // F at each edge's two ends, then their transformed values
    edges.clear();
    ends.clear();
    r.cells.clear();
    r.edgeVertex.assign(kBlockEdges, -1);
    for (int k = 0; k < kBlock; ++k)
      for (int j = 0; j < kBlock; ++j) {
        const uint32_t r00 = rowMask(j, k), r10 = rowMask(j + 1, k), r01 = rowMask(j, k + 1), r11 = rowMask(j + 1, k + 1);
        const uint32_t anyIn = r00 | r10 | r01 | r11, allIn = r00 & r10 & r01 & r11;
        for (uint32_t mixed = (anyIn | anyIn >> 1) & ~(allIn & allIn >> 1) & kCellBits; mixed != 0; mixed &= mixed - 1) {
          const int i = std::countr_zero(mixed);
          const uint32_t cs = ((r00 >> i) & 3u) | ((r10 >> i) & 3u) << 2 | ((r01 >> i) & 3u) << 4 | ((r11 >> i) & 3u) << 6;
          r.cells.push_back(uint32_t(i + kBlock * (j + kBlock * k)) | cs << 16);
        }
        const std::array<uint32_t, 3> crossing = {(r00 ^ r00 >> 1) & kCellBits, (r00 ^ r10) & kCellBits, (r00 ^ r01) & kCellBits};
        for (uint32_t any = crossing[0] | crossing[1] | crossing[2]; any != 0; any &= any - 1) {
          const int i = std::countr_zero(any);
          const int s0 = sampleIndex(i, j, k);
          for (int axis = 0; axis < 3; ++axis) {
            if (!((crossing[size_t(axis)] >> i) & 1u)) continue;
            const int s1 = s0 + (axis == 0 ? 1 : axis == 1 ? kBlockVerts : kBlockVerts * kBlockVerts);
            const float f0 = r.samples[s0], f1 = r.samples[s1];
            r.edgeVertex[ownedEdgeIndex(axis, i, j, k)] = int16_t(edges.size());
            EdgeRoot e;
            bool moved = false;
            e.pa = samplePosition(i, j, k, moved);
            e.pb = samplePosition(i + (axis == 0), j + (axis == 1), k + (axis == 2), moved);
            ends.push_back(f0);
            ends.push_back(f1);
            // Edges from a vertex moved onto a thin limb span a much steeper field: give them more steps.
            e.iterations = moved ? std::max(options.rootIterations, 10) : options.rootIterations;
            edges.push_back(e);
          }
        }
      }
    r.hasSurface = !r.cells.empty();
    if (!r.hasSurface) return;

    // The ends' transformed values in one vectorised pass, then each edge's first interpolation.
    for (float& v : ends) v = transform(v);
    for (size_t q = 0; q < edges.size(); ++q) {
      EdgeRoot& e = edges[q];
      e.ga = ends[2 * q];
      e.gb = ends[2 * q + 1];
      e.t = e.ga / (e.ga - e.gb);
      // Scale-free stopping rule: |g| below 5e-4 of its change along the edge puts the vertex within about
      // 5e-4 of an edge of the root where g is near linear, which the transform makes it.
      e.tolerance = 5e-4f * std::abs(e.ga - e.gb);
    }

    // Regula falsi root finding on the true field, every unfinished edge of the block evaluated in one batch per step.
    thread_local std::vector<uint32_t> active, stillActive;
    thread_local std::vector<glm::vec3> at;
    thread_local std::vector<float> values;
    active.clear();
    for (uint32_t e = 0; e < edges.size(); ++e)
      if (edges[e].iterations > 0) active.push_back(e);
    for (int it = 0; !active.empty(); ++it) {
      at.resize(active.size());
      values.resize(active.size());
      for (size_t q = 0; q < active.size(); ++q) {
        const EdgeRoot& e = edges[active[q]];
        at[q] = e.pa + e.t * (e.pb - e.pa);
      }
      field.values(at, values, scratch);
      for (float& v : values) v = transform(v);  // one vectorised pass
      stillActive.clear();
      for (size_t q = 0; q < active.size(); ++q) {
        EdgeRoot& e = edges[active[q]];
        const float gt = values[q];
        if (std::abs(gt) <= e.tolerance) continue;
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
        e.t = e.ta + (e.tb - e.ta) * e.ga / (e.ga - e.gb);
        if (it + 1 < e.iterations) stillActive.push_back(active[q]);
      }
      active.swap(stillActive);
    }

    // Vertices, with normals and colours from one batched evaluation.
    at.resize(edges.size());
    for (size_t q = 0; q < edges.size(); ++q) at[q] = edges[q].pa + edges[q].t * (edges[q].pb - edges[q].pa);
    r.positions.resize(3 * edges.size());
    for (size_t q = 0; q < edges.size(); ++q) {
      r.positions[3 * q] = at[q].x;
      r.positions[3 * q + 1] = at[q].y;
      r.positions[3 * q + 2] = at[q].z;
    }
    if (options.computeNormals || options.computeColors) {
      thread_local std::vector<FieldSample> fs;
      fs.resize(edges.size());
      field.samples(at, fs, scratch);
      if (options.computeNormals) r.normals.resize(3 * edges.size());
      if (options.computeColors) r.colors.resize(3 * edges.size());
      for (size_t q = 0; q < edges.size(); ++q) {
        const float len = glm::length(fs[q].gradient);
        const glm::vec3 n = len > 0.0f ? -fs[q].gradient / len
                                       : glm::normalize(edges[q].pb - edges[q].pa) * (edges[q].ga >= 0.0f ? 1.0f : -1.0f);
        if (options.computeNormals) {
          r.normals[3 * q] = n.x;
          r.normals[3 * q + 1] = n.y;
          r.normals[3 * q + 2] = n.z;
        }
        if (options.computeColors) {
          r.colors[3 * q] = fs[q].color.x;
          r.colors[3 * q + 1] = fs[q].color.y;
          r.colors[3 * q + 2] = fs[q].color.z;
        }
      }
    }
  }, 1);

  phaseMs[2] = lap();
  // 4. Global vertex numbering in block order.
  uint32_t total = 0;
  work.clear();  // now: the blocks with surface
  for (size_t b = 0; b < blockCount; ++b) {
    BlockResult& r = st.blocks[b];
    r.base = total;
    if (!r.hasSurface) continue;
    total += uint32_t(r.positions.size() / 3);
    work.push_back(uint32_t(b));
  }

  // 5. Triangles: each cell's case, ambiguous faces decided from their four samples, edges mapped to the owning
  // block's vertex.
  parallelFor(work.size(), threads, [&](size_t w) {
    const size_t b = work[w];
    BlockResult& r = st.blocks[b];
    const int bx = int(b % size_t(g.blocks.x)), by = int((b / size_t(g.blocks.x)) % size_t(g.blocks.y)),
              bz = int(b / (size_t(g.blocks.x) * size_t(g.blocks.y)));
    r.centrePositions.clear();
    r.centreNormals.clear();
    r.centreColors.clear();
    thread_local FieldScratch scratch;
    bool prepared = false;
    // The block owning cell (i, j, k)'s cube edge e, and the vertex's index in it.
    struct EdgeRef {
      const BlockResult* owner;
      uint32_t local;
    };
    auto edgeVertex = [&](int i, int j, int k, int e) -> EdgeRef {
      const int corner = table.edgeStartCorner[size_t(e)], axis = e / 4;
      const int vi = i + (corner & 1), vj = j + ((corner >> 1) & 1), vk = k + ((corner >> 2) & 1);
      const int ox = vi / kBlock, oy = vj / kBlock, oz = vk / kBlock;  // 1 on the far faces: the next block owns it
      const BlockResult& owner = (ox | oy | oz) ? st.blocks[g.blockIndex(bx + ox, by + oy, bz + oz)] : r;
      IMPS_CHECK(owner.hasSurface);
      const int32_t local = owner.edgeVertex[ownedEdgeIndex(axis, vi - ox * kBlock, vj - oy * kBlock, vk - oz * kBlock)];
      IMPS_CHECK(local >= 0);
      return {&owner, uint32_t(local)};
    };
    for (const uint32_t cell : r.cells) {
      const int i = int(cell & 0xFFFFu) % kBlock, j = int(cell & 0xFFFFu) / kBlock % kBlock,
                k = int(cell & 0xFFFFu) / (kBlock * kBlock);
      const int cs = int(cell >> 16);
      // A cell off the block's far faces has every edge owned by this block: a table offset finds its vertex.
      const bool interior = i < kBlock - 1 && j < kBlock - 1 && k < kBlock - 1;
      auto ref = [&](int e) -> EdgeRef {
        if (!interior) return edgeVertex(i, j, k, e);
        const int32_t local = r.edgeVertex[size_t(int(cell & 0xFFFFu) + table.ownedEdgeOffset[size_t(e)])];
        IMPS_CHECK(local >= 0);
        return {&r, uint32_t(local)};
      };
      int joined = 0;
      const uint8_t ambiguous = table.ambiguousFaces[cs];
      if (ambiguous) {
        float f[8];
        for (int c = 0; c < 8; ++c) f[c] = r.samples[sampleIndex(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))];
        for (int face = 0; face < 6; ++face) {
          if (!((ambiguous >> face) & 1)) continue;
          const auto& cc = table.faces[face].canonical;
          const float a = f[cc[0]] - iso, bb = f[cc[1]] - iso, c2 = f[cc[2]] - iso, d = f[cc[3]] - iso;
          // Bilinear saddle value: inside corners are joined when it is inside.
          const float denom = a + c2 - bb - d;
          const float saddle = denom != 0.0f ? (a * c2 - bb * d) / denom : 0.0f;
          if (saddle >= 0.0f) joined |= 1 << face;
        }
      }
      const size_t entryIndex = table.entry(cs, joined);
      const auto& entry = table.entries[entryIndex];
      // Loop-centre vertices: the mean of the loop's vertices, then Newton steps onto the surface.
      uint32_t centreIndex[2] = {0, 0};
      const int centres = table.centreCount[entryIndex];
      for (int centre = 0; centre < centres; ++centre) {
        glm::vec3 sum(0.0f);
        int count = 0;
        for (int t = 0; t < entry[0]; ++t) {
          if (entry[1 + 3 * t] != kCentre + centre) continue;
          const auto [owner, local] = ref(entry[2 + 3 * t]);
          sum += glm::vec3(owner->positions[3 * local], owner->positions[3 * local + 1], owner->positions[3 * local + 2]);
          ++count;
        }
        if (count == 0) break;
        if (!prepared) {
          field.prepare(std::span<const uint32_t>(st.binMembers.data() + st.binOffsets[b],
                                                  st.binOffsets[b + 1] - st.binOffsets[b]), scratch);
          prepared = true;
        }
        glm::vec3 x = sum / float(count);
        FieldSample fs = field.sample(x, scratch);
        for (int step = 0; step < 3; ++step) {
          const float g2 = glm::dot(fs.gradient, fs.gradient);
          if (g2 <= 0.0f) break;
          x -= (fs.value - iso) / g2 * fs.gradient;
          fs = field.sample(x, scratch);
        }
        centreIndex[centre] = kProvisional | uint32_t(r.centrePositions.size() / 3);
        r.centrePositions.insert(r.centrePositions.end(), {x.x, x.y, x.z});
        const float len = glm::length(fs.gradient);
        const glm::vec3 n = len > 0.0f ? -fs.gradient / len : glm::vec3(0, 0, 1);
        if (options.computeNormals) r.centreNormals.insert(r.centreNormals.end(), {n.x, n.y, n.z});
        if (options.computeColors) r.centreColors.insert(r.centreColors.end(), {fs.color.x, fs.color.y, fs.color.z});
      }
      // The cell's triangles written in place (one size check per cell, not per index).
      const int count = 3 * entry[0];
      const size_t first = r.triangles.size();
      r.triangles.resize(first + size_t(count));
      uint32_t* indices = r.triangles.data() + first;
      if (interior && centres == 0) {  // the common case: every index from this block's table offsets
        for (int v = 0; v < count; ++v) {
          const int32_t local = r.edgeVertex[size_t(int(cell & 0xFFFFu) + table.ownedEdgeOffset[entry[size_t(1 + v)]])];
          IMPS_CHECK(local >= 0);
          indices[v] = r.base + uint32_t(local);
        }
        continue;
      }
      for (int v = 0; v < count; ++v) {
        const int code = entry[size_t(1 + v)];
        if (code >= kCentre) {
          indices[v] = centreIndex[code - kCentre];
        } else {
          const auto [owner, local] = ref(code);
          indices[v] = owner->base + local;
        }
      }
    }
  }, 1);

  phaseMs[3] = lap();
  // 6. Concatenate in block order: edge vertices, then loop-centre vertices (numbered after all edge vertices).
  uint32_t centreBase = total;
  std::vector<uint32_t> centreBases(blockCount, 0);
  for (size_t b = 0; b < blockCount; ++b) {
    centreBases[b] = centreBase;
    if (st.blocks[b].hasSurface) centreBase += uint32_t(st.blocks[b].centrePositions.size() / 3);
  }
  out.positions.reserve(size_t(centreBase) * 3);
  for (const BlockResult& r : st.blocks) {
    if (!r.hasSurface) continue;
    out.positions.insert(out.positions.end(), r.positions.begin(), r.positions.end());
    out.normals.insert(out.normals.end(), r.normals.begin(), r.normals.end());
    out.colors.insert(out.colors.end(), r.colors.begin(), r.colors.end());
  }
  for (size_t b = 0; b < blockCount; ++b) {
    const BlockResult& r = st.blocks[b];
    if (!r.hasSurface) continue;
    out.positions.insert(out.positions.end(), r.centrePositions.begin(), r.centrePositions.end());
    out.normals.insert(out.normals.end(), r.centreNormals.begin(), r.centreNormals.end());
    out.colors.insert(out.colors.end(), r.centreColors.begin(), r.centreColors.end());
    if (r.centrePositions.empty()) {  // no provisional indices
      out.indices.insert(out.indices.end(), r.triangles.begin(), r.triangles.end());
      continue;
    }
    const size_t at = out.indices.size();
    out.indices.resize(at + r.triangles.size());
    for (size_t q = 0; q < r.triangles.size(); ++q) {
      const uint32_t v = r.triangles[q];
      out.indices[at + q] = v & kProvisional ? centreBases[b] + (v & ~kProvisional) : v;
    }
  }

  phaseMs[4] = lap();
  if (stats) {
    stats->setupMs = phaseMs[0];
    stats->thinFeaturesMs = phaseMs[1];
    stats->sampleMs = phaseMs[2];
    stats->triangulateMs = phaseMs[3];
    stats->gatherMs = phaseMs[4];
    stats->cells = g.cells;
    stats->cellSize = g.cell;
    stats->origin = g.origin;
    stats->blocks = blockCount;
    stats->blocksSampled = stats->blocksWithSurface = 0;
    for (const BlockResult& r : st.blocks) {
      stats->blocksSampled += r.sampled;
      stats->blocksWithSurface += r.hasSurface;
    }
    stats->thinFeatureVertices = snaps.size();
    stats->milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
}

}  // namespace imps
