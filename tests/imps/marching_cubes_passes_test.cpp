// SPDX-License-Identifier: MIT
// The passes of Marching Cubes one at a time (imps/src/marching_cubes_passes.h), each against a brute-force statement
// of its contract; and the options' cancel flag and progress callback.
#include "marching_cubes_passes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <random>
#include <set>
#include <thread>

#include "imps/marching_cubes.h"
#include "imps/mesh.h"

namespace imps::mc {
namespace {

// A lone primitive with a very hard blend (its surface is exactly d = 1), or several blended softly.
Field makeField(std::vector<Primitive> prims, float blobbiness) {
  const size_t n = prims.size();
  BlendFunction blend;
  blend.defaultParam = blobbiness;
  return Field(std::move(prims), std::vector<float>(n, blobbiness), std::vector<glm::vec3>(n, glm::vec3(0.5f)), blend,
               BlendSets::all(n));
}

Field threeBalls() {
  return makeField({Primitive::metaball({0, 0, 0}, 0.5f), Primitive::metaball({0.6f, 0.1f, 0}, 0.3f),
                    Primitive::metaball({-0.2f, 0.7f, 0.3f}, 0.25f)},
                   -2.0f);
}

bool overlaps(const Box& a, const Box& b) {
  return glm::all(glm::lessThanEqual(a.lo, b.hi)) && glm::all(glm::lessThanEqual(b.lo, a.hi));
}

TEST(MarchingCubesPasses, MakeGridHasAMarginOfACellAndWholeBlocks) {
  const Field field = threeBalls();
  MarchingCubesOptions o;
  o.cellSize = 0.05f;
  const Grid g = makeGrid(field, o);
  EXPECT_EQ(g.cells, g.blocks * kBlock);
  const Box bounds = field.surfaceBounds();
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(g.origin[a] + g.cell[a], bounds.lo[a] + 1e-5f) << "a cell of margin below, axis " << a;
    EXPECT_GE(g.origin[a] + float(g.cells[a] - 1) * g.cell[a], bounds.hi[a] - 1e-5f) << "and above, axis " << a;
  }
  EXPECT_EQ(makeGrid(makeField({}, -2.0f), o).blockCount(), 0u) << "no surface, no blocks";
}

TEST(MarchingCubesPasses, BinPrimitivesListsEveryBlockTheSupportBoxReaches) {
  const Field field = threeBalls();
  MarchingCubesOptions o;
  o.cellSize = 0.02f;
  const Grid g = makeGrid(field, o);
  Bins bins;
  binPrimitives(field, g, bins);
  ASSERT_EQ(bins.offsets.size(), g.blockCount() + 1);
  size_t listed = 0;
  for (size_t b = 0; b < g.blockCount(); ++b) {
    const auto members = bins.of(b);
    EXPECT_TRUE(std::is_sorted(members.begin(), members.end()));
    const glm::ivec3 c = g.blockCoords(b);
    const Box box = g.blockBox(c.x, c.y, c.z);
    for (uint32_t i = 0; i < field.size(); ++i) {
      Box grown = field.supportBox(i);  // the contract: grown by a cell for moved vertices
      grown.lo -= g.cell;
      grown.hi += g.cell;
      Box shrunk = box;  // away from the shared faces, where rounding may go either way
      shrunk.lo += 1e-4f;
      shrunk.hi -= 1e-4f;
      const bool member = std::find(members.begin(), members.end(), i) != members.end();
      if (overlaps(shrunk, grown)) {
        EXPECT_TRUE(member) << "block " << b << " primitive " << i;
      }
      Box wide = grown;
      wide.lo -= 1e-4f;
      wide.hi += 1e-4f;
      if (member) {
        EXPECT_TRUE(overlaps(box, wide)) << "block " << b << " primitive " << i;
      }
    }
    listed += members.size();
  }
  EXPECT_GT(listed, field.size());
}

TEST(MarchingCubesPasses, CullBlockKeepsOnlyBlocksTheSurfaceMayCross) {
  const Field field = makeField({Primitive::metaball({0, 0, 0}, 0.5f)}, -8.0f);
  MarchingCubesOptions o;
  o.cellSize = 0.02f;  // blocks of 0.16 m: some wholly inside the ball, some outside, some across
  const Grid g = makeGrid(field, o);
  Bins bins;
  binPrimitives(field, g, bins);
  WorkerScratch ws;
  size_t kept = 0;
  for (size_t b = 0; b < g.blockCount(); ++b) {
    const glm::ivec3 c = g.blockCoords(b);
    const Box box = g.blockBox(c.x, c.y, c.z);
    // The ball's distance range over the box: nearest and farthest point from the centre.
    const glm::vec3 nearest = glm::clamp(glm::vec3(0.0f), box.lo, box.hi);
    const glm::vec3 farthest = glm::max(glm::abs(box.lo), glm::abs(box.hi));
    const float rMin = glm::length(nearest), rMax = glm::length(farthest);
    const bool crosses = rMin <= 0.5f && rMax >= 0.5f;
    const bool keep = cullBlock(field, g, b, bins.of(b), false, ws);
    if (crosses) {
      EXPECT_TRUE(keep) << "block " << b << " is crossed by the surface";
    }
    if (rMax < 0.45f || rMin > 0.55f) {
      EXPECT_FALSE(keep) << "block " << b << " is wholly inside or outside";
    }
    kept += keep;
    EXPECT_TRUE(cullBlock(field, g, b, bins.of(b), true, ws)) << "a forced block is always sampled";
  }
  EXPECT_GT(kept, 0u);
  EXPECT_LT(kept, g.blockCount());
}

TEST(MarchingCubesPasses, ClassifyBlockFindsEveryMixedCellAndOwnedCrossingEdgeInOrder) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> value(0.0f, 2.0f);
  Grid g;
  g.cell = glm::vec3(0.1f);
  g.blocks = glm::ivec3(1);
  g.cells = glm::ivec3(kBlock);
  const BlockAxes axes(g, glm::ivec3(0));
  for (int trial = 0; trial < 20; ++trial) {
    BlockResult r;
    r.samples.resize(kBlockSamples);
    for (float& v : r.samples) v = trial == 0 ? 0.5f : value(rng);  // trial 0: no surface at all
    WorkerScratch ws;
    const float iso = 1.0f;
    const bool surface = classifyBlock(iso, 6, axes, r, ws);
    auto in = [&](int i, int j, int k) { return r.samples[size_t(sampleIndex(i, j, k))] >= iso; };
    std::vector<uint32_t> cells;
    for (int k = 0; k < kBlock; ++k)
      for (int j = 0; j < kBlock; ++j)
        for (int i = 0; i < kBlock; ++i) {
          uint32_t code = 0;
          for (uint32_t c = 0; c < 8; ++c) code |= uint32_t(in(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1))) << c;
          if (code != 0 && code != 255) cells.push_back(uint32_t(i + kBlock * (j + kBlock * k)) | code << 16);
        }
    EXPECT_EQ(r.cells, cells);
    EXPECT_EQ(surface, !cells.empty());
    int16_t next = 0;
    for (int k = 0; k < kBlock; ++k)
      for (int j = 0; j < kBlock; ++j)
        for (int i = 0; i < kBlock; ++i)
          for (int axis = 0; axis < 3; ++axis) {
            const int di = axis == 0, dj = axis == 1, dk = axis == 2;
            const bool crossing = in(i, j, k) != in(i + di, j + dj, k + dk);
            const int16_t local = r.edgeVertex[size_t(ownedEdgeIndex(axis, i, j, k))];
            if (!crossing) {
              EXPECT_EQ(local, -1);
              continue;
            }
            ASSERT_EQ(local, next) << "numbered cells ascending, axes x, y, z within a cell";
            const EdgeRoot& e = ws.edges[size_t(local)];
            EXPECT_EQ(e.pa, glm::vec3(axes.xs[size_t(i)], axes.ys[size_t(j)], axes.zs[size_t(k)]));
            EXPECT_EQ(e.pb, glm::vec3(axes.xs[size_t(i + di)], axes.ys[size_t(j + dj)], axes.zs[size_t(k + dk)]));
            EXPECT_EQ(ws.ends[2 * size_t(local)], r.samples[size_t(sampleIndex(i, j, k))]);
            EXPECT_EQ(e.iterations, 6);
            ++next;
          }
    EXPECT_EQ(ws.edges.size(), size_t(next));
  }
}

