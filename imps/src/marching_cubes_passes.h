// SPDX-License-Identifier: MIT
// The passes of MarchingCubes::polygonize, in the order they run, with the buffers they share. Internal (not
// installed): marching_cubes.cpp and the passes' unit tests (tests/imps/marching_cubes_passes_test.cpp) include it.
//
// A polygonize() call, in the spirit of OpenVDB's VolumeToMesh:
//   1. makeGrid         the grid: the surface bounds plus a cell of margin, whole blocks of kBlock^3 cells;
//   2. binPrimitives    every primitive into the blocks its support box overlaps (CSR lists, ascending);
//   3. findThinFeatures grid vertices moved onto skeleton points, and the blocks that must be sampled for them;
//   4. per block, in parallel (sampleBlocks):
//      a. cullBlock          conservative field bounds: blocks entirely inside or outside are never sampled;
//      b. cullSubBlocks      the same bounds on the block's 2^3 sub-blocks: the rows of samples that need the field;
//      c. sampleBlock        the field samples on those rows (moved vertices overwritten), the others' side known;
//      d. classifyBlock      surface cells (case codes) and the crossing edges the block owns, numbered locally;
//      e. findEdgeRoots      each crossing edge's vertex by Anderson-Bjorck regula falsi on the true field, each
//                            step a whole sample (the last one the vertex's normal and colour);
//      f. shadeEdgeVertices  positions, normals and colours of those vertices;
//   5. numberVertices   global vertex numbers: each surface block's first vertex, in block order;
//   6. triangulateBlock per surface block, in parallel: each cell's triangles from the face-consistent case table,
//                       ambiguous faces decided by the asymptotic decider, loop-centre vertices where needed;
//   7. gatherMesh       concatenation in block order (edge vertices, then loop-centre vertices), its four streams
//                       (positions, normals, colours, triangles) in parallel.
// Every pass writes only its own block's results (or runs serially), so 1 and N threads give the identical mesh.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "imps/field.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"

