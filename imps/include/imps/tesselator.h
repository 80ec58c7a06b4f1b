// SPDX-License-Identifier: MIT
// The particle polygonizer (Tesselator3MP, thesis 3.4-3.8 and appendix A): Witkin-Heckbert particles that follow a
// character's surface from frame to frame, triangulated every render into a closed mesh.
//
// Based on: A. Witkin and P. Heckbert, "Using Particles to Sample and Control Implicit Surfaces", SIGGRAPH 1994;
//           H. Pedersen's simplified radius update (as adopted in the thesis, 3.4);
//           P. Heckbert, "Fast Surface Particle Repulsion", 1997 (uniform hash);
//           K. Russell, "IMPS", MIT 1999, 3.4-3.8 (ownership, differential transforms, approximate triangulation,
//           parallel compute / sequential update).
//
// One update (update()):
//   1. differential transforms: every particle moves rigidly with its owner's joint since the last update;
//   2. spatial sort, uniform hash rebuild and neighbour list (only when particles moved since the list was built; the
//      list is shared by repulsion, fusion and the triangulation's fans);
//   3. compute phase (parallel, fixed partition): field sample, repulsion velocity constrained to the surface, radius
//      rate (Pedersen), ownership transfer to blend neighbours only;
//   4. integration (parallel, each particle writes only itself): clamped step, one Newton projection onto the surface;
//   5. add/delete phase (sequential, particle order): strays killed, fusion, death, fission.
// triangulate() builds the mesh: tangent-plane Delaunay fans (Voronoi cells of the projected neighbours) voted on by
// all three corners, assembled without non-manifold edges, then the remaining boundary loops are filled.
// docs/tesselator.md describes every choice and what differs from the thesis.
//
// Determinism: for a fixed seed and thread count (and in fact for any thread count) the same calls give the same
// particles and meshes: randomness comes from per-particle streams (seed, particle id, update number), parallel passes
// write per-particle outputs only, and every sequential pass runs in particle order.
// Thread safety: one owner calls everything; the worker threads are internal.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "imps/mesh.h"
#include "imps/scene.h"

namespace imps {

class Field;
class SkeletonCache;
class Character;

struct TesselatorOptions {
  // Figure A-1 fields (lengths in metres, deltaT in the simulation's time unit).
  float deltaT = 0.045f;         // integration step
  float desiredRadius = 0.3f;    // sigma-hat: target particle repulsion radius = target spacing (edge length)
  float queryRadius = 0.8f;      // neighbour-cache radius (energies beyond it are ignored)
  float energyCoeff = 10.0f;     // alpha: repulsion energy amplitude
  float surfaceCoeff = 30.0f;    // phi: feedback pulling particles onto the surface
  float fissioningFrac = 0.5f;   // nu: a large particle fissions once its energy exceeds nu * E-hat
  bool useSimpleRadii = true;    // Pedersen's radius rule (true) or Witkin-Heckbert's original (false)
  int threads = 1;               // worker threads for the compute phase (0: all cores), as MarchingCubesOptions
  int updatesPerRender = 1;      // updates per frame() (the triangulation runs once per frame)
  float colorWidth = 3.0f;       // > 0: colour blending width; larger blends primitive colours over a wider band
  bool doDifferentialTransforms = true;
  float cubeSize = 0.6f;         // UniformHash cubeSize
  int bitsPerDim = 3;            // UniformHash bitsPerDim (clamped to [1, 7])
  // Ours.
  uint64_t seed = 1;             // random streams: same seed (and same calls) => same meshes
  // The most particles (seeding and fission stop here; about 1.7 kB each while updating and triangulating). A
  // desiredRadius too small for the character reaches it; the surface is then sampled more coarsely than asked.
  size_t maxParticles = size_t{1} << 18;
  int maxHoleLoop = 40;          // boundary loops up to this many edges are filled by the hole repair
  // A triangulation left with a hole or a pinched vertex after repair, or one that meshes a part apart from the solid
  // it joins (stats().cutOffParts), is replaced by Marching Cubes of the same field at cell desiredRadius
  // (stats().fallback), so that no hole and no part off the body is ever shown. False: the particle mesh as it is.
  bool closedFallback = true;
  // A closed triangulation's folds (triangles winding against the field's outward normal at their centroid, in the
  // concave creases) are repaired by edge flips, vertex removals and retriangulations of a disk around them, which
  // keep it closed and manifold (pass H, docs/tesselator.md); stats().foldedTriangles counts those left. False: folds
  // stay (and are not counted).
  bool unfold = true;
  // Thin parts: where a particle's primitive is thinner than desiredRadius (the particle's distance from the
  // primitive's core), its spacing is desiredRadius times thickness / desiredRadius (at least 0.5), so that a ring of
  // about 2 pi particles closes round a wrist or a small blob instead of the three or four of the full spacing
  // (docs/tesselator.md, "Thin parts"). Parts at least desiredRadius thick are sampled as without. False: the
  // thesis's one spacing everywhere.
  bool resolveThinParts = true;
  // Projective: a textured mesh's coordinates come from the generators (textureMesh alone). Carried: every particle
  // carries its coordinates (see carryTexcoords), so the texture stretches with the skin instead of sliding.
  TextureMode textureMode = TextureMode::Projective;
  // Long bakes (settle()), as libfive's BRepSettings: when *cancel becomes true (from any thread) settle() returns
  // after the update under way, with `mesh` empty and stats().cancelled set. Null: never.
  std::atomic<bool>* cancel = nullptr;
  // Called by settle() on the calling thread after every update with the fraction of maxUpdates done (non-decreasing;
  // 1 when it returns settled or at maxUpdates). It may set *cancel.
  std::function<void(float fraction)> progress;