// With the samples beyond the edges' ends (a cubic or quadratic first estimate, every step a whole sample) and
// without (the line's root, every step a value). A vertex root finding shaded has the very sample of its point.
TEST(MarchingCubesPasses, FindEdgeRootsPutsEveryVertexOnTheSurface) {
  for (const bool outer : {true, false})
    for (float blobbiness : {-8.0f, -2.0f}) {
      const Field field = makeField({Primitive::metaball({0, 0, 0}, 0.5f)}, blobbiness);
      WorkerScratch ws;
      Box region;
      region.lo = glm::vec3(-1.0f);
      region.hi = glm::vec3(1.0f);
      field.prepare(region, ws.field);
      std::mt19937 rng(3);
      std::uniform_real_distribution<float> u(-1.0f, 1.0f);
      for (int q = 0; q < 200; ++q) {
        const glm::vec3 dir = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(1e-3f));
        EdgeRoot e;
        e.pa = dir * (0.5f - 0.06f);  // inside
        e.pb = dir * (0.5f + 0.04f);  // outside
        e.iterations = 6;
        ws.edges.push_back(e);
        ws.ends.push_back(field.value(e.pa));
        ws.ends.push_back(field.value(e.pb));
        // The samples just outside the ends: known for some edges (a cubic or quadratic first estimate), not others.
        if (outer) {
          ws.outer.push_back(q % 3 == 0 ? -1.0f : field.value(e.pa - (e.pb - e.pa)));
          ws.outer.push_back(q % 4 == 0 ? -1.0f : field.value(e.pb + (e.pb - e.pa)));
        }
      }
      findEdgeRoots(field, RootTransform(field), /*shade=*/true, ws);
      float worstF = 0.0f;
      size_t shaded = 0;
      for (size_t q = 0; q < ws.edges.size(); ++q) {
        const EdgeRoot& e = ws.edges[q];
        ASSERT_GE(e.t, 0.0f);
        ASSERT_LE(e.t, 1.0f);
        const glm::vec3 x = e.pa + e.t * (e.pb - e.pa);
        ASSERT_EQ(ws.shaded.size(), ws.edges.size());
        if (ws.shaded[q]) {
          ++shaded;
          const FieldSample at = field.sample(x);
          ASSERT_EQ(ws.samples[q].value, at.value);
          ASSERT_EQ(ws.samples[q].gradient, at.gradient);
          ASSERT_EQ(ws.samples[q].color, at.color);
        }
        worstF = std::max(worstF, std::abs(field.value(x) - field.iso()));
        if (blobbiness == -8.0f) {
          EXPECT_NEAR(glm::length(x), 0.5f, 1e-4f) << "the hard blend's surface is the sphere";
        }
      }
      EXPECT_LT(worstF, 1e-3f) << "blobbiness " << blobbiness << (outer ? " with" : " without") << " outer samples";
      if (outer) {
        EXPECT_GT(shaded, ws.edges.size() * 9 / 10) << "nearly every vertex is an evaluated point";
      } else {
        EXPECT_EQ(shaded, 0u) << "from the line's root shading evaluates separately";
      }
    }
}