namespace imps::mc {

inline constexpr int kBlock = 8;                          // cells per block side
inline constexpr int kBlockVerts = kBlock + 1;            // samples per block side
inline constexpr int kBlockSamples = kBlockVerts * kBlockVerts * kBlockVerts;
inline constexpr int kBlockEdges = 3 * kBlock * kBlock * kBlock;  // edges owned by a block (start vertex in [0, B)^3)
static_assert(kBlockEdges <= INT16_MAX, "a block's local vertex indices fit BlockResult::edgeVertex");
inline constexpr uint32_t kCellBits = (1u << kBlock) - 1;  // the cells (or owned edges) of one row, as bits
inline constexpr int kCentre = 12;                        // table code of a cell's first loop-centre vertex
inline constexpr uint32_t kProvisional = 0x80000000u;     // triangle index of a centre vertex before gatherMesh
inline constexpr int kSubBlock = kBlock / 2;              // cells per sub-block side (cullSubBlocks)
inline constexpr int kSubBlocks = 8;                      // sub-blocks per block
inline constexpr size_t kSubBlockMinCandidates = 4;       // fewer candidates: every sub-block is sampled
inline constexpr float kRootBracket = 5e-4f;  // findEdgeRoots: bisect past the steps while a bracket is wider (edges)
inline constexpr int kMaxBisections = 16;     // findEdgeRoots: at most this many (2^-11 is already below kRootBracket)
enum SubBlockClass : uint8_t { kLive, kOutside, kInside };  // cullSubBlocks' verdicts

inline int sampleIndex(int i, int j, int k) { return i + kBlockVerts * (j + kBlockVerts * k); }
inline int ownedEdgeIndex(int axis, int i, int j, int k) {
  return axis * kBlock * kBlock * kBlock + i + kBlock * (j + kBlock * k);
}

struct Grid {
  glm::vec3 origin{0.0f}, cell{1.0f};
  glm::ivec3 cells{0};   // multiple of kBlock
  glm::ivec3 blocks{0};
  glm::vec3 vertex(int i, int j, int k) const {
    return {origin.x + float(i) * cell.x, origin.y + float(j) * cell.y, origin.z + float(k) * cell.z};
  }
  glm::ivec3 verts() const { return cells + 1; }
  size_t blockCount() const { return size_t(blocks.x) * size_t(blocks.y) * size_t(blocks.z); }
  size_t blockIndex(int bx, int by, int bz) const {
    return size_t(bx) + size_t(blocks.x) * (size_t(by) + size_t(blocks.y) * size_t(bz));
  }
  glm::ivec3 blockCoords(size_t b) const {
    return {int(b % size_t(blocks.x)), int((b / size_t(blocks.x)) % size_t(blocks.y)),
            int(b / (size_t(blocks.x) * size_t(blocks.y)))};
  }
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

// A grid vertex moved onto a skeleton point.
struct Snap {
  int64_t key;  // Grid::vertexKey
  glm::vec3 position;
  float value;  // F at position
};

// One block's results, kept between calls (their buffers are reused).
struct BlockResult {
  bool sampled = false, hasSurface = false;
  std::vector<float> samples;                   // kBlockSamples
  std::vector<int16_t> edgeVertex;              // kBlockEdges: local vertex index or -1 (16 bits: half the cache
                                                // lines for the triangles' lookups, often from the other core)
  std::vector<uint32_t> cells;                  // surface cells: index i + B (j + B k), case code << 16
  std::vector<float> positions, normals, colors;
  std::vector<uint32_t> triangles;              // global indices (centre vertices kProvisional until gatherMesh)
  std::vector<float> centrePositions, centreNormals, centreColors;  // loop-centre vertices of this block
  std::vector<std::pair<int, glm::vec3>> moved;  // sample index -> moved position
  uint32_t base = 0;                            // global number of the first edge vertex (numberVertices)
};

// Root finding state of one crossing edge: the bracket [ta, tb] along pa -> pb with transformed values ga, gb.
struct EdgeRoot {
  glm::vec3 pa, pb;
  float ta = 0.0f, tb = 1.0f, ga = 0.0f, gb = 0.0f, t = 0.0f, tolerance = 0.0f;
  int side = 0, iterations = 0;
};

// The value root finding runs on: F - iso, or for the exponential blend a distance-like transform of ln F that is
// near linear along an edge (marching_cubes.cpp says why). Same sign as F - iso.
struct RootTransform {
  bool logSpace = false;
  float iso = 1.0f, logIso = 0.0f, invB = 0.0f, rootIso = 0.0f;
  explicit RootTransform(const Field& field);
  float operator()(float v) const;  // inline in marching_cubes.cpp, so that loops over it vectorise
};

// The samples' coordinates along each axis of one block (Grid::vertex's).
struct BlockAxes {
  std::array<float, kBlockVerts> xs, ys, zs;
  BlockAxes(const Grid& g, glm::ivec3 block);
};

// Scratch memory of one worker thread, owned by the polygonizer (one per worker, reused by every call).
struct WorkerScratch {
  FieldScratch field;
  std::vector<uint32_t> reaching;        // cullBlock: the candidates whose support reaches the block
  std::vector<float> reachingDistances;  // and their minDistance() to it (then, for the lower bound, maxDistance())
  std::array<uint8_t, kSubBlocks> subBlocks{};  // cullSubBlocks -> sampleBlock: each sub-block's SubBlockClass
  std::array<uint8_t, kBlockVerts * kBlockVerts> rows{};  // cullSubBlocks -> sampleBlock: rows (j + 9 k) to sample
  std::vector<EdgeRoot> edges;           // classifyBlock -> findEdgeRoots -> shadeEdgeVertices
  std::vector<float> ends;               // F at each edge's two ends, then their transformed values
  std::vector<float> outer;              // F just outside each edge's ends (-1: unknown), then transformed (NaN)
  std::vector<uint32_t> active, stillActive;
  std::vector<glm::vec3> at;
  std::vector<float> values;
  std::vector<FieldSample> samples;  // findEdgeRoots -> shadeEdgeVertices: each edge vertex's sample
  std::vector<uint8_t> shaded;       // findEdgeRoots -> shadeEdgeVertices: whether samples[e] is the vertex's
  std::vector<FieldSample> batch;    // one batched evaluation
};

// Primitives binned to blocks (CSR): block b's candidates are members[offsets[b] .. offsets[b + 1]), ascending.
struct Bins {
  std::vector<uint32_t> offsets, members, cursor;
  std::span<const uint32_t> of(size_t b) const { return {members.data() + offsets[b], offsets[b + 1] - offsets[b]}; }
};

}  // namespace imps::mc

namespace imps {

struct MarchingCubes::State {
  std::vector<mc::BlockResult> blocks;
  mc::Bins bins;
  std::vector<mc::Snap> snaps;
  std::vector<uint8_t> forced;        // per block: holds a moved vertex, so it is sampled whatever its bounds
  std::vector<uint32_t> work;         // the blocks a parallel pass visits
  std::vector<uint32_t> centreBases;  // per block: global number of its first loop-centre vertex
  std::vector<glm::vec3> skeleton;    // findThinFeatures: one primitive's skeleton points
  std::vector<mc::WorkerScratch> workers;
};

}  // namespace imps

namespace imps::mc {

// 1. The grid for field's surface bounds and the options' resolution. An empty surface gives no blocks.
Grid makeGrid(const Field& field, const MarchingCubesOptions& options);

// 2. Bins every primitive into the blocks its support box (grown by a cell, for moved vertices) overlaps.
// Output: bins.offsets has blockCount + 1 entries; each block's members ascend. Reuses bins' buffers.
void binPrimitives(const Field& field, const Grid& g, Bins& bins);

// 3. Thin features: the grid vertices moved onto skeleton points (one per vertex, the deepest point wins; sorted by
// key), and `forced` (one byte per block): 1 for every block whose closed vertex range holds one of them.
// Uses st.skeleton and worker 0's field scratch.
void findThinFeatures(const Field& field, const Grid& g, MarchingCubes::State& st);

// 4a. Whether block b may hold surface: false when no candidate's support reaches it or its conservative field
// bounds lie entirely below or above iso (1e-3 relative margin). On true, ws.field is prepared for sampling it.
bool cullBlock(const Field& field, const Grid& g, size_t b, std::span<const uint32_t> candidates, bool forced,
               WorkerScratch& ws);

// 4b. Sub-blocks (kSubBlock^3 cells, sub-block (x, y, z) at index x + 2 y + 4 z) whose conservative field bounds
// lie entirely below (kOutside) or above (kInside) iso, 1e-3 relative margin, hold no surface cell, so the samples
// only they hold need no field value, only their side. ws.subBlocks gets each sub-block's class, ws.rows (j + 9 k) a
// 1 for every row of samples some kLive sub-block's closed vertex range meets. A forced block, one with fewer than
// kSubBlockMinCandidates candidates or one whose candidates are all separable on the lattice (cheaper to sample
// than to bound) keeps every sub-block live. Returns whether any is live: if none is, the block
// holds no surface. ws.field must be prepared for the block.
bool cullSubBlocks(const Field& field, const Grid& g, glm::ivec3 block, bool forced, WorkerScratch& ws);

// 4c. The block's 9^3 samples into r.samples (sampleIndex order): F on the rows ws.rows asks for; on the others a
// stand-in of the right side (0 outside, FLT_MAX inside, from ws.subBlocks), never used but by its side (every
// crossing edge and surface cell lies in a live sub-block). Moved vertices' values and positions from snaps (sorted
// by key) into r.samples and r.moved. ws.field, ws.rows and ws.subBlocks must be prepared by cullSubBlocks.
void sampleBlock(const Field& field, const Grid& g, glm::ivec3 block, const BlockAxes& axes,
                 std::span<const Snap> snaps, BlockResult& r, WorkerScratch& ws);

// 4d. From r.samples: r.cells (surface cells in index order with their case codes), r.edgeVertex (every owned edge's
// local vertex number or -1) and, in the same order, ws.edges (ends' positions, iterations), ws.ends (F at both
// ends) and ws.outer (F at the samples one step beyond each end on the edge's line, -1 where there is none: off the
// block or on a row left out; ws.outer stays empty in a block with moved vertices or with fewer than
// kCubicMinCandidates candidates). Local numbers follow cells (i, j, k) ascending with i fastest, axes x, y, z within
// a cell. ws.rows must say which rows were sampled, ws.field be prepared for the block. Returns whether the block
// has a surface cell.
bool classifyBlock(float iso, int rootIterations, const BlockAxes& axes, BlockResult& r, WorkerScratch& ws);

// 4e. Root finding on ws.edges: their parameters t in (0, 1) along pa -> pb. The first estimate is the root of the
// polynomial through ws.ends and the known ws.outer, or of the line through ws.ends when ws.outer is empty; then at
// most each edge's iterations batched evaluations of the true field (regula falsi), and for an edge whose bracket is
// still wider than kRootBracket of the edge after them, up to kMaxBisections bisections, so that its vertex is on
// the root its bracket holds. With `shade` and ws.outer the evaluations are whole samples, and an edge whose root is
// an evaluated point (it met the tolerance) gets that sample in ws.samples and a 1 in ws.shaded; every other edge a
// 0. ws.field must be prepared for the block.
void findEdgeRoots(const Field& field, RootTransform transform, bool shade, WorkerScratch& ws);

// 4f. r.positions (and, as the options ask, r.normals and r.colors) of ws.edges' vertices, 3 floats per vertex: the
// normals and colours from ws.samples where ws.shaded says so, from one batched evaluation elsewhere (the same bits:
// a sample is a function of the point).
void shadeEdgeVertices(const Field& field, const MarchingCubesOptions& options, BlockResult& r, WorkerScratch& ws);

// 5. Global vertex numbers: every surface block's r.base (blocks without surface get the running total too) and
// surfaceBlocks the blocks with surface, ascending. Returns the number of edge vertices.
uint32_t numberVertices(std::span<BlockResult> blocks, std::vector<uint32_t>& surfaceBlocks);

// 6. Block b's triangles (global vertex numbers; loop-centre vertices kProvisional | local number) and loop-centre
// vertices, from its cells and the edge vertices of it and its +x, +y, +z neighbours (numbered by pass 5).
void triangulateBlock(const Field& field, const Grid& g, size_t b, const MarchingCubesOptions& options,
                      MarchingCubes::State& st, FieldScratch& scratch);

// 7. out = every surface block's edge vertices in block order, then every block's loop-centre vertices (numbered
// from `edgeVertices` on, st.centreBases), and the triangles in block order with provisional indices resolved.
void gatherMesh(uint32_t edgeVertices, int threads, MarchingCubes::State& st, Mesh& out);

}  // namespace imps::mc