  // From a scene's Tesselator3MP node (every figure A-1 field plus seed).
  static TesselatorOptions fromNode(const Tesselator3MPNode& node);
  // For a scene without a Tesselator3MP node: the defaults above with the lengths scaled to the field's feature size,
  // so that the particles can reach every part of it. desiredRadius is half the smallest primitive's minRadius() (a
  // ball of that primitive's size gets about 60 particles; the default 0.3 m gave a 0.15 m metaball 3), and at most
  // twice `cellSize` when that is > 0 (a MarchingCubes node's cell: the particles then resolve what its grid
  // resolves); raised only if the primitives' summed surface area (overlaps counted twice) would need more than
  // kDefaultParticleBudget particles. queryRadius and the hash cube keep their ratios to it (8/3 and 2), and
  // bitsPerDim grows until the hash covers the field's surfaceBounds() (at most 7). A field without primitives gets
  // the plain defaults.
  static constexpr size_t kDefaultParticleBudget = size_t{1} << 19;
  static TesselatorOptions forField(const Field& field, float cellSize = 0.0f);
  // The scene's Tesselator3MP node if it has one (fromNode), else forField(field, its MarchingCubes cellSize if any)
  // with that MarchingCubes node's numThreads.
  static TesselatorOptions forScene(const Scene& scene, const Field& field);
};

// Milliseconds and counts, per call (the phases of thesis Table 3.1).
struct TesselatorStats {
  double simulateMs = 0.0;   // last update(): differential transforms, hash, compute and integration
  double addDeleteMs = 0.0;  // last update(): sequential additions and deletions
  double meshMs = 0.0;       // last triangulate()
  size_t particles = 0;
  size_t triangles = 0;      // last triangulate()
  size_t boundaryEdges = 0;  // last triangulate(): edges with one triangle left after hole repair
  size_t filledTriangles = 0;  // last triangulate(): triangles added by the hole repair
  size_t unfilledLoops = 0;    // last triangulate(): boundary loops the repair could not close
  size_t openEdges = 0;        // last triangulate(): the particle triangulation's edges with one triangle after repair
  size_t pinchedVertices = 0;  // last triangulate(): its vertices whose triangles form more than one fan
  size_t foldedTriangles = 0;  // last triangulate(): triangles still winding against their corners' normals
  size_t surfaceRowVertices = 0;  // last triangulate(): vertices the hole repair added on the surface (after the
                                  // particles' own in the mesh; 0 for the fallback)
  size_t cutOffParts = 0;      // last triangulate(): solid parts the particles' closed triangulation meshed apart from
                               // the solid the field joins them to (a head capped at the neck), by Marching Cubes;
                               // the render then falls back. Checked only with closedFallback (0 without)
  bool fallback = false;       // last triangulate(): the mesh is the Marching Cubes fallback (see closedFallback)
  uint64_t fallbacks = 0;      // triangulations that fell back, since reset
  uint64_t updates = 0;        // total update() calls since reset
  bool cancelled = false;      // the last settle() was stopped by options.cancel
  // Totals since reset.
  uint64_t fissions = 0, deaths = 0, fusions = 0, strays = 0, reseeds = 0;
  uint64_t transfers = 0;         // ownership changes (always to the owner or one of its blend neighbours)
  uint64_t blockedTransfers = 0;  // field owner was not a blend neighbour: ownership kept
};

// Read-only view of the particles, for display and tests (valid until the next non-const call).
struct ParticleView {
  std::span<const glm::vec3> positions;  // world space, metres
  std::span<const glm::vec3> normals;    // unit, outward (down the field gradient) at the last compute phase
  std::span<const float> radii;          // repulsion radius sigma, metres
  std::span<const int32_t> owners;       // owning primitive (Field index), -1 if none
  std::span<const uint64_t> ids;         // stable per-particle id (new ids for fissioned particles)
  size_t size() const { return positions.size(); }
};

class Tesselator {
 public:
  explicit Tesselator(const TesselatorOptions& options = {});
  ~Tesselator();
  Tesselator(const Tesselator&) = delete;
  Tesselator& operator=(const Tesselator&) = delete;