TEST(MarchingCubesPasses, NumberVerticesCountsInBlockOrder) {
  std::vector<BlockResult> blocks(6);
  const size_t vertices[6] = {0, 4, 0, 7, 1, 0};
  for (size_t b = 0; b < 6; ++b) {
    blocks[b].hasSurface = vertices[b] > 0;
    blocks[b].positions.resize(3 * vertices[b]);
  }
  std::vector<uint32_t> surface = {99};  // replaced
  EXPECT_EQ(numberVertices(blocks, surface), 12u);
  EXPECT_EQ(surface, (std::vector<uint32_t>{1, 3, 4}));
  EXPECT_EQ(blocks[1].base, 0u);
  EXPECT_EQ(blocks[3].base, 4u);
  EXPECT_EQ(blocks[4].base, 11u);
}

TEST(MarchingCubesPasses, GatherMeshPutsLoopCentresAfterEveryEdgeVertex) {
  MarchingCubes::State st;
  st.blocks.resize(3);
  auto fill = [](BlockResult& r, size_t edge, size_t centre) {
    r.hasSurface = true;
    for (size_t v = 0; v < edge; ++v) r.positions.insert(r.positions.end(), {float(v), 0, 0});
    for (size_t v = 0; v < centre; ++v) r.centrePositions.insert(r.centrePositions.end(), {float(v), 1, 0});
  };
  fill(st.blocks[0], 3, 1);
  fill(st.blocks[2], 2, 2);
  st.blocks[0].triangles = {0, 1, kProvisional | 0};
  st.blocks[2].triangles = {3, 4, kProvisional | 1, 2, 3, kProvisional | 0};
  Mesh out;
  gatherMesh(5, 2, st, out);
  EXPECT_EQ(out.vertexCount(), 8u);
  EXPECT_EQ(out.indices, (std::vector<uint32_t>{0, 1, 5, 3, 4, 7, 2, 3, 6}));
  EXPECT_EQ(out.position(5).y, 1.0f) << "block 0's centre follows all five edge vertices";
  EXPECT_EQ(out.position(7), glm::vec3(1, 1, 0)) << "block 2's second centre";
}

