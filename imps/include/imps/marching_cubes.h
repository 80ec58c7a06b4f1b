// SPDX-License-Identifier: MIT
// Marching Cubes polygonizer: a closed, indexed triangle mesh of a Field's iso-surface on a regular grid.
//
// Based on: W. Lorensen and H. Cline, "Marching Cubes", 1987; G. Nielson and B. Hamann, "The Asymptotic Decider",
//           1991 (face ambiguities); K. Russell, "IMPS", MIT 1999, 3.3.
//
// Guarantees:
//  * Closed 2-manifold output wherever the surface is closed: the triangulation of every cell is derived from its
//    faces alone (the asymptotic decider resolves ambiguous faces from the face's four samples), so neighbouring
//    cells always agree on the contour across their shared face; the grid has a one-cell margin outside the
//    surface's conservative bounds, so no surface reaches the grid boundary. Shared vertices (indexed mesh).
//  * Vertices lie on the surface: each is found by root finding along its edge (Anderson-Bjorck regula falsi, then
//    bisection where the steps run out with a wide bracket) on the true field, not only linear interpolation; a
//    loop-centre vertex by Newton steps from its loop's mean, else by a bracketed root on a line through it. Normals
//    are the normalised negative field gradient; colours are the materials blended by each primitive's share of the
//    field.
//  * The unwanted-blending rule holds (the Field's blend sets), unlike the thesis's Marching Cubes.
//  * Thin features survive coarse grids (preserveThinFeatures): every primitive's skeleton (metaball centre,
//    ellipsoid major axis, line segment) is sampled at half-cell spacing; a grid vertex nearest to a skeleton point
//    that is inside the surface, but itself outside, is moved onto that point (its sample taken there). The grid
//    vertices of a skeleton are made 6-connected, so a limb thinner than a cell is still a closed tube, connected
//    to the rest of the body, instead of vanishing. Its shape is then only as good as the grid allows.
//  * Deterministic: 1 thread and N threads give the identical mesh (same vertex and triangle order).
//  * Empty space is skipped: the grid is split into blocks of 8^3 cells; blocks whose conservative field bounds
//    are entirely below or above the iso-value (with a 1e-3 relative margin) are never sampled.
#pragma once

#include <atomic>
#include <cstddef>
#include <expected>
#include <functional>
#include <memory>
#include <string>

#include <glm/vec3.hpp>

#include "imps/diagnostic.h"
#include "imps/field.h"
#include "imps/mesh.h"

namespace imps {

struct MarchingCubesOptions {
  // Cubic cell edge in metres. Takes precedence when > 0.
  float cellSize = 0.0f;
  // The thesis's X/Y/Z resolution: cells along each axis of the surface bounds (cells may be non-cubic).
  // Used when cellSize is 0 and all three are > 0.
  glm::ivec3 gridResolution{0};
  // Otherwise: cubic cells, this many along the longest side of the surface bounds.
  int resolution = 64;
  // Worker threads (0: all cores).
  int threads = 0;
  // Most root-finding iterations per vertex after the initial interpolation (0: interpolation only). They run on
  // ln F for the exponential blend (F - iso for the others) and stop once that is within 5e-4 of its change
  // along the edge.
  int rootIterations = 6;
  bool preserveThinFeatures = true;
  bool computeNormals = true;
  bool computeColors = true;
  // The most cells a grid may have (2^28, about 645^3). A finer grid is refused: polygonize() gives an empty mesh
  // and planGrid() says why. Raise it for a deliberately huge mesh.
  size_t maxCells = size_t{1} << 28;
  // Long bakes (libfive's BRepSettings is the model). When *cancel becomes true (from any thread) the call returns
  // promptly: every pass stops at its next block, `out` is left empty and stats->cancelled is set. Null: never.
  std::atomic<bool>* cancel = nullptr;
  // Called on the thread that called polygonize(), between passes and between slices of the sampling pass, with the
  // fraction done in [0, 1], non-decreasing; the last call of a completed polygonize() reports 1. It may set *cancel.
  std::function<void(float fraction)> progress;
};

struct MarchingCubesStats {
  glm::ivec3 cells{0};       // grid size in cells
  glm::vec3 cellSize{0.0f};  // metres
  glm::vec3 origin{0.0f};    // the grid's lowest corner
  size_t blocks = 0, blocksSampled = 0, blocksWithSurface = 0;
  size_t thinFeatureVertices = 0;  // grid vertices moved onto a skeleton
  double milliseconds = 0.0;       // the whole call; then its phases:
  double setupMs = 0.0;            // surface bounds, grid, binning primitives into blocks
  double thinFeaturesMs = 0.0;     // skeleton sampling and vertex moves
  double sampleMs = 0.0;           // block bounds, samples, edge vertices (parallel)
  double triangulateMs = 0.0;      // cell cases and triangles (parallel)
  double gatherMs = 0.0;           // concatenation into the output mesh
  bool cancelled = false;          // options.cancel stopped the call: the mesh is empty
};

// The grid polygonize() uses for `field` with `options`: cells along x, y and z (zero for an empty field), or, when
// it would have more than options.maxCells cells, one error without a location (the caller knows where the cell
// size came from) saying "a grid of X x Y x Z cells (N) for a surface of ... m at cell C m is more than the limit
// of M cells". Cheap (the field's bounds only); call it before polygonize() to report a refused grid.
std::expected<glm::ivec3, Diagnostics> planGrid(const Field& field, const MarchingCubesOptions& options);

// Polygonizes field's iso-surface. Reuses nothing between calls; see MarchingCubes for repeated use. A grid beyond
// options.maxCells gives an empty mesh (see planGrid); so does options.cancel (stats->cancelled then says so).
Mesh polygonize(const Field& field, const MarchingCubesOptions& options = {}, MarchingCubesStats* stats = nullptr);

// A polygonizer that keeps its buffers between calls (for the live app, which meshes every frame).
class MarchingCubes {
 public:
  MarchingCubes();
  ~MarchingCubes();
  MarchingCubes(const MarchingCubes&) = delete;
  MarchingCubes& operator=(const MarchingCubes&) = delete;

  // Polygonizes into `out` (cleared first). Returns false (and leaves `out` empty) when options.cancel stopped it.
  // Scratch memory (per-block results, one set of buffers per worker thread) is kept in this object and reused.
  bool polygonize(const Field& field, const MarchingCubesOptions& options, Mesh& out,
                  MarchingCubesStats* stats = nullptr);

  struct State;  // opaque: defined in marching_cubes_passes.h (the passes' unit tests use it)

 private:
  std::unique_ptr<State> state_;
};

}  // namespace imps
