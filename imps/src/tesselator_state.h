// SPDX-License-Identifier: MIT
// Internal state shared by the tesselator's source files (simulation, seeding, triangulation). Not installed.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glm/glm.hpp>

#include "imps/character.h"
#include "imps/field.h"
#include "imps/tesselator.h"
#include "imps/uniform_hash.h"

namespace imps {

inline constexpr size_t kMaxNeighbours = 48;  // neighbour list slots per particle (nearest first, within nbrRadius)
inline constexpr size_t kMaxRepulsion = 40;   // the repulsion uses at most this many nearest (within queryRadius)
inline constexpr float kFanRadius = 2.5f;     // triangulation fans look this far (units of desiredRadius)
inline constexpr size_t kMaxFan = 24;         // tangent-plane fan entries per particle
inline constexpr size_t kMaxHalfEdges = 24;   // outgoing half-edges per vertex during assembly
inline constexpr size_t kMaxFuse = 4;        // fusion partners remembered per particle
inline constexpr size_t kChunk = 64;          // particles per parallel task: the fixed work partition

// Deterministic random numbers: one stream per (seed, particle id, update, purpose); splitmix64 finaliser.
inline uint64_t mixBits(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
inline float uniform01(uint64_t seed, uint64_t id, uint64_t update, uint64_t purpose) {
  const uint64_t h = mixBits(mixBits(mixBits(seed ^ 0x5bd1e995ull) ^ id) ^ (update * 4 + purpose));
  return float(h >> 40) * (1.0f / 16777216.0f);
}

// Sort key ordering (distance squared >= 0, index) pairs: non-negative floats order like their bit patterns.
inline uint64_t sortKey(float d2, uint32_t j) {
  uint32_t bits;
  std::memcpy(&bits, &d2, sizeof bits);
  return (uint64_t(bits) << 32) | j;
}

inline bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Two unit vectors b0, b1 with b0 x b1 = n (n unit).
inline void tangentBasis(const glm::vec3& n, glm::vec3& b0, glm::vec3& b1) {
  const glm::vec3 a =
      std::fabs(n.x) < 0.6f ? glm::vec3(1, 0, 0) : (std::fabs(n.y) < 0.6f ? glm::vec3(0, 1, 0) : glm::vec3(0, 0, 1));
  b0 = glm::normalize(glm::cross(a, n));
  b1 = glm::cross(n, b0);
}

struct Tesselator::State {
  // Particles, structure of arrays, in particle order.
  std::vector<glm::vec3> pos, vel, grad, nrm;
  std::vector<float> sigma, sigmaRate, energy, value;
  std::vector<float> scale;  // computeForces -> addAndDeleteParticles: each particle's spacing, in desiredRadius
  std::vector<int32_t> owner;
  std::vector<uint64_t> id;
  std::vector<uint8_t> dead;
  // The neighbour list: for each particle every other within max(queryRadius, kFanRadius desiredRadius) (the
  // kMaxNeighbours nearest in a crowd), in the hash's deterministic visiting order. Built once per particle
  // configuration by findNeighbours() and shared by the compute phase, the fusion test and the triangulation's fans;
  // nbrValid says it matches the current positions and particle order (cleared whenever a particle moves, is born or
  // dies).
  std::vector<uint32_t> nbr;
  std::vector<uint8_t> nbrCount;
  bool nbrValid = false;
  // Field samples (value, gradient, owner) taken by triangulate()'s vertex pass at the particles' positions, reused
  // by the next compute phase when nothing moved in between and the field is the same (skeleton generation).
  std::vector<float> cacheValue;
  std::vector<glm::vec3> cacheGrad;
  std::vector<int32_t> cacheOwner;
  bool cacheValid = false;
  uint64_t cacheStamp = ~0ull;
  uint64_t fieldStamp = ~0ull;  // skeleton generation of the last update's field; ~0 for a bare field (no cache)
  std::vector<uint32_t> fuse;  // per particle its kMaxFuse nearest at the compute phase (the fusion candidates)
  std::vector<uint8_t> fuseCount;

  // Carried texture coordinates (TextureMode::Carried on a textured mesh; tesselator_texcoords.cpp). While `carry`,
  // every particle has two slots 2i and 2i+1: texLayer (a layer of the mesh, -1: none) and texUv. texGens are the
  // layers' generators at the current pose (world space; from the skeleton cache at every update, else from the last
  // carried mesh). Empty otherwise.
  bool carry = false;
  size_t carryLayers = 0;  // the mesh's layer count the slots refer to
  std::vector<int32_t> texLayer;
  std::vector<glm::vec2> texUv;
  std::vector<TexGen> texGens;
  std::vector<glm::vec3> prevPos;  // the positions before this update's integration (the advection's step)

  UniformHashGrid hash;
  std::vector<FieldScratch> scratch;  // one per chunk (reused)

  const Field* field = nullptr;
  const Character* character = nullptr;  // set when updated from a skeleton: who may take a particle over
  uint64_t lastGeneration = ~0ull;
  uint64_t nextId = 0;
  uint64_t update = 0;
  float eHat = 1.0f;  // desired energy per particle (hexagonal packing at spacing desiredRadius)
  // Coming to rest on a still field (tesselator.cpp, kStillAfter): whether the field moved before this update, the
  // updates since it last moved, the particle counts of the last updates, the calm updates so far (0: moving; fission,
  // fusion and death stop while > 0) and the factor on this update's step and radius rate.
  bool fieldMoved = true;
  uint32_t stillUpdates = 0, calm = 0;
  std::vector<size_t> recentCounts;
  float stepScale = 1.0f;
  // The last triangulate() left the particles' own triangulation open or pinched (before any fallback): the particles
  // must not come to rest on it (a frozen hole would stay for good); set by triangulate(), read by the rest schedule.
  bool lastMeshOpen = false;
  // Pass J: the number of solid pieces of the last closed triangulation that Marching Cubes found to be the field's
  // own (no part cut off). A triangulation of that many pieces is not checked again: a part cut off adds a piece.
  size_t fieldPieces = 1;

  // Reorder scratch.
  std::vector<glm::vec3> tmpV;
  std::vector<float> tmpF;
  std::vector<int32_t> tmpI;
  std::vector<uint64_t> tmpU;
  std::vector<glm::vec2> tmpUv;

  // Triangulation buffers.
  std::vector<glm::vec3> vpos, vcol;
  std::vector<uint8_t> vok;  // the particle is close enough to the surface to be a mesh vertex this render
  std::vector<int32_t> fan;
  std::vector<uint8_t> fanCount;
  std::vector<uint8_t> fanUnanimous;  // per fan slot k: triangle (i, fan[k], fan[k+1]) is in all three corners' fans
  std::vector<uint8_t> fanRepeat;     // per particle: a label repeats among its unanimous slots (sequential fallback)
  std::vector<uint32_t> cand;  // per particle up to kMaxFan candidate triangles (a, b, votes)
  std::vector<uint8_t> candCount;
  std::vector<uint8_t> candVotes;  // per particle: bit v set if one of its candidates has v votes
  std::vector<uint32_t> heTo;
  std::vector<uint8_t> heCount;
  std::vector<uint32_t> heThird;  // per half-edge slot a -> heTo: the third corner of its triangle (kept with heTo)
  std::vector<uint8_t> dropSlot;  // per half-edge slot: its triangle is in a pinched vertex's smaller fan
  std::vector<uint32_t> holeTo;
  std::vector<uint8_t> holeCount, holeUsed, openUp, openOut;
  std::vector<uint64_t> dropEdges;  // repairHoles -> removeAround: directed edges (a << 32 | b) whose triangles go
  std::vector<uint32_t> loop, tris;
  std::vector<uint32_t> loops;       // repairHoles: one round's closed hole loops, concatenated
  std::vector<size_t> loopStart;     // repairHoles: loop k is loops[loopStart[k], loopStart[k + 1])
  std::vector<uint8_t> loopBridged;  // repairHoles: per loop, joined to another by bridgeTubes
  std::vector<uint32_t> strip;       // bridgeLoops: the strip's triangles before they are added
  std::vector<uint32_t> ring;        // bridgeLoops: rows of the band's particles round the tube, in order
  std::vector<size_t> ringStart;     // bridgeLoops: row k of several is ring[ringStart[k], ringStart[k + 1])
  std::vector<uint32_t> pocket;      // closePockets: one sheet's particles
  std::vector<uint8_t> pocketSeen;   // closePockets: per particle, taken into a sheet of this side
  std::vector<uint64_t> stripEdges;  // pocketHull: the hull's half-edges, sorted
  std::vector<uint32_t> band;        // bridgeLoops: the particles without triangles between two rims
  std::vector<uint8_t> inBand;       // per particle, bandParticles' mark (all 0 between calls)
  std::vector<uint32_t> heTri;   // unfoldTriangles: per half-edge slot the index of its triangle in s.tris / 3
  std::vector<uint8_t> heTriKnown;  // unfoldTriangles: per vertex, heTri is valid for its half-edges
  bool heTriAll = false;            // unfoldTriangles: heTri is valid for every half-edge
  std::vector<uint32_t> folded;  // unfoldTriangles: the triangles winding against their corners' normals
  FieldScratch foldScratch;      // E and H: the field prepared over the vertices' box, on first use after pass A
  bool foldScratchReady = false;
  FieldScratch rowScratch;  // surfaceRows: the field prepared round one tube (never a chunk's: see computeForces)
  // The last triangulation's surface-row vertices (after the particles' in its mesh): for each, the particle whose
  // carried texture coordinates it follows (carryTexcoords). Kept until the next triangulate().
  std::vector<uint32_t> addedFrom;
  std::vector<size_t> chunkUnanimous;  // voteTriangles: per chunk its emitted unanimous triangles, then offsets
  std::vector<size_t> chunkOpen;       // assembleTriangles: per chunk its open directed edges
  // Per-update scratch (step's phases).
  std::vector<uint64_t> chunkTransfers, chunkBlocked;  // ownership changes made and refused, per chunk
  std::vector<Rigid> differentials;                    // per primitive: its motion since the last update

  explicit State(const TesselatorOptions& o) : hash(o.cubeSize, o.bitsPerDim) {}
  size_t size() const { return pos.size(); }
  // The triangulation's vertices: the particles (pass A), then the vertices the hole repair put on the surface for
  // this render only (surface rows, pass E), at the end of s.vpos, s.nrm and s.vcol until triangulate() returns.
  size_t vertexCount() const { return vpos.size(); }
  void resizeParticles(size_t n);
  // Appends a particle on the surface (grad: field gradient there).
  // Appends a particle. Takes its vectors by value: callers pass elements of the arrays this grows.
  void add(glm::vec3 p, glm::vec3 g, float s, int32_t ownerIndex);
  // Drops the carried coordinates (the particles carry none until the next carryTexcoords()).
  void dropTexcoords();
};

// Sorts the particles into hash-bucket order (every per-particle array is permuted) and rebuilds the neighbour list
// (tesselator.cpp). Parallel, deterministic for any thread count.
void findNeighbours(Tesselator::State& s, const TesselatorOptions& o);

// Places particles on the field's surface from every primitive (tesselator_seed.cpp).
void seedParticles(Tesselator::State& s, const Field& field, const TesselatorOptions& o);

// The surface area of primitive p's own d = 1 surface (m^2): a sphere's, an ellipsoid's as a sphere of its mean radius,
// a segment's as its two end spheres plus a cylinder of the larger radius. Seeding's point budget and the
// scene-derived particle spacing (TesselatorOptions::forField) both estimate from it.
double primitiveSurfaceArea(const Primitive& p);

// ---- The triangulation's passes (tesselator_mesh.cpp), in the order Tesselator::triangulate runs them. Each needs
// the neighbour list (findNeighbours) and s.field; each reads the previous passes' outputs and writes only its own.
// Parallel ones write per-particle outputs only (deterministic for any thread count).

// A. vertices (parallel): s.vpos (the particle moved onto the surface by up to three Newton steps), s.nrm (unit,
// outward), s.vcol (colours blended over colorWidth) and s.vok (1: close enough to the surface to be a vertex this
// render); the field samples at the particles into s.cacheValue/Grad/Owner for the next compute phase.
void projectVertices(Tesselator::State& s, const TesselatorOptions& o);
// B. fans (parallel): s.fan / s.fanCount, per particle with s.vok the labels of its Voronoi cell's edges among its
// projected neighbours in its tangent plane, counter-clockwise seen from outside (-1: the bounding octagon), so
// consecutive labels (a, b) make the Delaunay triangle (i, a, b). Particles without s.vok get an empty fan.
void buildFans(Tesselator::State& s, const TesselatorOptions& o);
// C. votes (parallel): each fan triangle (i, a, b) is proposed by each corner whose fan holds it; its smallest
// proposer emits it into s.cand (a, b, votes in 1..3). s.fanUnanimous marks the slots held by all three corners,
// s.fanRepeat the particles where a label repeats among those; s.chunkUnanimous[c + 1] counts chunk c's 3-vote ones.
void voteTriangles(Tesselator::State& s, const TesselatorOptions& o);
// D. assembly: s.tris from the candidates, 3 votes first, then 2, then 1, each in particle order, keeping a triangle
// only if none of its directed edges is taken (no edge ever has more than two triangles; orientations agree).
// Fills the half-edge table (s.heTo / s.heCount) and s.openOut. Returns the directed edges without a twin.
size_t assembleTriangles(Tesselator::State& s, const TesselatorOptions& o);
// E. hole repair: up to four rounds of closing boundary loops of at most maxHoleLoop edges: the two rims of a tube
// left open all round (on pieces not joined across an edge) are joined by a strip (through one ring, or up to
// kMaxRows rows, of the particles left between them when they are far apart, else through rows of new vertices on the
// surface: addVertex, after the particles in s.vpos / s.nrm / s.vcol, with s.addedFrom); a rim facing two pieces is
// first split between them (forkTube); every other loop is capped by ear clipping; loops it cannot close are opened
// up (the triangles around them removed) for the next round. Keeps `boundary` (directed edges without a twin) up to
// date; returns the loops left unfilled. The passes from here on take s.vertexCount() vertices; triangulate() cuts
// the arrays back to the particles' when it is done.
size_t repairHoles(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary);
// F. pinches: a vertex whose triangles form more than one fan (two disks touching at a point, which the edge-based
// assembly and repair cannot see) loses the triangles of its smaller fans (twice; the third time every triangle
// around it) and the holes are repaired again (E). A pinch whose fans lie on different pieces (vertices joined by
// triangles, never through a pinched one: it is all that joins them) loses every triangle around it from the first
// time, so that the repair can join the two holes as a tube's rims instead of capping one. Returns the pinched
// vertices left (0: the triangulation is a 2-manifold wherever it is closed).
size_t unpinchVertices(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary, size_t& unfilled);
// I. pockets (after F): particles left in no triangle that make up, on their own, a small closed sheet too curved for
// the fans (a blob, or an air pocket enclosed by the solid, 4 to kMaxPocket particles whose neighbours are 60-120
// degrees apart; the fans take no neighbour in front of the tangent plane, so a pocket's particles never connect)
// get its convex hull, oriented with the field (turned inside out for a pocket), when every hull triangle agrees with
// the sum of its corners' normals and lies within kBridgeOff desiredRadius of the surface (stripFits). The particles of one
// sheet are those joined by chords on its side (onePocketSheet), none of them so joined to a particle in a
// triangle. Each hull is a closed 2-manifold of its own, so the triangulation stays closed and manifold. Returns the
// sheets closed.
inline constexpr size_t kMaxPocket = 16;  // particles in a small closed sheet, at most
size_t closePockets(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary);
// Counts the vertices whose triangles do not form a single fan (a disk, or a half-disk on the boundary), marking them
// in s.openUp and the half-edge slots of all but their largest fan in s.dropSlot. Parallel; reads the half-edge table.
size_t markPinchedVertices(Tesselator::State& s, const TesselatorOptions& o);
// H. folds (sequential; only on a closed, manifold triangulation): a triangle winding against its corners' field
// normals (a fold, in the concave creases where the corners' tangent planes disagree) gets the first repair that
// unfolds it without folding another: an edge flip (it and its neighbour become the quad's other diagonal), else the
// removal of a corner (its ring triangulated again), else the retriangulation of a disk-shaped region grown around it
// (retriangulateAround). Each replaces a disk by a disk with the same boundary, so the mesh stays closed and
// manifold. In triangle order, up to three rounds. Returns the folds left.
size_t unfoldTriangles(Tesselator::State& s);
// J. parts cut off (only on a closed, manifold triangulation): the pieces of s.tris (triangles joined by corners,
// which on a manifold is by edges) that face outward (positive signed volume; an air pocket's faces inward). More
// than one: triangulate() asks Marching Cubes whether the field joins them (matchComponents), as it does for a head
// capped at a neck whose ring of particles made no triangle, unless the count is the one it last found to be the
// field's own (State::fieldPieces). One union-find pass.
size_t solidPieces(const Tesselator::State& s);
// The output: one vertex per particle, then the surface rows' (s.vpos, s.nrm, s.vcol clamped to [0, 1]), and s.tris.
void writeMesh(const Tesselator::State& s, const TesselatorOptions& o, Mesh& mesh);
// G. the fallback output: Marching Cubes of s.field at cell desiredRadius (closed and manifold by construction).
void writeFallbackMesh(const Tesselator::State& s, const TesselatorOptions& o, Mesh& mesh);

// ---- The update's phases (tesselator.cpp), in the order Tesselator::step runs them after findNeighbours.

// Compute (parallel, fixed partition): per particle its field sample (the cache of the last triangulation when
// `cached`), stray test (s.dead), ownership transfer to a blend neighbour (counted in s.chunkTransfers /
// chunkBlocked), its kMaxFuse nearest (s.fuse), repulsion velocity constrained to the surface (s.vel), energy and
// radius rate, all in units of the local spacing (s.scale, every particle's first: 1 but on thin parts). Sizes every
// per-particle output and clears s.dead first. Reads others' positions, radii and spacings; writes only particle i's
// outputs.
void computeForces(Tesselator::State& s, const Field& field, const TesselatorOptions& o, bool cached);
// Integration (parallel): the clamped step along s.vel and the radius rate (the radius clamped in units of s.scale),
// then one Newton step back onto the surface along the compute phase's gradient; particles carried off the surface
// are marked dead. Needs computeForces' outputs.
void integrateParticles(Tesselator::State& s, const Field& field, const TesselatorOptions& o);
// Carried coordinates (tesselator_texcoords.cpp; only while s.carry): after integration, each particle's coordinates
// move by what its layer's generator maps its step (s.prevPos -> s.pos) to. Parallel, each particle writes only its
// own slots.
void advectTexcoords(Tesselator::State& s, const TesselatorOptions& o);
// The generators of a carried mesh's layers at the skeleton's current pose (no change if their count differs).
void updateTexGens(Tesselator::State& s, const SkeletonCache& skeleton);
// Additions and deletions (sequential, particle order): strays, fusion, death, fission (children appended; radii and
// lengths in units of s.scale), then compaction in particle order. Counts into stats. Needs computeForces' outputs.
void addAndDeleteParticles(Tesselator::State& s, const TesselatorOptions& o, TesselatorStats& stats);

}  // namespace imps