// Every culled sub-block is wholly on the side it is given: all the samples of its closed vertex range (evaluated
// here without culling) agree; sampleBlock puts F on every row a live sub-block meets and a stand-in of the right
// side elsewhere; and some sub-blocks of blocks that are sampled are culled. (Short line segments: metaballs alone,
// being separable on the lattice, are cheaper to sample than to bound and are never culled, as the end checks.)
TEST(MarchingCubesPasses, CullSubBlocksCullsOnlySubBlocksWhollyInsideOrOutside) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), radius(0.1f, 0.3f), offset(-0.05f, 0.05f);
  std::vector<Primitive> prims, balls;
  for (int i = 0; i < 40; ++i) {
    const glm::vec3 c(u(rng), u(rng), u(rng));
    const float r = radius(rng);
    prims.push_back(Primitive::lineSeg(c, c + glm::vec3(offset(rng), offset(rng), offset(rng)), r, r));
    balls.push_back(Primitive::metaball(c, r));
  }
  const Field field = makeField(prims, -2.0f);
  MarchingCubesOptions o;
  o.cellSize = 0.02f;
  const Grid g = makeGrid(field, o);
  Bins bins;
  binPrimitives(field, g, bins);
  WorkerScratch ws;
  size_t culled[3] = {0, 0, 0};
  for (size_t b = 0; b < g.blockCount(); ++b) {
    if (!cullBlock(field, g, b, bins.of(b), false, ws)) continue;
    const glm::ivec3 block = g.blockCoords(b);
    const BlockAxes axes(g, block);
    BlockResult all;
    all.samples.resize(kBlockSamples);
    field.latticeValues(axes.xs, axes.ys, axes.zs, all.samples, ws.field);
    const bool live = cullSubBlocks(field, g, block, false, ws);
    BlockResult r;
    sampleBlock(field, g, block, axes, {}, r, ws);
    bool anyLive = false;
    for (int s = 0; s < kSubBlocks; ++s) {
      const uint8_t c = ws.subBlocks[size_t(s)];
      ++culled[c];
      anyLive |= c == kLive;
      const glm::ivec3 lo = glm::ivec3(s & 1, (s >> 1) & 1, s >> 2) * kSubBlock;
      for (int k = lo.z; k <= lo.z + kSubBlock; ++k)
        for (int j = lo.y; j <= lo.y + kSubBlock; ++j) {
          if (c == kLive) {
            EXPECT_TRUE(ws.rows[size_t(j + kBlockVerts * k)]) << "a live sub-block's row is sampled";
          }
          for (int i = lo.x; i <= lo.x + kSubBlock; ++i) {
            const size_t q = size_t(sampleIndex(i, j, k));
            if (c != kLive) {
              ASSERT_EQ(all.samples[q] >= field.iso(), c == kInside) << "block " << b << " sub " << s;
            }
            ASSERT_EQ(r.samples[q] >= field.iso(), all.samples[q] >= field.iso()) << "block " << b << " sub " << s;
            if (ws.rows[size_t(j + kBlockVerts * k)]) {
              ASSERT_EQ(r.samples[q], all.samples[q]);
            }
          }
        }
    }
    EXPECT_EQ(live, anyLive);
    EXPECT_TRUE(cullSubBlocks(field, g, block, true, ws)) << "a forced block keeps every sub-block";
    for (uint8_t c : ws.subBlocks) EXPECT_EQ(c, kLive);
  }
  EXPECT_GT(culled[kLive], 0u);
  EXPECT_GT(culled[kOutside], 0u);
  EXPECT_GT(culled[kInside], 0u);
  const Field separable = makeField(balls, -2.0f);
  Bins ballBins;
  binPrimitives(separable, g, ballBins);
  size_t sampled = 0;
  for (size_t b = 0; b < g.blockCount(); ++b) {
    if (!cullBlock(separable, g, b, ballBins.of(b), false, ws)) continue;
    ++sampled;
    EXPECT_TRUE(separable.separableOnLattice(ws.field));
    EXPECT_TRUE(cullSubBlocks(separable, g, g.blockCoords(b), false, ws));
    for (uint8_t c : ws.subBlocks) EXPECT_EQ(c, kLive) << "block " << b;
  }
  EXPECT_GT(sampled, 10u);
}