  const TesselatorOptions& options() const { return options_; }

  // Drops every particle; the next update() seeds from every primitive of the field.
  void reset();

  // One particle update against the cache's current field. If the skeleton was updated since the last call and
  // differential transforms are on, particles first move with their owners' joints (call once per skeleton update;
  // a skipped generation loses that frame's differential). The character must be the one the cache was built from.
  void update(const SkeletonCache& skeleton);
  // One update against a bare field (flat use; no hierarchy, no differential transforms, any owner may take over).
  void update(const Field& field);

  // Triangulates the current particles into `mesh` (replaced): one vertex per particle, in particle order, projected
  // onto the surface with a Newton step; outward normals; colours blended over colorWidth. Then, where the hole
  // repair joined the two rims of a tube too thin for the particles (a neck or wrist about as thick as their spacing)
  // through rows of new vertices on the surface, those stats().surfaceRowVertices vertices (this render's only).
  // Uses the field of the last update (which must have happened). If that triangulation still has a hole or a pinched
  // vertex after repair and options().closedFallback is set, `mesh` is instead Marching Cubes of the field at cell
  // desiredRadius (closed and manifold; not one vertex per particle) and stats().fallback is set.
  void triangulate(Mesh& mesh);

  // updatesPerRender updates then one triangulation.
  void frame(const SkeletonCache& skeleton, Mesh& mesh);

  // Carried texture coordinates (options().textureMode == Carried; otherwise a no-op). Call after textureMesh() on
  // the mesh triangulate() just made. Each particle keeps a (layer, u, v) for each of its vertex's two layers: a layer
  // it already carries keeps its coordinates, a new one (a particle born by seeding, or a layer it did not have)
  // takes its generator's mapping of the vertex; the mesh gets them all in mesh.layerTexcoords (and texcoords).
  // Between calls the coordinates ride with the particles: unchanged through the differential transforms (the skin
  // moves, the texture with it); when a particle moves over the surface on its own (repulsion, projection) they
  // change by what the layer's generator maps that step to (the texture must not be dragged along); a fission's two
  // particles get the parent's, moved by what their offsets map to; fusion keeps the survivor's. A surface-row vertex
  // (after the particles' in the mesh) takes a nearby particle's coordinates moved by what the generator maps the step
  // from that particle's vertex to it, so the texture runs on across the rows. A mesh that is the Marching Cubes
  // fallback, or one without layers, is left projective (a character without textures costs nothing).
  // Deterministic for any thread count, as every pass of the tesselator.
  void carryTexcoords(Mesh& mesh);

  // Runs updates until settled (particle count stable to 1% over 10 updates, and the particle triangulation closed
  // without the fallback: no hole, no pinch, no part cut off) or maxUpdates; returns the number of updates run.
  // Leaves the last triangulation in `mesh`. Reports progress and stops on cancel as the options say (then `mesh` is
  // empty, stats().cancelled is set, and the particles are those of the last complete update, so a later call goes
  // on from there).
  int settle(const SkeletonCache& skeleton, Mesh& mesh, int maxUpdates = 400);

  ParticleView particles() const;
  const TesselatorStats& stats() const { return stats_; }

  struct State;  // opaque: defined in the implementation

 private:
  void step(const Field& field, const SkeletonCache* skeleton);
  TesselatorOptions options_;
  TesselatorStats stats_;
  std::unique_ptr<State> s_;
};

// The worst distance from points to a triangle mesh (metres): for each point the distance to the nearest triangle,
// searched within `searchRadius` (a point with no triangle that near counts as searchRadius). For accuracy reports.
double worstDistanceToMesh(const Mesh& mesh, std::span<const glm::vec3> points, float searchRadius);

}  // namespace imps