TEST(MarchingCubesPasses, PassesByHandMakeThePolygonizersMesh) {
  const Field field = threeBalls();
  MarchingCubesOptions o;
  o.cellSize = 0.04f;
  o.preserveThinFeatures = false;
  MarchingCubes::State st;
  st.workers.resize(1);
  const Grid g = makeGrid(field, o);
  st.blocks.resize(g.blockCount());
  binPrimitives(field, g, st.bins);
  st.forced.assign(g.blockCount(), 0);
  for (size_t b = 0; b < g.blockCount(); ++b) {
    BlockResult& r = st.blocks[b];
    WorkerScratch& ws = st.workers[0];
    r.sampled = r.hasSurface = false;
    if (!cullBlock(field, g, b, st.bins.of(b), false, ws)) continue;
    if (!cullSubBlocks(field, g, g.blockCoords(b), false, ws)) continue;
    const BlockAxes axes(g, g.blockCoords(b));
    sampleBlock(field, g, g.blockCoords(b), axes, {}, r, ws);
    r.hasSurface = classifyBlock(field.iso(), o.rootIterations, axes, r, ws);
    if (!r.hasSurface) continue;
    findEdgeRoots(field, RootTransform(field), /*shade=*/true, ws);
    shadeEdgeVertices(field, o, r, ws);
  }
  std::vector<uint32_t> surface;
  const uint32_t edgeVertices = numberVertices(st.blocks, surface);
  for (uint32_t b : surface) triangulateBlock(field, g, b, o, st, st.workers[0].field);
  Mesh byHand;
  gatherMesh(edgeVertices, 1, st, byHand);
  const Mesh whole = polygonize(field, o);
  EXPECT_GT(whole.triangleCount(), 100u);
  EXPECT_EQ(byHand.positions, whole.positions);
  EXPECT_EQ(byHand.normals, whole.normals);
  EXPECT_EQ(byHand.indices, whole.indices);
}

// ---- Cancel and progress ---------------------------------------------------------------------------------------

TEST(MarchingCubesOptions, ProgressIsReportedOnTheCallingThreadUpToOne) {
  const Field field = threeBalls();
  for (int threads : {1, 2}) {
    MarchingCubesOptions o;
    o.cellSize = 0.02f;
    o.threads = threads;
    std::vector<float> reports;
    bool otherThread = false;
    const auto caller = std::this_thread::get_id();
    o.progress = [&](float f) {
      reports.push_back(f);
      otherThread |= std::this_thread::get_id() != caller;
    };
    MarchingCubes mc;
    Mesh mesh;
    MarchingCubesStats stats;
    EXPECT_TRUE(mc.polygonize(field, o, mesh, &stats));
    EXPECT_FALSE(stats.cancelled);
    ASSERT_GT(reports.size(), 4u);
    EXPECT_FALSE(otherThread);
    EXPECT_TRUE(std::is_sorted(reports.begin(), reports.end()));
    EXPECT_EQ(reports.front(), 0.0f);
    EXPECT_EQ(reports.back(), 1.0f);
    MarchingCubesOptions quiet = o;
    quiet.progress = nullptr;
    EXPECT_EQ(mesh.indices, polygonize(field, quiet).indices) << "progress does not change the mesh";
  }
}

TEST(MarchingCubesOptions, CancelStopsPromptlyWithAnEmptyMeshThatSaysSo) {
  const Field field = threeBalls();
  MarchingCubesOptions o;
  o.cellSize = 0.02f;
  o.threads = 2;
  std::atomic<bool> cancel{true};
  o.cancel = &cancel;
  MarchingCubes mc;
  Mesh mesh;
  mesh.positions = {1, 2, 3};
  MarchingCubesStats stats;
  EXPECT_FALSE(mc.polygonize(field, o, mesh, &stats)) << "cancelled before it starts";
  EXPECT_TRUE(stats.cancelled);
  EXPECT_EQ(mesh.vertexCount(), 0u);
  EXPECT_EQ(mesh.triangleCount(), 0u);

  // Cancelled from the progress callback in the middle of the sampling pass: no report after it, nothing output.
  cancel = false;
  int reportsAfterCancel = 0;
  o.progress = [&](float f) {
    if (cancel) ++reportsAfterCancel;
    if (f > 0.3f) cancel = true;
  };
  EXPECT_FALSE(mc.polygonize(field, o, mesh, &stats));
  EXPECT_TRUE(stats.cancelled);
  EXPECT_EQ(mesh.vertexCount(), 0u);
  EXPECT_EQ(reportsAfterCancel, 0);

  // The same object, not cancelled, makes the same mesh as a fresh one: nothing stale survives a cancel.
  cancel = false;
  o.progress = nullptr;
  EXPECT_TRUE(mc.polygonize(field, o, mesh, &stats));
  EXPECT_FALSE(stats.cancelled);
  const Mesh fresh = polygonize(field, o);
  EXPECT_GT(fresh.triangleCount(), 0u);
  EXPECT_EQ(mesh.positions, fresh.positions);
  EXPECT_EQ(mesh.indices, fresh.indices);
}

}  // namespace
}  // namespace imps::mc
