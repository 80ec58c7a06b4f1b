// SPDX-License-Identifier: MIT
// The particle tesselator's triangulation (thesis 3.7, made closed): tangent-plane Delaunay fans voted on by their
// three corners, manifold assembly, then hole repair.
//
// Based on: K. Russell, "IMPS", MIT 1999, 3.7 (neighbours sorted by angle in the tangent plane); P. Crossno and
//           E. Angel, "Isosurface Extraction Using Particle Systems", 1997; the local Delaunay consensus idea of
//           M. Gopi, S. Krishnan and C. Silva, "Surface Reconstruction based on Lower Dimensional Localized Delaunay
//           Triangulation", 2000.
//
// Passes:
//  A. vertices (parallel): Newton projection of each particle onto the surface, normal, colour over colorWidth;
//  B. fans (parallel): the Voronoi cell of the particle among its projected neighbours in its tangent plane; each
//     pair of consecutive Voronoi edges is a Delaunay triangle of the particle's 1-ring, counter-clockwise seen from
//     outside;
//  C. votes (parallel): a triangle is proposed by each corner whose fan holds it; the smallest proposer emits it with
//     its vote count (1 to 3);
//  D. assembly (particle order, 3 votes first, then 2, then 1): a triangle is kept only if none of its directed edges
//     is already used, so no edge ever has more than two triangles and orientations agree;
//  E. hole repair (sequential): boundary loops (directed edges whose twin is missing) are walked; the two rims of a
//     tube are joined by strips, every other loop is closed by ear clipping, choosing each time the ear with the
//     shortest new edge whose normal agrees with the vertex normals.
//  F. pinches: vertices whose triangles form more than one fan lose the smaller fans; the holes are repaired again;
//  I. pockets (after F): particles in no triangle that make up a small closed sheet of their own (an air pocket's wall,
//     its neighbours in front of each other's tangent planes, which the fans never join) get its convex hull;
//  G. the fallback: a triangulation still open or pinched is replaced by Marching Cubes (never a hole);
//  H. folds (sequential, closed triangulations only): a triangle winding against the field normal at its centroid
//     gets an edge flip, else one of its corners is removed and its ring re-triangulated, when that unfolds it.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>

#include "disjoint_sets.h"
#include "imps/check.h"
#include "imps/marching_cubes.h"
#include "imps/parallel.h"
#include "tesselator_state.h"

namespace imps {
namespace {

// A particle farther than this (desiredRadius) from the surface, or whose projection does not converge in three
// Newton steps, is no vertex this render: it was carried into a limb it does not blend with and dies as a stray.
constexpr float kVertexOff = 0.5f;
constexpr size_t kFanCandidates = 32;  // the nearest this many agreeing neighbours cut a particle's cell
// A fan candidate agrees with the particle when their normals are less than 72 degrees apart (n_i . n_j >= 0.3), or
// less than 90 degrees apart where the two lie on a convex arc, each behind the other's tangent plane: the neighbours
// around a limb resolved by only four to seven particles (the biped's wrists, hands and feet at ~900 particles). The
// far side of a thin limb (normals opposed) never connects, nor does a separate surface in front of the particle.
constexpr float kFanAgreement = 0.3f;
constexpr float kFanAgreementConvex = 0.0f;
constexpr float kNearFan = 1.5f;       // fan candidates nearer than this (desiredRadius) are sorted up front

// Four lanes of GCC's portable vector extension: the hot tests below look at four cell corners, half-edges or fan
// slots at once, without data-dependent branches.
using F32x4 = float __attribute__((vector_size(16)));
using I32x4 = int32_t __attribute__((vector_size(16)));
template <class V, class T>
V load4(const T* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
bool any(I32x4 v) {  // as two 64-bit halves: cheaper than four lane extractions
  uint64_t half[2];
  std::memcpy(half, &v, sizeof half);
  return (half[0] | half[1]) != 0;
}
constexpr I32x4 kLane = {0, 1, 2, 3};

// The Voronoi cell of the origin among 2D points (halfplane clipping), as the cyclic list of the labels of its
// edges, counter-clockwise; label -1 marks the initial bounding octagon. The corner arrays are padded to a multiple of
// four with copies of corner 0, so that the tests run four corners at a time.
struct Cell {
  static constexpr int kMax = 64;
  // Two buffers, swapped by each cutting clip (no copy back); x, y, lab point at the current one.
  static constexpr int kSlack = 8;  // room for whole four-lane reads and writes past the last corner
  alignas(16) float bx[2][kMax + kSlack];
  alignas(16) float by[2][kMax + kSlack];
  alignas(16) int32_t bl[2][kMax + kSlack];
  float* x = bx[0];
  float* y = by[0];
  int32_t* lab = bl[0];
  int cur = 0;
  int n = 0;
  float rad2 = 0.0f;  // the largest squared corner distance (maintained by init and clip)

  Cell() = default;
  Cell(const Cell&) = delete;
  Cell& operator=(const Cell&) = delete;

  void init(float r) {
    // The unit octagon's corners, computed once.
    static const struct Octagon {
      float c[8], s[8];
      Octagon() {
        for (int k = 0; k < 8; ++k) c[k] = std::cos(0.78539816f * float(k)), s[k] = std::sin(0.78539816f * float(k));
      }
    } octagon;
    n = 8;
    for (int k = 0; k < 8; ++k) {
      x[k] = r * octagon.c[k];
      y[k] = r * octagon.s[k];
      lab[k] = -1;
    }
    rad2 = radius2();
  }
  // Pads the corners to a multiple of four and returns the largest squared corner distance.
  float radius2() {
    x[n] = x[n + 1] = x[n + 2] = x[0];
    y[n] = y[n + 1] = y[n + 2] = y[0];
    F32x4 m = {};
    for (int k = 0; k < n; k += 4) {
      const F32x4 vx = load4<F32x4>(x + k), vy = load4<F32x4>(y + k), d = vx * vx + vy * vy;
      m = m > d ? m : d;
    }
    return std::max(std::max(m[0], m[1]), std::max(m[2], m[3]));
  }
  // Keeps the part with qx * X + qy * Y <= (qx^2 + qy^2) / 2 (closer to the origin than to q).
  // Returns whether anything was cut.
  bool clip(float qx, float qy, int32_t label) {
    const float h = 0.5f * (qx * qx + qy * qy);
    // Most candidates do not reach the cell: test every corner first, and write only when something is cut.
    alignas(16) float dist[kMax + kSlack];
    const F32x4 vqx = F32x4{} + qx, vqy = F32x4{} + qy, vh = F32x4{} + h;
    I32x4 cuts = {};
    for (int k = 0; k < n; k += 4) {
      const F32x4 d = vqx * load4<F32x4>(x + k) + vqy * load4<F32x4>(y + k) - vh;
      std::memcpy(dist + k, &d, sizeof d);
      cuts |= d > F32x4{};
    }
    if (!any(cuts)) return false;
    float* ox = bx[1 - cur];
    float* oy = by[1 - cur];
    int32_t* ol = bl[1 - cur];
    int m = 0;
    // (The helpers are forced inline: the clip is the fans' inner loop, and GCC's inlining budget for this file
    // otherwise leaves them as calls whenever the file grows.)
    auto put = [&](float px, float py, int32_t l) __attribute__((always_inline)) {
      ox[m] = px, oy[m] = py, ol[m++] = l;
    };
    // The point where edge k -> k1 crosses the line.
    auto cross = [&](int k, int k1, int32_t l) __attribute__((always_inline)) {
      const float dc = dist[k], dn = dist[k1];
      const float t = dc / (dc - dn);
      put(x[k] + t * (x[k1] - x[k]), y[k] + t * (y[k1] - y[k]), l);
    };
    // Corners [from, to) unchanged; up to eight as whole lanes (slack).
    auto copy = [&](int from, int to) __attribute__((always_inline)) {
      if (to - from <= 8) {
        auto lanes = [&](auto* dst, const auto* src) __attribute__((always_inline)) {  // 32-bit lanes, as bits
          const I32x4 a = load4<I32x4>(src + from), b = load4<I32x4>(src + from + 4);
          std::memcpy(dst + m, &a, sizeof a);
          std::memcpy(dst + m + 4, &b, sizeof b);
        };
        lanes(ox, x);
        lanes(oy, y);
        lanes(ol, lab);
        m += to - from;
      } else {
        for (int k = from; k < to; ++k) put(x[k], y[k], lab[k]);
      }
    };
    // The cell is convex, so the cut-off corners are one cyclic run [o1, o2]: the new cell is the rest, with an exit
    // point on the edge into the run (labelled by the cut) and an entry point on the edge out of it (labelled by the
    // edge it lies on), in the corners' order. Only if rounding breaks the run up (or everything is cut) are the
    // edges walked one by one; both ways give the same corners.
    uint64_t out = 0;
    for (int k = 0; k < n; ++k) out |= uint64_t(dist[k] > 0.0f) << k;
    const uint64_t all = n == 64 ? ~uint64_t(0) : (uint64_t(1) << n) - 1;
    const uint64_t before = ((out << 1) | (out >> (n - 1))) & all;  // bit k: corner k - 1 is cut
    const uint64_t after = ((out >> 1) | (out << (n - 1))) & all;   // bit k: corner k + 1 is cut
    const uint64_t first = out & ~before, last = out & ~after;
    auto single = [](uint64_t bits) { return bits != 0 && (bits & (bits - 1)) == 0; };
    if (n < kMax - 3 && single(first) && single(last)) {
      const int o1 = std::countr_zero(first), o2 = std::countr_zero(last);
      const int e = o1 == 0 ? n - 1 : o1 - 1, next = o2 + 1 == n ? 0 : o2 + 1;
      if (e < o2) {  // the run lies inside [0, n)
        copy(0, e + 1);
        cross(e, o1, label);
        cross(o2, next, lab[o2]);
        copy(o2 + 1, n);
      } else {  // the run wraps around corner 0
        cross(o2, next, lab[o2]);
        copy(o2 + 1, e + 1);
        cross(e, o1, label);
      }
    } else {
      for (int k = 0; k < n && m < kMax - 2; ++k) {
        const int k1 = k + 1 == n ? 0 : k + 1;
        if (dist[k] <= 0.0f) {
          put(x[k], y[k], lab[k]);
          if (dist[k1] > 0.0f) cross(k, k1, label);
        } else if (dist[k1] <= 0.0f) {
          cross(k, k1, lab[k]);
        }
      }
    }
    n = m;
    cur = 1 - cur;
    x = ox, y = oy, lab = ol;
    rad2 = radius2();
    return true;
  }
};

static_assert(kMaxHalfEdges >= 8);

bool hasHalfEdge(const Tesselator::State& s, uint32_t a, uint32_t b) {
  const uint32_t* to = &s.heTo[size_t(a) * kMaxHalfEdges];
  const size_t n = s.heCount[a];
  if (n <= 8) {  // the common case (about six)
    const I32x4 want = I32x4{} + int32_t(b), count = I32x4{} + int32_t(n);
    return any(((load4<I32x4>(to) == want) & (kLane < count)) | ((load4<I32x4>(to + 4) == want) & (kLane + 4 < count)));
  }
  for (size_t k = 0; k < n; ++k)
    if (to[k] == b) return true;
  return false;
}

// Adds triangle (a, b, c) if none of its directed edges exists yet (and there is room): manifold by construction.
// With `boundary`, keeps that count of directed edges without a twin up to date, and flags the corners in s.openOut
// (they may have an open outgoing edge now).
bool addTriangle(Tesselator::State& s, uint32_t a, uint32_t b, uint32_t c, size_t* boundary = nullptr) {
  if (a == b || b == c || c == a) return false;
  if (hasHalfEdge(s, a, b) || hasHalfEdge(s, b, c) || hasHalfEdge(s, c, a)) return false;
  if (s.heCount[a] >= kMaxHalfEdges || s.heCount[b] >= kMaxHalfEdges || s.heCount[c] >= kMaxHalfEdges) return false;
  if (boundary) {  // each new edge either closes its twin's boundary or opens one of its own
    const size_t twins = size_t(hasHalfEdge(s, b, a)) + size_t(hasHalfEdge(s, c, b)) + size_t(hasHalfEdge(s, a, c));
    *boundary = *boundary + (3 - twins) - twins;
    s.openOut[a] = s.openOut[b] = s.openOut[c] = 1;
  }
  const size_t ka = size_t(a) * kMaxHalfEdges + s.heCount[a]++, kb = size_t(b) * kMaxHalfEdges + s.heCount[b]++,
               kc = size_t(c) * kMaxHalfEdges + s.heCount[c]++;
  s.heTo[ka] = b, s.heThird[ka] = c;
  s.heTo[kb] = c, s.heThird[kb] = a;
  s.heTo[kc] = a, s.heThird[kc] = b;
  s.tris.push_back(a);
  s.tris.push_back(b);
  s.tris.push_back(c);
  return true;
}

static_assert(kMaxFan >= 9);

// Does particle a's fan hold the consecutive pair (b, c)?
bool fanHas(const Tesselator::State& s, uint32_t a, uint32_t b, uint32_t c) {
  const int32_t* f = &s.fan[size_t(a) * kMaxFan];
  const size_t m = s.fanCount[a];
  if (m <= 8) {  // the common case (five to seven): slot k holds b and slot k + 1 (cyclically) holds c
    const I32x4 wb = I32x4{} + int32_t(b), wc = I32x4{} + int32_t(c), last = I32x4{} + int32_t(m) - 1;
    const I32x4 wrap = I32x4{} + (f[0] == int32_t(c) ? -1 : 0);
    auto pairs = [&](int k) {
      const I32x4 lane = kLane + k;
      const I32x4 next = ((lane < last) & (load4<I32x4>(f + k + 1) == wc)) | ((lane == last) & wrap);
      return (load4<I32x4>(f + k) == wb) & (lane <= last) & next;
    };
    return any(pairs(0) | pairs(4));
  }
  for (size_t k = 0; k < m; ++k)
    if (f[k] == int32_t(b) && f[k + 1 == m ? 0 : k + 1] == int32_t(c)) return true;
  return false;
}

// Collects the boundary loops' directed edges: b -> a for every used a -> b whose twin is missing. Only vertices
// flagged in s.openOut can have such edges; they are visited in particle order.
void collectHoles(Tesselator::State& s) {
  const size_t n = s.vertexCount();
  s.holeCount.assign(n, 0);
  for (uint32_t a = 0; a < n; ++a) {
    if (!s.openOut[a]) continue;
    for (size_t k = 0; k < s.heCount[a]; ++k) {
      const uint32_t b = s.heTo[size_t(a) * kMaxHalfEdges + k];
      if (hasHalfEdge(s, b, a)) continue;
      if (s.holeCount[b] < 4) s.holeTo[size_t(b) * 4 + s.holeCount[b]++] = a;
    }
  }
}

// Whether a hole loop may be filled: it turns counter-clockwise seen from outside (its vector area along the
// vertices' mean normal is positive), as the loop around a hole does. A clockwise one runs around an island of
// triangles inside a larger hole (or between overlapping triangles, in a saddle), and filling it would cap the island
// with a second, flipped layer; it is opened up instead, by the triangles across its edges only (repairHoles): in the
// neck's saddle at ~900 particles several such loops lie side by side, and opening up every triangle round their
// vertices merged them into one band round the neck that no strip could join, and the head was capped off. Only loops
// whose normals all lie within 90 degrees of their mean (a patch that projects onto one plane) get this verdict: one
// wrapped around a thin limb has no meaningful plane and is filled as before.
bool fillable(const Tesselator::State& s, const std::vector<uint32_t>& loop) {
  glm::vec3 normal(0.0f), area(0.0f);
  for (size_t k = 0; k < loop.size(); ++k) {
    normal += s.nrm[loop[k]];
    area += glm::cross(s.vpos[loop[k]], s.vpos[loop[(k + 1) % loop.size()]]);
  }
  for (uint32_t v : loop)
    if (glm::dot(s.nrm[v], normal) < 0.0f) return true;
  return glm::dot(area, normal) > 0.0f;
}

// Removes directed edge a -> b from a's half-edge table (keeping the others' order).
void removeHalfEdge(Tesselator::State& s, uint32_t a, uint32_t b) {
  uint32_t* to = &s.heTo[size_t(a) * kMaxHalfEdges];
  uint32_t* third = &s.heThird[size_t(a) * kMaxHalfEdges];
  const size_t n = s.heCount[a];
  size_t k = 0;
  while (k < n && to[k] != b) ++k;
  if (k == n) return;
  std::copy(to + k + 1, to + n, to + k);
  std::copy(third + k + 1, third + n, third + k);
  --s.heCount[a];
}

// Removes every triangle with a corner marked in openUp or a directed edge in s.dropEdges, with its half-edges, keeping
// `boundary` (directed edges without a twin) and s.openOut (a superset of the vertices with an open outgoing edge) up
// to date.
void removeAround(Tesselator::State& s, size_t& boundary) {
  std::sort(s.dropEdges.begin(), s.dropEdges.end());
  const auto dropped = [&](uint32_t a, uint32_t b) {
    return std::binary_search(s.dropEdges.begin(), s.dropEdges.end(), uint64_t(a) << 32 | b);
  };
  size_t w = 0;
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    const uint32_t c[3] = {s.tris[t], s.tris[t + 1], s.tris[t + 2]};
    const bool onRim = dropped(c[0], c[1]) || dropped(c[1], c[2]) || dropped(c[2], c[0]);
    if (!(s.openUp[c[0]] | s.openUp[c[1]] | s.openUp[c[2]]) && !onRim) {
      for (int k = 0; k < 3; ++k) s.tris[w + size_t(k)] = c[k];
      w += 3;
      continue;
    }
    for (int k = 0; k < 3; ++k) {  // an edge with a twin leaves the twin open; an open edge just goes
      const uint32_t a = c[k], b = c[(k + 1) % 3];
      removeHalfEdge(s, a, b);
      boundary = hasHalfEdge(s, b, a) ? boundary + 1 : boundary - 1;
      s.openOut[a] = 1;
    }
  }
  s.tris.resize(w);
}

// Particle i's vertex: up to three Newton steps from the particle onto the surface (vpos, nrm; vok whether it
// converged), caching the field sample at the particle itself for the next compute phase.
void projectVertex(Tesselator::State& s, const Field& field, float h, size_t i, FieldScratch& scratch,
                   FieldSample& fs, uint32_t& winner) {
  const float iso = field.iso();
  const glm::vec3 p = s.pos[i];
  glm::vec3 v = p;
  bool converged = false;
  for (int it = 0; it < 3; ++it) {
    fs = field.sample(v, scratch);
    if (it == 0) {  // at the particle itself: the next compute phase reuses it if nothing moves before it
      winner = scratch.lastWinner;
      s.cacheValue[i] = fs.value;
      s.cacheGrad[i] = fs.gradient;
      s.cacheOwner[i] = fs.owner;
    }
    const float g2 = glm::dot(fs.gradient, fs.gradient);
    // A particle this far off (carried into a limb it does not blend with, about to die as a stray) would
    // make a spike: it is left out of this render's triangulation and the gap is filled around it.
    if (!(g2 > 1e-20f) || (it == 0 && std::fabs(fs.value - iso) > kVertexOff * h * std::sqrt(g2))) break;
    s.nrm[i] = -fs.gradient / std::sqrt(g2);
    if (std::fabs(fs.value - iso) < 1e-5f * h * std::sqrt(g2)) {
      converged = true;
      break;
    }
    glm::vec3 d = (iso - fs.value) / g2 * fs.gradient;
    const float len = glm::length(d);
    if (len > 0.5f * h) d *= 0.5f * h / len;
    v += d;
    // A step this short leaves an error of order len^2 / curvature radius (< 1e-4 desiredRadius on any
    // surface the particles can resolve): no need to sample again. The particles are usually this close, as
    // the integration ended with a Newton step.
    if (len < 1e-2f * h) {
      converged = true;
      break;
    }
  }
  s.vok[i] = converged ? 1 : 0;  // else no vertex this render (see kVertexOff)
  s.vpos[i] = finite3(v) ? v : p;
}

// A vertex's colour at p (a particle's position, with its owner): primitive colours weighted by term^(1/colorWidth)
// over `winner`, the local blend set of `scratch` winning there (wider = smoother), so only primitives that blend
// there mix their colours; fs.color where no term is positive.
glm::vec3 vertexColor(const Field& field, float colorExp, glm::vec3 p, int32_t owner, const FieldScratch& scratch,
                      const FieldSample& fs, uint32_t winner) {
  glm::vec3 col(0.0f);
  float wsum = 0.0f;
  auto addColor = [&](uint32_t k) {
    const float t = field.blend().term(field.primitive(k).distance(p), field.param(k));
    const float base = field.blend().additive() ? t : t + 1.0f;
    if (base <= 0.0f) return;
    const float w = std::pow(base, colorExp);
    col += w * field.color(k);
    wsum += w;
  };
  if (owner >= 0 && scratch.setCount() > 0) {
    for (uint32_t m = scratch.setOffsets[winner]; m < scratch.setOffsets[winner + 1]; ++m)
      addColor(scratch.candidates[scratch.setMembers[m]]);
  } else {
    for (uint32_t k : scratch.candidates) addColor(k);
  }
  return wsum > 0.0f ? col / wsum : fs.color;
}

// Particle i's fan candidates into keys (near, sorted) and farKeys (far, unsorted): agreeing neighbours within rT,
// by (distance, index) (one 64-bit key: d2 > 0 orders like its bits). Returns the two counts.
std::pair<size_t, size_t> fanCandidates(const Tesselator::State& s, size_t i, float rT2, float nearT2,
                                        uint64_t* keys, uint64_t* farKeys) {
  const glm::vec3 p = s.vpos[i], nn = s.nrm[i];
  size_t nearCnt = 0, farCnt = 0;
  const uint32_t* nl = &s.nbr[i * kMaxNeighbours];
  for (size_t k = 0; k < s.nbrCount[i]; ++k) {  // branch-free: which are kept, and where, is unpredictable
    const uint32_t j = nl[k];
    const glm::vec3 d = s.vpos[j] - p;
    const float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    const float agree = glm::dot(s.nrm[j], nn);
    const size_t convex = size_t(glm::dot(d, nn) <= 0.0f) & size_t(glm::dot(d, s.nrm[j]) >= 0.0f);
    const size_t ok = size_t(s.vok[j] != 0) & size_t(d2 <= rT2) & size_t(d2 > 0.0f) &
                      (size_t(agree >= kFanAgreement) | (size_t(agree >= kFanAgreementConvex) & convex));
    const size_t near = size_t(d2 <= nearT2);
    const uint64_t key = sortKey(d2, j);
    keys[nearCnt] = key;
    farKeys[farCnt] = key;
    nearCnt += ok & near;
    farCnt += ok & (near ^ 1);
  }
  std::sort(keys, keys + nearCnt);
  return {nearCnt, farCnt};
}

// Particle i's fan: its Voronoi cell among the candidates projected into its tangent plane, as the cyclic list of
// the cell edges' labels (repeats merged).
void buildFan(Tesselator::State& s, size_t i, float h, Cell& cell) {
  const float rT = kFanRadius * h, rT2 = rT * rT;
  const float nearT2 = kNearFan * kNearFan * h * h;
  uint64_t keys[kMaxNeighbours], farKeys[kMaxNeighbours];
  // Only the near candidates (within kNearFan) are sorted up front; the far ones are sorted only if the cell is
  // still large enough for them to cut it (rarely: the cell shrinks to about 0.6 desiredRadius once the first ring
  // is clipped). The processing order is the full sort's.
  const auto [nearCnt, farCnt] = fanCandidates(s, i, rT2, nearT2, keys, farKeys);
  const glm::vec3 p = s.vpos[i];
  bool farSorted = false;
  glm::vec3 b0, b1;
  tangentBasis(s.nrm[i], b0, b1);
  cell.init(0.5f * rT);
  float r2 = cell.rad2;
  const size_t total = std::min(nearCnt + farCnt, kFanCandidates);
  for (size_t k = 0; k < total; ++k) {
    if (k == nearCnt && !farSorted) {
      // The near ones are used up: the far ones are needed only if they can still cut the cell.
      if (nearT2 > 4.0f * r2) break;
      std::sort(farKeys, farKeys + farCnt);
      std::copy(farKeys, farKeys + std::min(farCnt, kFanCandidates - nearCnt), keys + nearCnt);
      farSorted = true;
    }
    const uint32_t j = uint32_t(keys[k]);
    const uint32_t bits = uint32_t(keys[k] >> 32);
    float d2;
    std::memcpy(&d2, &bits, sizeof d2);
    if (d2 > 4.0f * r2) break;  // sorted by distance: no farther point can cut the cell
    const glm::vec3 d = s.vpos[j] - p;
    float x = glm::dot(d, b0), y = glm::dot(d, b1);
    const float l2 = x * x + y * y;
    if (l2 < 1e-12f * h * h) continue;
    const float lift = std::sqrt(d2 / l2);  // keep the 3D distance: a local geodesic-like unfolding
    x *= lift, y *= lift;
    if (cell.clip(x, y, int32_t(j))) r2 = cell.rad2;
  }
  int32_t* f = &s.fan[i * kMaxFan];
  size_t m = 0;
  for (int k = 0; k < cell.n && m < kMaxFan; ++k)
    if (m == 0 || f[m - 1] != cell.lab[k]) f[m++] = cell.lab[k];
  if (m > 1 && f[m - 1] == f[0]) --m;
  s.fanCount[i] = uint8_t(m);
}

// Particle i's votes: its fan slots' triangles it emits (it is their smallest proposer) into s.cand with their vote
// counts, which slots are unanimous, and whether a label repeats among those. Returns the unanimous ones emitted.
size_t voteFan(Tesselator::State& s, size_t i) {
  const int32_t* f = &s.fan[i * kMaxFan];
  uint8_t* unanimous = &s.fanUnanimous[i * kMaxFan];
  const size_t m = s.fanCount[i];
  size_t out = 0, unanimousOut = 0;
  uint8_t votes = 0;  // bit v: a candidate with v votes
  bool repeat = false;
  uint64_t seen = 0;  // labels of the unanimous slots so far, hashed to 64 bits
  for (size_t k = 0; k < m; ++k) {
    unanimous[k] = 0;
    if (m < 2) continue;
    const int32_t a = f[k], b = f[k + 1 == m ? 0 : k + 1];
    if (a < 0 || b < 0 || a == b) continue;
    const uint32_t ua = uint32_t(a), ub = uint32_t(b), ui = uint32_t(i);
    const bool byA = fanHas(s, ua, ub, ui), byB = fanHas(s, ub, ui, ua);
    if (byA && byB) {
      unanimous[k] = 1;
      const uint64_t bit = uint64_t(1) << (ua & 63u);
      if (seen & bit)  // maybe a repeat: check exactly
        for (size_t q = 0; q < k; ++q) repeat = repeat || (unanimous[q] && f[q] == a);
      seen |= bit;
    }
    uint32_t minProposer = ui;
    if (byA) minProposer = std::min(minProposer, ua);
    if (byB) minProposer = std::min(minProposer, ub);
    if (minProposer != ui) continue;
    uint32_t* slot = &s.cand[(i * kMaxFan + out++) * 3];
    slot[0] = ua;
    slot[1] = ub;
    slot[2] = 1u + uint32_t(byA) + uint32_t(byB);
    votes |= uint8_t(1u << slot[2]);
    unanimousOut += slot[2] == 3 ? 1 : 0;
  }
  s.candCount[i] = uint8_t(out);
  s.candVotes[i] = votes;
  s.fanRepeat[i] = repeat ? 1 : 0;
  return unanimousOut;
}

// Particle i's unanimous triangles and half-edges, written without the sequential test (see assembleTriangles):
// its outgoing edges are the first labels of its unanimous slots; the triangles go to tri. Returns the open ones.
size_t placeUnanimous(Tesselator::State& s, size_t i, uint32_t*& tri) {
  const int32_t* f = &s.fan[i * kMaxFan];
  const uint8_t* unanimous = &s.fanUnanimous[i * kMaxFan];
  const size_t m = s.fanCount[i];
  uint32_t* to = &s.heTo[i * kMaxHalfEdges];
  uint32_t* from = &s.heThird[i * kMaxHalfEdges];  // the twins' start vertices: f[q + 1] of each unanimous slot q
  size_t cnt = 0;
  for (size_t k = 0; k < m; ++k)
    if (unanimous[k]) {
      IMPS_DCHECK_LT(cnt, kMaxHalfEdges);
      from[cnt] = uint32_t(f[k + 1 == m ? 0 : k + 1]);
      to[cnt++] = uint32_t(f[k]);
    }
  s.heCount[i] = uint8_t(cnt);
  size_t open = 0;
  for (size_t k = 0; k < cnt; ++k) {
    bool twin = false;
    for (size_t q = 0; q < cnt; ++q) twin |= from[q] == to[k];
    open += twin ? 0 : 1;
  }
  s.openOut[i] = open > 0 ? 1 : 0;
  for (size_t k = 0; k < s.candCount[i]; ++k) {
    const uint32_t* slot = &s.cand[(i * kMaxFan + k) * 3];
    if (slot[2] != 3) continue;
    tri[0] = uint32_t(i), tri[1] = slot[0], tri[2] = slot[1];
    tri += 3;
  }
  return open;
}

// Whether vertex v's triangles form more than one fan; if so marks v in s.openUp and the half-edge slots of all but
// its largest fan in s.dropSlot (writes only v's entries). Around v, the corner of slot k spans heTo .. heThird; the
// next corner is the slot whose heTo is this one's heThird. Each slot has at most one successor and predecessor, so
// the corners fall into paths and cycles: fans. One fan (a disk, or a half-disk on the boundary) is manifold.
size_t markIfPinched(Tesselator::State& s, size_t v) {
  const size_t m = s.heCount[v];
  s.openUp[v] = 0;
  if (m < 2) return 0;
  const uint32_t* to = &s.heTo[v * kMaxHalfEdges];
  const uint32_t* third = &s.heThird[v * kMaxHalfEdges];
  uint8_t next[kMaxHalfEdges], hasPredecessor[kMaxHalfEdges] = {}, fanOf[kMaxHalfEdges];
  size_t links = 0;
  for (size_t k = 0; k < m; ++k) {
    size_t q = 0;
    while (q < m && to[q] != third[k]) ++q;
    next[k] = uint8_t(q);
    if (q < m) hasPredecessor[q] = 1, ++links;
    fanOf[k] = 0xff;
  }
  if (links + 1 == m) {  // one path, or a cycle plus a path: walk from the path's start
    size_t k = 0;
    while (hasPredecessor[k]) ++k;
    size_t visited = 1;
    for (size_t cur = next[k]; cur < m; cur = next[cur]) ++visited;
    if (visited == m) return 0;
  } else if (links == m) {  // cycles only: one iff the walk from slot 0 visits all
    size_t visited = 1;
    for (size_t cur = next[0]; cur != 0 && visited <= m; cur = next[cur]) ++visited;
    if (visited == m) return 0;
  }
  size_t fans = 0, fanSize[kMaxHalfEdges] = {};
  for (int cycles = 0; cycles < 2; ++cycles)  // paths from their first corner, then the cycles
    for (size_t k = 0; k < m; ++k) {
      if (fanOf[k] != 0xff || (cycles == 0 && hasPredecessor[k])) continue;
      for (size_t cur = k; cur < m && fanOf[cur] == 0xff; cur = next[cur]) fanOf[cur] = uint8_t(fans), ++fanSize[fans];
      ++fans;
    }
  const size_t keep = size_t(std::max_element(fanSize, fanSize + fans) - fanSize);
  for (size_t k = 0; k < m; ++k) s.dropSlot[v * kMaxHalfEdges + k] = fanOf[k] != keep;
  s.openUp[v] = 1;
  return 1;
}

// Walks the hole loop that starts with start's e-th hole edge along unused hole edges into s.loop (marking them
// used). Returns whether it came back to start within 4 maxHoleLoop steps.
bool walkHoleLoop(Tesselator::State& s, uint32_t start, size_t e, int maxHoleLoop) {
  s.loop.clear();
  s.loop.push_back(start);
  s.holeUsed[size_t(start) * 4 + e] = 1;
  uint32_t cur = s.holeTo[size_t(start) * 4 + e];
  while (s.loop.size() <= size_t(4 * maxHoleLoop)) {
    if (cur == start) return true;
    s.loop.push_back(cur);
    size_t pick = 4;
    for (size_t q = 0; q < s.holeCount[cur]; ++q)
      if (!s.holeUsed[size_t(cur) * 4 + q]) {
        pick = q;
        break;
      }
    if (pick == 4) return false;
    s.holeUsed[size_t(cur) * 4 + pick] = 1;
    cur = s.holeTo[size_t(cur) * 4 + pick];
  }
  return false;
}

// The ear of loop L to clip next: (L[k], L[k+1], L[k+2]) with the shortest new edge whose normal agrees with the
// vertex normals, among those that use no taken half-edge. L.size() if none.
size_t bestEar(const Tesselator::State& s, const std::vector<uint32_t>& L, float h) {
  size_t best = L.size();
  float bestScore = 1e30f;
  for (size_t k = 0; k < L.size(); ++k) {
    const uint32_t a = L[k], b = L[(k + 1) % L.size()], c = L[(k + 2) % L.size()];
    if (a == c || a == b || b == c || hasHalfEdge(s, c, a) || hasHalfEdge(s, a, b) || hasHalfEdge(s, b, c)) continue;
    const glm::vec3 pa = s.vpos[a], pb = s.vpos[b], pc = s.vpos[c];
    const glm::vec3 cr = glm::cross(pb - pa, pc - pa);
    const float cl = glm::length(cr);
    const glm::vec3 nv = s.nrm[a] + s.nrm[b] + s.nrm[c];
    const float agree = cl > 0.0f ? glm::dot(cr, nv) / (cl * std::max(glm::length(nv), 1e-6f)) : -1.0f;
    const glm::vec3 diag = pc - pa;
    const float score = glm::dot(diag, diag) / (h * h) + 4.0f * (1.0f - agree) + (agree < 0.0f ? 100.0f : 0.0f);
    if (score < bestScore) {
      bestScore = score;
      best = k;
    }
  }
  return best;
}

// Closes s.loop by ear clipping: ear (a, b, c) uses the hole edges a->b, b->c and adds c->a. Returns whether the
// loop was closed completely (else its vertices are what is left in s.loop).
bool clipEars(Tesselator::State& s, float h, size_t& boundary) {
  auto& L = s.loop;
  while (L.size() > 3) {
    const size_t best = bestEar(s, L, h);
    if (best == L.size()) break;
    const size_t k1 = (best + 1) % L.size();
    addTriangle(s, L[best], L[k1], L[(best + 2) % L.size()], &boundary);
    L.erase(L.begin() + std::ptrdiff_t(k1));
  }
  return L.size() == 3 && addTriangle(s, L[0], L[1], L[2], &boundary);
}

// The field sample at p, with s.foldScratch prepared over the vertices' box on first use (p inside that box: a point
// between vertices). Shared by the hole repair and the fold pass (the vertices do not move in between).
FieldSample sampleAmongVertices(Tesselator::State& s, const glm::vec3& p) {
  if (!s.foldScratchReady) {
    Box box;
    for (const glm::vec3& v : s.vpos) box.extend(v);
    s.field->prepare(box, s.foldScratch);
    s.foldScratchReady = true;
  }
  return s.field->sample(p, s.foldScratch);
}

// A hole loop's shape: its centroid, vector area (along the outward normal of a cap over it: a hole loop turns
// counter-clockwise seen from outside) and mean distance of its vertices from the centroid.
struct LoopShape {
  glm::vec3 centroid{0.0f}, area{0.0f};
  float radius = 0.0f;
};
LoopShape loopShape(const Tesselator::State& s, const uint32_t* L, size_t m) {
  LoopShape shape;
  for (size_t k = 0; k < m; ++k) {
    shape.centroid += s.vpos[L[k]];
    shape.area += 0.5f * glm::cross(s.vpos[L[k]], s.vpos[L[(k + 1) % m]]);
  }
  shape.centroid /= float(m);
  for (size_t k = 0; k < m; ++k) shape.radius += glm::length(s.vpos[L[k]] - shape.centroid) / float(m);
  return shape;
}

// Whether loops a and b can be the two rims of a tube the triangulation left open all the way round (a neck, wrist or
// ankle whose ring of particles made no triangle), by their shapes: close together (centroids within twice the larger
// mean radius) and facing each other (the caps ear clipping would put over them face each other). Symmetric.
bool facingRims(const LoopShape& a, const LoopShape& b) {
  const glm::vec3 d = b.centroid - a.centroid;
  const float reach = 2.0f * std::max(a.radius, b.radius);
  return glm::dot(d, d) < reach * reach && glm::dot(a.area, d) > 0.0f && glm::dot(b.area, d) < 0.0f;
}

// Whether the solid runs between two facing rims: their centroids and the midpoint are inside (F > iso). Two bodies
// with facing holes, or an arm against the hip, have air between them.
bool solidBetween(Tesselator::State& s, const LoopShape& a, const LoopShape& b) {
  const float iso = s.field->iso();
  return sampleAmongVertices(s, a.centroid).value > iso && sampleAmongVertices(s, b.centroid).value > iso &&
         sampleAmongVertices(s, 0.5f * (a.centroid + b.centroid)).value > iso;
}

// Appends to s.strip a strip of triangles joining hole loops A and B (the rims of one tube, running opposite ways round
// it), A walked forwards and B backwards, each step taking the cheaper of the two next triangles: (a_i, a_i+1, b_j)
// uses A's hole edge a_i -> a_i+1, (b_j-1, b_j, a_i) B's b_j-1 -> b_j, and consecutive triangles share their rung
// both ways, so the strip closes the hole exactly. Disjoint loops start at their closest pair of vertices. Loops
// that touch at one vertex v (what is left of the tube is one triangle wide there) make a disk: the strip starts with
// (b_v-1, v, a_v+1) and ends with (a_v-1, v, b_v+1). Returns false (appending nothing) if they share more vertices.
bool appendStrip(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, float h) {
  const float invH2 = 1.0f / (h * h);
  size_t shared = 0, i = 0, j = 0;
  for (size_t p = 0; p < na; ++p)
    for (size_t q = 0; q < nb; ++q)
      if (A[p] == B[q]) ++shared, i = p, j = q;
  if (shared > 1) return false;
  const auto a = [&](size_t k) { return A[k % na]; };
  const auto b = [&](size_t k) { return B[k % nb]; };
  const auto dist2 = [&](uint32_t u, uint32_t v) {
    const glm::vec3 d = s.vpos[u] - s.vpos[v];
    return glm::dot(d, d);
  };
  i += na, j += nb;  // indices stay positive when walked back
  size_t stepsA = na, stepsB = nb;
  if (shared == 1) {
    s.strip.insert(s.strip.end(), {b(j - 1), b(j), a(i + 1)});
    ++i, --j;
    stepsA = na - 2, stepsB = nb - 2;
  } else {
    float best = 1e30f;
    for (size_t p = 0; p < na; ++p)
      for (size_t q = 0; q < nb; ++q)
        if (dist2(A[p], B[q]) < best) best = dist2(A[p], B[q]), i = p + na, j = q + nb;
  }
  // A step's cost: its new rung's length (in desiredRadius) squared, plus how far the triangle's normal turns from
  // its corners' normals, as bestEar scores an ear.
  const auto cost = [&](uint32_t u, uint32_t v, uint32_t w, uint32_t rung0, uint32_t rung1) {
    const glm::vec3 cr = glm::cross(s.vpos[v] - s.vpos[u], s.vpos[w] - s.vpos[u]);
    const glm::vec3 nv = s.nrm[u] + s.nrm[v] + s.nrm[w];
    const float cl = glm::length(cr);
    const float agree = cl > 0.0f ? glm::dot(cr, nv) / (cl * std::max(glm::length(nv), 1e-6f)) : -1.0f;
    return dist2(rung0, rung1) * invH2 + 4.0f * (1.0f - agree) + (agree < 0.0f ? 100.0f : 0.0f);
  };
  for (size_t ia = 0, jb = 0; ia < stepsA || jb < stepsB;) {
    if (jb == stepsB ||
        (ia < stepsA && cost(a(i), a(i + 1), b(j), a(i + 1), b(j)) <= cost(b(j - 1), b(j), a(i), a(i), b(j - 1)))) {
      s.strip.insert(s.strip.end(), {a(i), a(i + 1), b(j)});
      ++i, ++ia;
    } else {
      s.strip.insert(s.strip.end(), {b(j - 1), b(j), a(i)});
      --j, ++jb;
    }
  }
  if (shared == 1) s.strip.insert(s.strip.end(), {a(i), a(i + 1), b(j)});
  return true;
}

constexpr float kBridgeOff = 2.0f;  // a strip triangle's centroid may lie this far off the surface (desiredRadius)
constexpr size_t kMaxRows = 6;      // rows of particles a tube's band is joined through, at most
constexpr size_t kMaxBand = 512;    // particles a band gathers, at most

// Whether every triangle of s.strip may be added: no degenerate or taken half-edge, room in the half-edge table, and
// its centroid within kBridgeOff desiredRadius of the surface.
bool stripFits(Tesselator::State& s, float h) {
  const float iso = s.field->iso(), maxOff = kBridgeOff * h;
  for (size_t t = 0; t < s.strip.size(); t += 3) {
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t u = s.strip[t + k], v = s.strip[t + (k + 1) % 3];
      if (u == v || hasHalfEdge(s, u, v) || size_t(s.heCount[u]) + 6 > kMaxHalfEdges) return false;
    }
    const glm::vec3 c = (s.vpos[s.strip[t]] + s.vpos[s.strip[t + 1]] + s.vpos[s.strip[t + 2]]) / 3.0f;
    const FieldSample fs = sampleAmongVertices(s, c);
    if (!(std::fabs(fs.value - iso) <= maxOff * glm::length(fs.gradient))) return false;
  }
  return true;
}

// Appends a vertex that is no particle (a surface row's, this render only) to every per-vertex array of passes D-H.
// `from`: a particle near it, whose carried texture coordinates it follows.
uint32_t addVertex(Tesselator::State& s, glm::vec3 p, glm::vec3 normal, glm::vec3 color, uint32_t from) {
  const size_t v = s.vertexCount(), n = v + 1;
  s.addedFrom.push_back(from < s.size() ? from : s.addedFrom[from - s.size()]);
  s.vpos.push_back(p);
  s.nrm.push_back(normal);
  s.vcol.push_back(color);
  s.vok.push_back(1);
  s.heTo.resize(n * kMaxHalfEdges);
  s.heThird.resize(n * kMaxHalfEdges);
  s.heCount.resize(n, 0);
  s.openOut.resize(n, 0);
  s.holeTo.resize(n * 4);
  s.holeCount.resize(n, 0);
  s.holeUsed.resize(n * 4, 0);
  s.openUp.resize(n, 0);
  return uint32_t(v);
}

// Drops the vertices from `first` on (added by addVertex, in no triangle yet).
void dropVerticesFrom(Tesselator::State& s, size_t first) {
  s.addedFrom.resize(first - s.size());
  s.vpos.resize(first);
  s.nrm.resize(first);
  s.vcol.resize(first);
  s.vok.resize(first);
  s.heCount.resize(first);
}

// A tube between hole loops A and B (bridgeTubes): the axis joining their centroids, and the angle round it.
struct Tube {
  glm::vec3 from, axis, b0, b1;
  float len2;
  float along(const glm::vec3& p) const { return glm::dot(p - from, axis) / len2; }  // 0 at A's centroid, 1 at B's
  float angle(const glm::vec3& p) const { return std::atan2(glm::dot(p - from, b1), glm::dot(p - from, b0)); }
  float offAxis(const glm::vec3& p) const { return glm::length(p - from - along(p) * axis); }
};

// The particles left without triangles between rims A and B into s.band. Near: the rims' neighbours between the rims
// (a fraction 0.15-0.85 of the way along the axis) within 1.5 rim radii of the axis, for one middle ring. Not near:
// from those on through neighbours, the whole band (0.1-0.9 of the way) within 1.25 times the rims' radius there (the
// radius interpolated along the axis, so that a wide rim does not reach into the shoulders), for several rows.
void bandParticles(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, const Tube& tube,
                   const LoopShape& sa, const LoopShape& sb, bool near) {
  const float reach = 1.5f * std::max(sa.radius, sb.radius);
  const auto inside = [&](uint32_t u) {
    const float t = tube.along(s.vpos[u]);
    const float limit = near ? reach : 1.25f * ((1.0f - t) * sa.radius + t * sb.radius);
    return s.heCount[u] == 0 && s.vok[u] && t > 0.0f && t < 1.0f && tube.offAxis(s.vpos[u]) < limit;
  };
  std::vector<uint32_t>& band = s.band;
  band.clear();
  s.inBand.resize(s.size(), 0);
  const auto add = [&](uint32_t u) {
    if (!s.inBand[u] && inside(u)) s.inBand[u] = 1, band.push_back(u);
  };
  for (const auto& [L, m] : {std::pair{A, na}, std::pair{B, nb}})
    for (size_t k = 0; k < m; ++k)
      if (L[k] < s.size())  // (a surface-row vertex has no neighbour list)
        for (size_t q = 0; q < s.nbrCount[L[k]]; ++q) add(s.nbr[size_t(L[k]) * kMaxNeighbours + q]);
  for (size_t head = 0; !near && head < band.size() && band.size() < kMaxBand; ++head)
    for (size_t q = 0; q < s.nbrCount[band[head]]; ++q) add(s.nbr[size_t(band[head]) * kMaxNeighbours + q]);
  for (uint32_t u : band) s.inBand[u] = 0;
  const float lo = near ? 0.15f : 0.1f;
  std::erase_if(band, [&](uint32_t u) {
    const float t = tube.along(s.vpos[u]);
    return t <= lo || t >= 1.0f - lo;
  });
}

// `rows` rows of s.band into s.ring / s.ringStart, row k round the tube at a fraction (k + 1) / (rows + 1) of the way
// from A to B. A row keeps one particle per sector of the angle round the axis (as many sectors as the rims have
// vertices on average), the one nearest its fraction, and runs round the axis the way B does. False if a row has fewer
// than three or leaves a gap of more than 120 degrees round the axis.
bool bandRows(Tesselator::State& s, size_t na, size_t nb, const Tube& tube, const LoopShape& sb, size_t rows) {
  const size_t sectors = std::max<size_t>(3, (na + nb) / 2);
  const auto angle = [&](uint32_t u) { return tube.angle(s.vpos[u]); };
  const auto sectorOf = [&](uint32_t u) {
    return std::min(sectors - 1, size_t((angle(u) + 3.14159265f) / 6.2831853f * float(sectors)));
  };
  s.ring.clear();
  s.ringStart.assign(1, 0);
  for (size_t r = 0; r < rows; ++r) {
    const float target = float(r + 1) / float(rows + 1), window = 0.5f / float(rows + 1);
    const auto off = [&](uint32_t u) { return std::fabs(tube.along(s.vpos[u]) - target); };
    const size_t first = s.ring.size();
    for (uint32_t u : s.band)
      if (rows == 1 || off(u) < window) s.ring.push_back(u);
    const auto row = s.ring.begin() + std::ptrdiff_t(first);
    std::sort(row, s.ring.end(), [&](uint32_t u, uint32_t v) {
      const size_t su = sectorOf(u), sv = sectorOf(v);
      return su != sv ? su < sv : off(u) < off(v);
    });
    s.ring.erase(std::unique(row, s.ring.end(), [&](uint32_t u, uint32_t v) { return sectorOf(u) == sectorOf(v); }),
                 s.ring.end());
    const size_t count = s.ring.size() - first;
    if (count < 3) return false;
    std::sort(row, s.ring.end(), [&](uint32_t u, uint32_t v) { return angle(u) < angle(v); });
    for (size_t k = 0; k < count; ++k) {
      float gap = angle(s.ring[first + (k + 1) % count]) - angle(s.ring[first + k]);
      if (gap <= 0.0f) gap += 6.2831853f;
      if (gap > 2.0943951f) return false;
    }
    // Sorted by angle a row runs counter-clockwise round the axis (b0 x b1 = axis); B does so when its vector area
    // points along the axis (rims facing each other: it points back along it, and B runs clockwise).
    if (glm::dot(sb.area, tube.axis) < 0.0f) std::reverse(row, s.ring.end());
    s.ringStart.push_back(s.ring.size());
  }
  return true;
}

constexpr float kRowSpacing = 1.5f;  // surface rows: at most this far apart along the tube (desiredRadius)
constexpr size_t kMinRowVertices = 4, kMaxRowVertices = 32;

// Loop L (m vertices) resampled at `count` points evenly spaced along its length, from its first vertex on, walked
// forwards or backwards; `nearest` gets the loop vertex nearer each point.
void resampleLoop(const Tesselator::State& s, const uint32_t* L, size_t m, bool backwards, size_t count, glm::vec3* out,
                  uint32_t* nearest) {
  const auto vertex = [&](size_t k) { return L[backwards ? (m - k % m) % m : k % m]; };
  const auto at = [&](size_t k) { return s.vpos[vertex(k)]; };
  float total = 0.0f;
  for (size_t k = 0; k < m; ++k) total += glm::length(at(k + 1) - at(k));
  size_t seg = 0;
  float walked = 0.0f;
  for (size_t q = 0; q < count; ++q) {
    const float want = total * float(q) / float(count);
    float len = glm::length(at(seg + 1) - at(seg));
    while (seg + 1 < m && walked + len < want) {
      walked += len;
      ++seg;
      len = glm::length(at(seg + 1) - at(seg));
    }
    const float f = len > 0.0f ? std::clamp((want - walked) / len, 0.0f, 1.0f) : 0.0f;
    out[q] = at(seg) + f * (at(seg + 1) - at(seg));
    nearest[q] = vertex(f < 0.5f ? seg : seg + 1);
  }
}

// Where the ray from `from` (inside the solid: F > iso) along unit `dir` first leaves it, within `reach`: stepped a
// quarter desiredRadius at a time, then regula falsi (Illinois) on F - iso to 1e-4 desiredRadius. False if `from` is
// not inside or the ray does not leave the solid within reach.
bool rayExit(const Field& field, FieldScratch& scratch, glm::vec3 from, glm::vec3 dir, float reach, float h,
             glm::vec3& out) {
  const float iso = field.iso(), step = 0.25f * h;
  float tIn = 0.0f, fIn = field.value(from, scratch) - iso;
  if (!(fIn > 0.0f)) return false;
  for (float t = step; t < reach + step; t += step) {
    const float f = field.value(from + t * dir, scratch) - iso;
    if (f > 0.0f) {
      tIn = t, fIn = f;
      continue;
    }
    float tOut = t, fOut = f;
    for (int it = 0; it < 16 && tOut - tIn > 1e-4f * h; ++it) {
      const float tm = tIn + (tOut - tIn) * fIn / (fIn - fOut);
      const float fm = field.value(from + tm * dir, scratch) - iso;
      if (fm > 0.0f) {
        tIn = tm, fIn = fm;
        fOut *= 0.5f;
      } else {
        tOut = tm, fOut = fm;
        fIn *= 0.5f;
      }
    }
    out = from + (fIn < -fOut ? tIn : tOut) * dir;  // the nearer to the surface
    return true;
  }
  return false;
}

// `rows` rows of new vertices on the surface between rims A and B (addVertex) into s.ring / s.ringStart, for rims
// whose band holds too few particles for rows of its own (a neck, wrist or ankle about as thin as the particle
// spacing: rings of three or four particles the fans could not mesh). Both rims are resampled at the same number of
// points evenly along their length (as many as space a ring of their mean radius about a desiredRadius apart,
// kMinRowVertices to kMaxRowVertices), B's way round, A's turned to lie closest to B's; row k takes the points a
// fraction (k + 1) / (rows + 1) of the way from A's to B's, each put on the surface where the ray from the tube's axis
// through it leaves the solid (rayExit), with the field's normal and the particles' colour rule there; each follows
// the rim vertex nearer its point on the nearer rim (s.addedFrom). False (adding nothing) if a ray finds no surface
// within its point's distance plus two desiredRadius (the axis point outside, or the solid running on) or a vertex's
// normal faces the axis (the ray reached another surface).
bool surfaceRows(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, const Tube& tube,
                 const LoopShape& sa, const LoopShape& sb, size_t rows, float h, float colorExp) {
  const Field& field = *s.field;
  const float radius = 0.5f * (sa.radius + sb.radius);
  const size_t count = std::clamp(size_t(std::lround(6.2831853f * radius / h)), kMinRowVertices, kMaxRowVertices);
  glm::vec3 ra[kMaxRowVertices], rb[kMaxRowVertices];
  uint32_t va[kMaxRowVertices], vb[kMaxRowVertices];
  resampleLoop(s, A, na, /*backwards=*/true, count, ra, va);
  resampleLoop(s, B, nb, /*backwards=*/false, count, rb, vb);
  size_t shift = 0;
  float best = FLT_MAX;
  for (size_t q = 0; q < count; ++q) {
    float cost = 0.0f;
    for (size_t k = 0; k < count; ++k) {
      const glm::vec3 d = ra[(k + q) % count] - rb[k];
      cost += glm::dot(d, d);
    }
    if (cost < best) best = cost, shift = q;
  }
  Box box;
  for (size_t k = 0; k < count; ++k) box.extend(ra[k]), box.extend(rb[k]);
  box.lo -= glm::vec3(3.0f * h);  // room for the rays beyond the rims' points
  box.hi += glm::vec3(3.0f * h);
  field.prepare(box, s.rowScratch);
  const size_t first = s.vertexCount();
  s.ring.clear();
  s.ringStart.assign(1, 0);
  for (size_t r = 0; r < rows; ++r) {
    const float t = float(r + 1) / float(rows + 1);
    for (size_t k = 0; k < count; ++k) {
      const glm::vec3 a = ra[(k + shift) % count], b = rb[k];
      const glm::vec3 towards = a + t * (b - a), centre = tube.from + tube.along(towards) * tube.axis;
      const float away = glm::length(towards - centre);
      glm::vec3 p;
      if (!(away > 0.0f) || !rayExit(field, s.rowScratch, centre, (towards - centre) / away, away + 2.0f * h, h, p))
        break;
      const FieldSample fs = field.sample(p, s.rowScratch);
      const glm::vec3 normal = -glm::normalize(fs.gradient);
      const glm::vec3 radial = p - tube.from - tube.along(p) * tube.axis;
      if (!(glm::dot(normal, radial) > -0.25f * glm::length(radial))) break;
      const glm::vec3 color = vertexColor(field, colorExp, p, fs.owner, s.rowScratch, fs, s.rowScratch.lastWinner);
      s.ring.push_back(
          addVertex(s, p, normal, glm::clamp(color, 0.0f, 1.0f), t < 0.5f ? va[(k + shift) % count] : vb[k]));
    }
    if (s.ring.size() != (r + 1) * count) break;
    s.ringStart.push_back(s.ring.size());
  }
  if (s.ringStart.size() == rows + 1) return true;
  dropVerticesFrom(s, first);
  return false;
}

// s.strip: A to the first row of s.ring, each row to the next, the last to B (appendStrip; each row's edges used once
// each way), when it fits (stripFits).
bool stripThroughRows(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, size_t rows,
                      float h) {
  s.strip.clear();
  const uint32_t* from = A;
  size_t nFrom = na;
  for (size_t r = 0; r < rows; ++r) {
    uint32_t* row = s.ring.data() + s.ringStart[r];
    const size_t nRow = s.ringStart[r + 1] - s.ringStart[r];
    if (!appendStrip(s, from, nFrom, row, nRow, h)) return false;
    std::reverse(row, row + nRow);  // the row's edges, the other way round for the next strip
    from = row, nFrom = nRow;
  }
  return appendStrip(s, from, nFrom, B, nb, h) && stripFits(s, h);
}

// Joins hole loops A and B, the rims of one tube (bridgeTubes), by a strip (appendStrip). When that strip would lie
// too far off the surface (the rims rings apart, where the particles between them made no triangle), through rows of
// those particles: one middle ring of the rims' neighbours (bandRows over the near band), else 2 to kMaxRows rows of
// the whole band (a neck opened up over several rings at the file's fidelity); else through surface rows of new
// vertices about kRowSpacing desiredRadius apart (surfaceRows). All or nothing: returns false, adding nothing, when no
// choice fits (stripThroughRows).
bool tubeStrip(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, const LoopShape& sa,
               const LoopShape& sb, float h, float colorExp) {
  s.strip.clear();
  bool fits = appendStrip(s, A, na, B, nb, h) && stripFits(s, h);
  Tube tube{sa.centroid, sb.centroid - sa.centroid, {}, {}, 0.0f};
  tube.len2 = glm::dot(tube.axis, tube.axis);
  if (!(tube.len2 > 0.0f)) return false;
  tangentBasis(tube.axis / std::sqrt(tube.len2), tube.b0, tube.b1);
  for (size_t rows = 1; rows <= kMaxRows && !fits; ++rows) {
    if (rows <= 2) bandParticles(s, A, na, B, nb, tube, sa, sb, rows == 1);
    fits = bandRows(s, na, nb, tube, sb, rows) && stripThroughRows(s, A, na, B, nb, rows, h);
  }
  // Surface rows about kRowSpacing apart, else one more, one fewer or two more: the first choice that fits.
  const size_t spaced =
      std::clamp<size_t>(size_t(std::ceil(std::sqrt(tube.len2) / (kRowSpacing * h))), 2, kMaxRows + 1) - 1;
  for (const size_t rows : {spaced, spaced + 1, spaced - 1, spaced + 2}) {
    if (fits) break;
    if (rows < 1 || rows > kMaxRows) continue;
    const size_t first = s.vertexCount();
    fits = surfaceRows(s, A, na, B, nb, tube, sa, sb, rows, h, colorExp) && stripThroughRows(s, A, na, B, nb, rows, h);
    if (!fits) dropVerticesFrom(s, first);
  }
  return fits;
}

bool bridgeLoops(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, const LoopShape& sa,
                 const LoopShape& sb, float h, float colorExp, size_t& boundary) {
  if (!tubeStrip(s, A, na, B, nb, sa, sb, h, colorExp)) return false;
  for (size_t t = 0; t < s.strip.size(); t += 3) addTriangle(s, s.strip[t], s.strip[t + 1], s.strip[t + 2], &boundary);
  return true;
}

// Joins hole loop A to two loops B and C on two more pieces (a body's hole opened round both a neck and a shoulder):
// A is split by a chord between two of its vertices into two loops of at least three vertices (the chord run once
// each way), the split and the assignment that put the halves' centroids nearest their partners', and each half is
// joined to its partner by tubeStrip. Both strips must fit, use no directed edge twice and leave every vertex room in
// its half-edge table; else nothing is added.
bool forkTube(Tesselator::State& s, const uint32_t* A, size_t na, const uint32_t* B, size_t nb, const uint32_t* C,
              size_t nc, const LoopShape& sb, const LoopShape& sc, float h, float colorExp, size_t& boundary) {
  std::vector<glm::vec3> prefix(na + 1, glm::vec3(0.0f));  // sums of A's positions, for the halves' centroids
  for (size_t k = 0; k < na; ++k) prefix[k + 1] = prefix[k] + s.vpos[A[k]];
  const auto centroid = [&](size_t i, size_t j) {  // of A[i..j] round the loop (i <= j < i + na, either may pass na)
    if (i >= na) i -= na, j -= na;
    const glm::vec3 sum = j < na ? prefix[j + 1] - prefix[i] : prefix[na] - prefix[i] + prefix[j - na + 1];
    return sum / float(j - i + 1);
  };
  float best = FLT_MAX;
  size_t bi = 0, bj = 0;
  bool swap = false;
  for (size_t i = 0; i < na; ++i)
    for (size_t j = i + 2; j + 2 <= i + na; ++j) {
      const glm::vec3 c1 = centroid(i, j), c2 = centroid(j, i + na);
      const float straight =
          glm::dot(c1 - sb.centroid, c1 - sb.centroid) + glm::dot(c2 - sc.centroid, c2 - sc.centroid);
      const float crossed = glm::dot(c1 - sc.centroid, c1 - sc.centroid) + glm::dot(c2 - sb.centroid, c2 - sb.centroid);
      if (std::min(straight, crossed) < best)
        best = std::min(straight, crossed), bi = i, bj = j, swap = crossed < straight;
    }
  if (best == FLT_MAX) return false;
  std::vector<uint32_t> half[2];
  for (size_t k = bi; k <= bj; ++k) half[0].push_back(A[k % na]);
  for (size_t k = bj; k <= bi + na; ++k) half[1].push_back(A[k % na]);
  const size_t first = s.vertexCount();
  std::vector<uint32_t> strips;
  for (int k = 0; k < 2; ++k) {
    const bool toB = (k == 0) != swap;
    const uint32_t* P = toB ? B : C;
    const size_t np = toB ? nb : nc;
    if (!tubeStrip(s, half[k].data(), half[k].size(), P, np, loopShape(s, half[k].data(), half[k].size()),
                   toB ? sb : sc, h, colorExp)) {
      dropVerticesFrom(s, first);
      return false;
    }
    strips.insert(strips.end(), s.strip.begin(), s.strip.end());
  }
  std::vector<uint64_t> edges;
  std::vector<uint8_t> added(s.vertexCount(), 0);
  for (size_t t = 0; t < strips.size(); t += 3)
    for (size_t k = 0; k < 3; ++k) {
      edges.push_back(uint64_t(strips[t + k]) << 32 | strips[t + (k + 1) % 3]);
      ++added[strips[t + k]];
    }
  std::sort(edges.begin(), edges.end());
  bool room = std::adjacent_find(edges.begin(), edges.end()) == edges.end();
  for (uint32_t v = 0; v < added.size() && room; ++v) room = size_t(s.heCount[v]) + added[v] <= kMaxHalfEdges;
  if (!room) {
    dropVerticesFrom(s, first);
    return false;
  }
  for (size_t t = 0; t < strips.size(); t += 3) addTriangle(s, strips[t], strips[t + 1], strips[t + 2], &boundary);
  return true;
}

// The round's hole loops into s.loops / s.loopStart: the closed ones of 3 to maxHoleLoop edges. The others are marked
// to be opened up (s.openUp); returns how many.
size_t collectLoops(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.vertexCount();
  size_t open = 0;
  s.loops.clear();
  s.loopStart.assign(1, 0);
  for (uint32_t start = 0; start < n; ++start)
    for (size_t e = 0; e < s.holeCount[start]; ++e) {
      if (s.holeUsed[size_t(start) * 4 + e]) continue;
      const bool closed = walkHoleLoop(s, start, e, o.maxHoleLoop);
      if (closed && s.loop.size() <= size_t(o.maxHoleLoop) && s.loop.size() >= 3) {
        s.loops.insert(s.loops.end(), s.loop.begin(), s.loop.end());
        s.loopStart.push_back(s.loops.size());
      } else {
        ++open;
        for (uint32_t v : s.loop) s.openUp[v] = 1;  // open up around it next round
      }
    }
  s.loopBridged.assign(s.loopStart.size() - 1, 0);
  return open;
}

// The slot of directed edge a -> b in a's half-edge table, SIZE_MAX if there is none.
size_t findHalfEdge(const Tesselator::State& s, uint32_t a, uint32_t b) {
  const uint32_t* to = &s.heTo[size_t(a) * kMaxHalfEdges];
  for (size_t k = 0; k < s.heCount[a]; ++k)
    if (to[k] == b) return size_t(a) * kMaxHalfEdges + k;
  return SIZE_MAX;
}

// The slot of directed edge a -> b in a's half-edge table (a -> b must exist).
size_t halfEdgeSlot(const Tesselator::State& s, uint32_t a, uint32_t b) {
  const size_t slot = findHalfEdge(s, a, b);
  IMPS_DCHECK(slot != SIZE_MAX);
  return slot;
}

// The pieces of the triangulation: its triangles (indices into s.tris / 3) joined across shared edges, so that pieces
// which touch at one vertex only (one on two loops, or a pinch) are pieces of their own. s.heTri gets every half-edge
// slot's triangle (unfoldTriangles builds its own again).
DisjointSets trianglePieces(Tesselator::State& s) {
  const size_t triangles = s.tris.size() / 3;
  DisjointSets pieces(triangles);
  s.heTri.resize(s.heTo.size());
  for (uint32_t t = 0; t < triangles; ++t)
    for (size_t k = 0; k < 3; ++k) s.heTri[halfEdgeSlot(s, s.tris[3 * t + k], s.tris[3 * t + (k + 1) % 3])] = t;
  for (uint32_t t = 0; t < triangles; ++t)
    for (size_t k = 0; k < 3; ++k) {
      const size_t twin = findHalfEdge(s, s.tris[3 * t + (k + 1) % 3], s.tris[3 * t + k]);
      if (twin != SIZE_MAX) pieces.unite(t, s.heTri[twin]);
    }
  return pieces;
}

// Joins the loops that are the two rims of one tube by strips (bridgeLoops), nearest pairs first, setting
// s.loopBridged: capping them would cut the limb off. Two loops are rims of one tube when they face each other
// (facingRims), lie on different pieces of the mesh (joining two holes of one piece would make a handle) and the solid
// runs between them (solidBetween). A loop that is the rim of two such tubes at once, to two more pieces, is first
// split between them (forkTube).
void bridgeTubes(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary) {
  const size_t loopCount = s.loopStart.size() - 1;
  if (loopCount < 2) return;
  std::vector<LoopShape> shapes(loopCount);
  for (size_t k = 0; k < loopCount; ++k)
    shapes[k] = loopShape(s, &s.loops[s.loopStart[k]], s.loopStart[k + 1] - s.loopStart[k]);
  // The pieces (trianglePieces), built on first need: most rounds have no facing pair.
  std::optional<DisjointSets> pieces;
  // A loop's piece: that of the triangle along its first edge (hole edge u -> w borders the triangle of w -> u).
  const auto pieceOf = [&](size_t k) {
    const size_t slot = findHalfEdge(s, s.loops[s.loopStart[k] + 1], s.loops[s.loopStart[k]]);
    IMPS_DCHECK(slot != SIZE_MAX);
    return slot == SIZE_MAX ? ~0u : pieces->find(s.heTri[slot]);
  };
  std::vector<std::pair<float, std::pair<uint32_t, uint32_t>>> pairs;
  for (uint32_t a = 0; a < loopCount; ++a)
    for (uint32_t b = a + 1; b < loopCount; ++b) {
      if (!facingRims(shapes[a], shapes[b]) || !solidBetween(s, shapes[a], shapes[b])) continue;
      if (!pieces) pieces.emplace(trianglePieces(s));
      const uint32_t pa = pieceOf(a), pb = pieceOf(b);
      if (pa == ~0u || pb == ~0u || pa == pb) continue;
      pairs.push_back({glm::length(shapes[b].centroid - shapes[a].centroid), {a, b}});
    }
  std::sort(pairs.begin(), pairs.end());
  // A loop with partners on two more pieces: one split strip to both (forkTube), nearest partners first.
  for (uint32_t a = 0; a < loopCount; ++a) {
    uint32_t partner[2] = {~0u, ~0u};
    for (const auto& [dist, bc] : pairs) {
      const uint32_t other = bc.first == a ? bc.second : bc.second == a ? bc.first : ~0u;
      if (other == ~0u || s.loopBridged[other] || pieceOf(other) == pieceOf(a)) continue;  // (an earlier fork)
      if (partner[0] == ~0u)
        partner[0] = other;
      else if (partner[1] == ~0u && pieceOf(other) != pieceOf(partner[0]))
        partner[1] = other;
    }
    if (s.loopBridged[a] || partner[1] == ~0u) continue;
    const auto loop = [&](uint32_t k) { return &s.loops[s.loopStart[k]]; };
    const auto size = [&](uint32_t k) { return s.loopStart[k + 1] - s.loopStart[k]; };
    const uint32_t b = partner[0], c = partner[1];
    if (forkTube(s, loop(a), size(a), loop(b), size(b), loop(c), size(c), shapes[b], shapes[c], o.desiredRadius,
                 1.0f / o.colorWidth, boundary)) {
      s.loopBridged[a] = s.loopBridged[b] = s.loopBridged[c] = 1;
      pieces->unite(pieceOf(a), pieceOf(b));
      pieces->unite(pieceOf(a), pieceOf(c));
    }
  }
  for (const auto& [dist, ab] : pairs) {
    const auto [a, b] = ab;
    if (s.loopBridged[a] || s.loopBridged[b] || pieceOf(a) == pieceOf(b)) continue;  // (joined by an earlier strip)
    const size_t na = s.loopStart[a + 1] - s.loopStart[a], nb = s.loopStart[b + 1] - s.loopStart[b];
    if (bridgeLoops(s, &s.loops[s.loopStart[a]], na, &s.loops[s.loopStart[b]], nb, shapes[a], shapes[b],
                    o.desiredRadius, 1.0f / o.colorWidth, boundary)) {
      s.loopBridged[a] = s.loopBridged[b] = 1;
      pieces->unite(pieceOf(a), pieceOf(b));
    }
  }
}

}  // namespace

// ---- The passes ----------------------------------------------------------------------------------------------

void projectVertices(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.size();
  const Field& field = *s.field;
  const float h = o.desiredRadius;
  const size_t chunks = (n + kChunk - 1) / kChunk;
  if (s.scratch.size() < chunks) s.scratch.resize(chunks);
  s.vpos.resize(n);
  s.vcol.resize(n);
  s.vok.resize(n);
  s.cacheValue.resize(n);
  s.cacheGrad.resize(n);
  s.cacheOwner.resize(n);
  const float colorExp = 1.0f / o.colorWidth;
  parallelFor(chunks, o.threads, [&](size_t c) {
    const size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
    FieldScratch& scratch = s.scratch[c];
    Box box;
    for (size_t i = begin; i < end; ++i) box.extend(s.pos[i]);
    box.lo -= glm::vec3(1.6f * h);  // room for the Newton steps below (each at most 0.5 desiredRadius)
    box.hi += glm::vec3(1.6f * h);
    field.prepare(box, scratch);
    for (size_t i = begin; i < end; ++i) {
      FieldSample fs;
      uint32_t winner = 0;
      projectVertex(s, field, h, i, scratch, fs, winner);
      s.vcol[i] = vertexColor(field, colorExp, s.pos[i], s.owner[i], scratch, fs, winner);
    }
  });
  s.cacheValid = true;
  s.cacheStamp = s.fieldStamp;
  s.foldScratchReady = false;  // the vertices moved: sampleAmongVertices prepares the field over their box again
}

void buildFans(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.size();
  s.fan.resize(n * kMaxFan);
  s.fanCount.resize(n);
  parallelFor((n + kChunk - 1) / kChunk, o.threads, [&](size_t c) {
    Cell cell;
    for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      if (s.vok[i]) buildFan(s, i, o.desiredRadius, cell);
      else s.fanCount[i] = 0;
    }
  });
}

void voteTriangles(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.size(), chunks = (n + kChunk - 1) / kChunk;
  s.cand.resize(n * kMaxFan * 3);
  s.candCount.resize(n);
  s.fanUnanimous.resize(n * kMaxFan);
  s.fanRepeat.resize(n);
  s.candVotes.resize(n);
  s.chunkUnanimous.assign(chunks + 1, 0);
  parallelFor(chunks, o.threads, [&](size_t c) {
    size_t unanimousOut = 0;
    for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) unanimousOut += voteFan(s, i);
    s.chunkUnanimous[c + 1] = unanimousOut;
  });
}

size_t assembleTriangles(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.size(), chunks = (n + kChunk - 1) / kChunk;
  s.heTo.resize(n * kMaxHalfEdges);
  s.heThird.resize(n * kMaxHalfEdges);
  s.heCount.resize(n);
  s.tris.clear();
  bool anyRepeat = false;
  for (size_t i = 0; i < n && !anyRepeat; ++i) anyRepeat = s.fanRepeat[i] != 0;
  // The boundary (directed edges without a twin) is counted here and kept up to date by every later addTriangle;
  // s.openOut flags (a superset of) the vertices with an open outgoing edge, for the repair's loop collection.
  size_t boundary = 0;
  s.openOut.resize(n);
  if (!anyRepeat) {
    // Each chunk writes its triangles at its offset: the same particle order as the sequential assembly. The
    // unanimous triangles at i are exactly i's unanimous slots (i, f[q], f[q + 1]), so i's outgoing edge i -> f[k]
    // has its twin f[k] -> i iff some unanimous slot q has f[q + 1] == f[k]: i's own fan tells.
    for (size_t c = 0; c < chunks; ++c) s.chunkUnanimous[c + 1] += s.chunkUnanimous[c];
    s.tris.resize(3 * s.chunkUnanimous[chunks]);
    s.chunkOpen.assign(chunks, 0);
    parallelFor(chunks, o.threads, [&](size_t c) {
      uint32_t* tri = s.tris.data() + 3 * s.chunkUnanimous[c];
      size_t chunkBoundary = 0;
      for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) chunkBoundary += placeUnanimous(s, i, tri);
      s.chunkOpen[c] = chunkBoundary;
    });
    for (size_t open : s.chunkOpen) boundary += open;
  } else {
    s.heCount.assign(n, 0);
    s.openOut.assign(n, 0);
    for (uint32_t i = 0; i < n; ++i)
      for (size_t k = 0; k < s.candCount[i]; ++k) {
        const uint32_t* slot = &s.cand[(size_t(i) * kMaxFan + k) * 3];
        if (slot[2] == 3) addTriangle(s, i, slot[0], slot[1], &boundary);
      }
  }
  // Then the triangles of two corners' fans, then those of one: on a surface curved strongly at the particle
  // spacing the corners' tangent planes disagree about near-cocircular quads, and a lone proposal that uses no taken
  // edge is usually exactly the triangle the hole repair would otherwise build, less folded (on the biped at 900
  // particles the repair's share drops from about 160 triangles per triangulation to a few; docs/tesselator.md).
  for (uint32_t votes : {2u, 1u})
    for (uint32_t i = 0; i < n; ++i)
      for (size_t k = 0; k < s.candCount[i] && (s.candVotes[i] >> votes & 1u); ++k) {
        const uint32_t* slot = &s.cand[(size_t(i) * kMaxFan + k) * 3];
        if (slot[2] == votes) addTriangle(s, i, slot[0], slot[1], &boundary);
      }
  return boundary;
}

size_t repairHoles(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary) {
  size_t unfilled = 0;
  for (int round = 0; round < 4 && boundary > 0; ++round) {
    const size_t n = s.vertexCount();  // (the surface rows of an earlier round or call add vertices)
    s.holeTo.resize(n * 4);
    collectHoles(s);
    s.holeUsed.assign(n * 4, 0);
    s.openUp.assign(n, 0);
    s.dropEdges.clear();
    unfilled = collectLoops(s, o);
    bridgeTubes(s, o, boundary);
    // Every loop not bridged is capped by ear clipping.
    for (size_t k = 0; k + 1 < s.loopStart.size(); ++k) {
      if (s.loopBridged[k]) continue;
      s.loop.assign(s.loops.begin() + std::ptrdiff_t(s.loopStart[k]),
                    s.loops.begin() + std::ptrdiff_t(s.loopStart[k + 1]));
      if (!fillable(s, s.loop)) {  // wrong way round: its rim's triangles go next round (see fillable)
        ++unfilled;
        for (size_t q = 0; q < s.loop.size(); ++q)
          s.dropEdges.push_back(uint64_t(s.loop[(q + 1) % s.loop.size()]) << 32 | s.loop[q]);
      } else if (!clipEars(s, o.desiredRadius, boundary)) {
        ++unfilled;
        for (uint32_t v : s.loop) s.openUp[v] = 1;  // open up around it next round
      }
    }
    // Loops that could not be closed (pinched or folded): remove every triangle touching them (a loop the wrong way
    // round: the triangles across its edges), so that the next round sees one larger, simple loop around the trouble
    // spot. (A loop counts as unclosed when another loop's triangles closed it first: then nothing is left open.)
    if (boundary == 0) unfilled = 0;
    if (unfilled > 0 && round < 3) removeAround(s, boundary);
  }
  s.dropEdges.clear();  // (pass F's removeAround takes pinches only)
  return unfilled;
}

size_t markPinchedVertices(Tesselator::State& s, const TesselatorOptions& o) {
  const size_t n = s.vertexCount(), chunks = (n + kChunk - 1) / kChunk;
  s.openUp.resize(n);
  s.dropSlot.resize(n * kMaxHalfEdges);
  s.chunkOpen.assign(chunks, 0);
  parallelFor(chunks, o.threads, [&](size_t c) {
    size_t pinched = 0;
    for (size_t v = c * kChunk; v < std::min(n, (c + 1) * kChunk); ++v) pinched += markIfPinched(s, v);
    s.chunkOpen[c] = pinched;
  });
  size_t pinched = 0;
  for (size_t p : s.chunkOpen) pinched += p;
  return pinched;
}

namespace {

// Removes the triangles that s.dropSlot marks at one of their corners (the pinched vertices' smaller fans), with
// their half-edges, keeping `boundary` and s.openOut up to date as removeAround does.
void removeSmallerFans(Tesselator::State& s, size_t& boundary) {
  // A pinch whose fans lie on different pieces is all that joins them (where the repair's caps over a neck met at one
  // vertex): cutting its smaller fan and capping the hole would leave a head or a hand apart for good. Every triangle
  // round it goes instead, so that the repair sees both pieces' holes there and joins them as the rims of a tube.
  // The pieces: vertices joined by triangles, but never through a pinched one (what the edges join, as
  // trianglePieces has it, for a fraction of the cost: this runs in every render with a pinch).
  DisjointSets pieces(s.vertexCount());
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    uint32_t first = ~0u;
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t v = s.tris[t + k];
      if (s.openUp[v]) continue;
      if (first == ~0u)
        first = v;
      else
        pieces.unite(first, v);
    }
  }
  for (uint32_t v = 0; v < s.vertexCount(); ++v) {
    if (!s.openUp[v]) continue;
    const uint32_t* to = &s.heTo[size_t(v) * kMaxHalfEdges];
    uint32_t piece = ~0u;
    bool apart = false;
    for (size_t q = 0; q < s.heCount[v] && !apart; ++q) {
      if (s.openUp[to[q]]) continue;
      const uint32_t p = pieces.find(to[q]);
      apart = piece != ~0u && p != piece;
      piece = p;
    }
    if (apart) std::fill_n(s.dropSlot.begin() + std::ptrdiff_t(size_t(v) * kMaxHalfEdges), s.heCount[v], uint8_t(1));
  }
  std::vector<uint8_t>& drop = s.holeUsed;  // per triangle (scratch: the repair rebuilds it)
  drop.assign(s.tris.size() / 3, 0);
  for (size_t t = 0; t < s.tris.size(); t += 3)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t a = s.tris[t + k], b = s.tris[t + (k + 1) % 3];
      if (!s.openUp[a]) continue;  // s.dropSlot is written for the pinched vertices only
      const uint32_t* to = &s.heTo[size_t(a) * kMaxHalfEdges];
      for (size_t q = 0; q < s.heCount[a]; ++q)
        if (to[q] == b && s.dropSlot[size_t(a) * kMaxHalfEdges + q]) drop[t / 3] = 1;
    }
  size_t w = 0;
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    const uint32_t c[3] = {s.tris[t], s.tris[t + 1], s.tris[t + 2]};
    if (!drop[t / 3]) {
      for (int k = 0; k < 3; ++k) s.tris[w + size_t(k)] = c[k];
      w += 3;
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = c[k], b = c[(k + 1) % 3];
      removeHalfEdge(s, a, b);
      boundary = hasHalfEdge(s, b, a) ? boundary + 1 : boundary - 1;
      s.openOut[a] = 1;
    }
  }
  s.tris.resize(w);
}

}  // namespace

namespace {

// Whether particles u and v lie on one small closed sheet of the given side, by their chord: a pocket's (air enclosed
// by the solid, the normals pointing into it) runs in front of both tangent planes through air; a blob's behind both
// through the solid.
bool onePocketSheet(Tesselator::State& s, uint32_t u, uint32_t v, bool air) {
  const glm::vec3 d = s.vpos[v] - s.vpos[u];
  const float front = glm::dot(d, s.nrm[u]), back = glm::dot(d, s.nrm[v]);
  if (air ? !(front > 0.0f && back < 0.0f) : !(front < 0.0f && back > 0.0f)) return false;
  return (sampleAmongVertices(s, s.vpos[u] + 0.5f * d).value < s.field->iso()) == air;
}

// The convex hull of s.pocket's vertices into s.strip (outward faces, wound counter-clockwise seen from outside), by
// brute force over every triple (a pocket has at most kMaxPocket vertices). False unless it is a closed 2-manifold
// over at least four of them (no four coplanar on a face).
bool pocketHull(Tesselator::State& s, float h) {
  const std::vector<uint32_t>& P = s.pocket;
  const float eps = 1e-6f * h * h * h;
  s.strip.clear();
  for (size_t i = 0; i < P.size(); ++i)
    for (size_t j = i + 1; j < P.size(); ++j)
      for (size_t k = j + 1; k < P.size(); ++k) {
        const glm::vec3 a = s.vpos[P[i]], n = glm::cross(s.vpos[P[j]] - a, s.vpos[P[k]] - a);
        int above = 0, below = 0;
        for (size_t m = 0; m < P.size(); ++m) {
          if (m == i || m == j || m == k) continue;
          const float side = glm::dot(n, s.vpos[P[m]] - a);
          above += side > eps, below += side < -eps;
          if (std::fabs(side) <= eps) ++above, ++below;  // coplanar: neither face is certain
        }
        if (above == 0)
          s.strip.insert(s.strip.end(), {P[i], P[j], P[k]});
        else if (below == 0)
          s.strip.insert(s.strip.end(), {P[i], P[k], P[j]});
      }
  // Closed 2-manifold: every directed edge once, with its twin; V - E + F = 2.
  std::vector<uint64_t>& edges = s.stripEdges;
  edges.clear();
  for (size_t t = 0; t < s.strip.size(); t += 3)
    for (size_t q = 0; q < 3; ++q) edges.push_back(uint64_t(s.strip[t + q]) << 32 | s.strip[t + (q + 1) % 3]);
  std::sort(edges.begin(), edges.end());
  if (edges.size() < 12 || std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
  for (const uint64_t e : edges)
    if (!std::binary_search(edges.begin(), edges.end(), e << 32 | e >> 32)) return false;
  std::vector<uint32_t> corners(s.strip);
  std::sort(corners.begin(), corners.end());
  const size_t vertices = size_t(std::unique(corners.begin(), corners.end()) - corners.begin());
  return vertices + s.strip.size() / 3 == edges.size() / 2 + 2;
}

}  // namespace

size_t closePockets(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary) {
  const size_t n = s.size();
  const float h = o.desiredRadius;
  const auto loose = [&](uint32_t u) { return s.heCount[u] == 0 && s.vok[u]; };
  size_t closed = 0;
  for (const bool air : {true, false}) {
    s.pocketSeen.assign(n, 0);
    for (uint32_t start = 0; start < n; ++start) {
      if (!loose(start) || s.pocketSeen[start]) continue;
      // The sheet: loose particles joined by chords of the side; none of them on the side of a particle in a
      // triangle (then it is part of a larger surface with a hole, the repair's).
      std::vector<uint32_t>& P = s.pocket;
      P.assign(1, start);
      s.pocketSeen[start] = 1;
      bool open = false;
      // Stops as soon as the sheet is open or too large (its particles reached so far stay marked: not a pocket).
      for (size_t head = 0; head < P.size() && !open && P.size() <= kMaxPocket; ++head)
        for (size_t q = 0; q < s.nbrCount[P[head]] && !open; ++q) {
          const uint32_t v = s.nbr[size_t(P[head]) * kMaxNeighbours + q];
          if (!s.vok[v] || (loose(v) && s.pocketSeen[v]) || !onePocketSheet(s, P[head], v, air)) continue;
          open = !loose(v);
          s.pocketSeen[v] = 1;
          P.push_back(v);
        }
      if (open || P.size() < 4 || P.size() > kMaxPocket || !pocketHull(s, h)) continue;
      // Outward for a blob; for a pocket the surface's outward normal points into it, so the hull turns inside out.
      if (air)
        for (size_t t = 0; t < s.strip.size(); t += 3) std::swap(s.strip[t + 1], s.strip[t + 2]);
      bool fits = true;
      for (size_t t = 0; t < s.strip.size() && fits; t += 3) {
        const uint32_t* c = &s.strip[t];
        const glm::vec3 face = glm::cross(s.vpos[c[1]] - s.vpos[c[0]], s.vpos[c[2]] - s.vpos[c[0]]);
        fits = glm::dot(face, s.nrm[c[0]] + s.nrm[c[1]] + s.nrm[c[2]]) > 0.0f;
      }
      if (!fits || !stripFits(s, h)) continue;
      for (size_t t = 0; t < s.strip.size(); t += 3)
        addTriangle(s, s.strip[t], s.strip[t + 1], s.strip[t + 2], &boundary);
      ++closed;
    }
  }
  return closed;
}

size_t unpinchVertices(Tesselator::State& s, const TesselatorOptions& o, size_t& boundary, size_t& unfilled) {
  size_t pinched = markPinchedVertices(s, o);
  // First only the smaller fans go (the vertex keeps its main disk, and the caps the repair lays where they were
  // are small); should that not do, every triangle around the vertex.
  for (int pass = 0; pass < 3 && pinched > 0; ++pass) {
    if (pass < 2) removeSmallerFans(s, boundary);
    else removeAround(s, boundary);
    unfilled = repairHoles(s, o, boundary);
    pinched = markPinchedVertices(s, o);
  }
  return pinched;
}

namespace {

// Whether triangle (a, b, c) winds with the surface: its normal agrees with the field's outward normal at its
// centroid. Where it agrees within 60 degrees with each corner's normal (almost everywhere), the field is not asked.
bool windsOutward(Tesselator::State& s, uint32_t a, uint32_t b, uint32_t c) {
  const glm::vec3 pa = s.vpos[a], face = glm::cross(s.vpos[b] - pa, s.vpos[c] - pa);
  const float near = 0.5f * glm::length(face);
  if (glm::dot(face, s.nrm[a]) > near && glm::dot(face, s.nrm[b]) > near && glm::dot(face, s.nrm[c]) > near)
    return true;
  return glm::dot(face, sampleAmongVertices(s, (pa + s.vpos[b] + s.vpos[c]) / 3.0f).gradient) < 0.0f;
}

// Points the half-edge slot of a -> b at triangle t with third corner c, adding the slot if a -> b is new.
void setHalfEdge(Tesselator::State& s, uint32_t a, uint32_t b, uint32_t c, uint32_t t, bool isNew) {
  const size_t k = isNew ? size_t(a) * kMaxHalfEdges + s.heCount[a]++ : halfEdgeSlot(s, a, b);
  s.heTo[k] = b, s.heThird[k] = c, s.heTri[k] = t;
}

// Removes directed edge a -> b, keeping heTri in step with heTo and heThird.
void dropHalfEdge(Tesselator::State& s, uint32_t a, uint32_t b) {
  const size_t k = halfEdgeSlot(s, a, b), end = size_t(a) * kMaxHalfEdges + s.heCount[a];
  std::copy(s.heTri.begin() + std::ptrdiff_t(k + 1), s.heTri.begin() + std::ptrdiff_t(end),
            s.heTri.begin() + std::ptrdiff_t(k));
  removeHalfEdge(s, a, b);
}

// Makes s.heTri valid for every half-edge out of v (s.heTriKnown[v]): those of each triangle around v, found by one
// scan of the triangles (the batch at the start of unfoldTriangles makes this rare).
void knowTrianglesAround(Tesselator::State& s, uint32_t v) {
  if (s.heTriKnown[v]) return;
  for (size_t t = 0; t < s.tris.size() / 3; ++t) {
    const uint32_t* tri = &s.tris[3 * t];
    if (tri[0] != v && tri[1] != v && tri[2] != v) continue;
    for (int k = 0; k < 3; ++k) s.heTri[halfEdgeSlot(s, tri[k], tri[(k + 1) % 3])] = uint32_t(t);
  }
  s.heTriKnown[v] = 1;
}

// Flips the edge u -> v of triangle t = (u, v, w) if that unfolds it: its neighbour (v, u, x) and t become (u, x, w)
// and (x, v, w), both winding with the normals, x -> w no edge yet. Returns whether it flipped.
bool flipToUnfold(Tesselator::State& s, uint32_t t, int k) {
  uint32_t* tri = &s.tris[3 * size_t(t)];
  const uint32_t u = tri[k], v = tri[(k + 1) % 3], w = tri[(k + 2) % 3];
  knowTrianglesAround(s, v);
  const size_t back = halfEdgeSlot(s, v, u);
  const uint32_t x = s.heThird[back], t2 = s.heTri[back];
  if (x == w || hasHalfEdge(s, w, x) || hasHalfEdge(s, x, w)) return false;
  if (s.heCount[x] >= kMaxHalfEdges || s.heCount[w] >= kMaxHalfEdges) return false;
  const int before = 1 + int(!windsOutward(s, v, u, x));
  if (int(!windsOutward(s, u, x, w)) + int(!windsOutward(s, x, v, w)) >= before) return false;
  dropHalfEdge(s, u, v);
  dropHalfEdge(s, v, u);
  tri[0] = u, tri[1] = x, tri[2] = w;
  uint32_t* tri2 = &s.tris[3 * size_t(t2)];
  tri2[0] = x, tri2[1] = v, tri2[2] = w;
  setHalfEdge(s, u, x, w, t, false);
  setHalfEdge(s, x, w, u, t, true);
  setHalfEdge(s, w, u, x, t, false);
  setHalfEdge(s, x, v, w, t2, false);
  setHalfEdge(s, v, w, x, t2, false);
  setHalfEdge(s, w, x, v, t2, true);
  return true;
}

constexpr size_t kMaxLoop = 2 * kMaxHalfEdges;  // the longest loop fanRing and clipRing triangulate

// A triangulation of ring[0..m) (a counter-clockwise loop) into `ears` whose triangles all wind with the surface and
// whose new edges are no edges yet: the fan from the ring vertex with the shortest diagonals. Returns the triangle
// count, m - 2, or 0 if no fan will do.
size_t fanRing(Tesselator::State& s, const uint32_t* ring, size_t m, uint32_t* ears) {
  size_t best = m;
  float bestLength = 1e30f;
  for (size_t j = 0; j < m; ++j) {
    const uint32_t a = ring[j];
    float length = 0.0f;
    bool ok = true;
    for (size_t i = 1; i + 1 < m && ok; ++i) {
      const uint32_t b = ring[(j + i) % m], c = ring[(j + i + 1) % m];
      ok = windsOutward(s, a, b, c) && (i == 1 || !(hasHalfEdge(s, a, b) || hasHalfEdge(s, b, a)));
      if (i >= 2) length += glm::length(s.vpos[b] - s.vpos[a]);
    }
    if (ok && length < bestLength) bestLength = length, best = j;
  }
  if (best == m) return 0;
  for (size_t i = 1; i + 1 < m; ++i) {
    uint32_t* ear = ears + 3 * (i - 1);
    ear[0] = ring[best], ear[1] = ring[(best + i) % m], ear[2] = ring[(best + i + 1) % m];
  }
  return m - 2;
}

// The same by ear clipping: each time the ear with the shortest new edge among those that wind with the surface,
// whose new edge is no edge yet and which hold no other vertex of the ring seen along the ring's mean normal (as
// plane ear clipping asks, so a ring that is a simple polygon in that view is not clipped into a dead end). Returns
// m - 2, or 0 if it gets stuck.
size_t clipRing(Tesselator::State& s, const uint32_t* ring, size_t m, uint32_t* ears) {
  uint32_t left[kMaxLoop];
  glm::vec2 flat[kMaxLoop];  // left[k] in the plane across the ring's mean normal
  glm::vec3 normal(0.0f), b0, b1;
  for (size_t k = 0; k < m; ++k) normal += s.nrm[ring[k]];
  if (!(glm::length(normal) > 1e-6f)) return 0;
  tangentBasis(glm::normalize(normal), b0, b1);
  for (size_t k = 0; k < m; ++k) {
    left[k] = ring[k];
    flat[k] = {glm::dot(s.vpos[ring[k]], b0), glm::dot(s.vpos[ring[k]], b1)};
  }
  auto cross2 = [](glm::vec2 o, glm::vec2 a, glm::vec2 b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  size_t n = m, count = 0;
  while (n > 3) {
    size_t best = n;
    float bestLength = 1e30f;
    for (size_t k = 0; k < n; ++k) {
      const size_t kb = (k + 1) % n, kc = (k + 2) % n;
      const uint32_t a = left[k], b = left[kb], c = left[kc];
      const float length = glm::length(s.vpos[c] - s.vpos[a]);
      if (length >= bestLength || hasHalfEdge(s, a, c) || hasHalfEdge(s, c, a)) continue;
      bool empty = true;  // no other loop vertex inside the ear, seen along the mean normal
      for (size_t q = 0; q < n && empty; ++q)
        if (q != k && q != kb && q != kc)
          empty = !(cross2(flat[k], flat[kb], flat[q]) > 0.0f && cross2(flat[kb], flat[kc], flat[q]) > 0.0f &&
                    cross2(flat[kc], flat[k], flat[q]) > 0.0f);
      if (empty && windsOutward(s, a, b, c)) bestLength = length, best = k;
    }
    if (best == n) return 0;
    uint32_t* ear = ears + 3 * count++;
    ear[0] = left[best], ear[1] = left[(best + 1) % n], ear[2] = left[(best + 2) % n];
    const size_t drop = (best + 1) % n;
    std::copy(left + drop + 1, left + n, left + drop);
    std::copy(flat + drop + 1, flat + n, flat + drop);
    --n;
  }
  if (!windsOutward(s, left[0], left[1], left[2])) return 0;
  std::copy_n(left, 3, ears + 3 * count++);
  return count;
}

// Removes vertex p if that unfolds its umbrella: its ring (a closed disk's boundary, distinct vertices) is
// triangulated again by fanRing, else clipRing. The ring's m triangles become m - 2 (the last two slots are marked
// dead, kDead). Returns whether it removed p (all or nothing).
constexpr uint32_t kDead = ~0u;
bool removeToUnfold(Tesselator::State& s, uint32_t p) {
  const size_t m = s.heCount[p];
  if (m < 3) return false;
  knowTrianglesAround(s, p);
  uint32_t ring[kMaxHalfEdges], ringTri[kMaxHalfEdges], ears[3 * kMaxHalfEdges];
  ring[0] = s.heTo[size_t(p) * kMaxHalfEdges];
  for (size_t i = 0; i < m; ++i) {  // counter-clockwise: triangle (p, ring[i], ring[i + 1]) is ringTri[i]
    const size_t k = halfEdgeSlot(s, p, ring[i]);
    ringTri[i] = s.heTri[k];
    if (i + 1 < m) ring[i + 1] = s.heThird[k];
    else if (s.heThird[k] != ring[0]) return false;  // not a closed disk
  }
  for (size_t i = 0; i < m; ++i)  // room for the new edges (each ring vertex loses two half-edges, gets at most m - 1)
    if (s.heCount[ring[i]] + m > kMaxHalfEdges + 1) return false;
  size_t count = fanRing(s, ring, m, ears);
  if (count == 0) count = clipRing(s, ring, m, ears);
  if (count == 0) return false;
  for (size_t i = 0; i < m; ++i) {
    const uint32_t b = ring[i], c = ring[(i + 1) % m];
    dropHalfEdge(s, p, b);
    dropHalfEdge(s, b, c);
    dropHalfEdge(s, c, p);
  }
  for (size_t q = 0; q < count; ++q) {
    const uint32_t a = ears[3 * q], b = ears[3 * q + 1], c = ears[3 * q + 2], t = ringTri[q];
    uint32_t* tri = &s.tris[3 * size_t(t)];
    tri[0] = a, tri[1] = b, tri[2] = c;
    setHalfEdge(s, a, b, c, t, true);
    setHalfEdge(s, b, c, a, t, true);
    setHalfEdge(s, c, a, b, t, true);
  }
  for (size_t i = m - 2; i < m; ++i) std::fill_n(&s.tris[3 * size_t(ringTri[i])], 3, kDead);
  return true;
}

// The best triangulation of loop[0..m) (counter-clockwise, m <= kMaxExactLoop) into `ears` among all whose triangles
// wind with the surface and whose diagonals are no edges yet: the one with the shortest diagonals in all, by dynamic
// programming over the loop's sub-polygons (each triangle tested once). Returns m - 2, or 0 if there is none. Unlike
// fanRing and clipRing it cannot miss a triangulation that exists.
constexpr size_t kMaxExactLoop = 20;
size_t triangulateLoop(Tesselator::State& s, const uint32_t* loop, size_t m, uint32_t* ears) {
  constexpr float kNone = 1e30f;
  float cost[kMaxExactLoop][kMaxExactLoop];  // cost[i][j], i < j: the best of sub-polygon loop[i..j]; kNone: none
  uint8_t apex[kMaxExactLoop][kMaxExactLoop];
  auto diagonal = [&](size_t i, size_t j) {  // usable as a diagonal (j - i >= 2, not the closing edge 0 -> m - 1)
    return !hasHalfEdge(s, loop[i], loop[j]) && !hasHalfEdge(s, loop[j], loop[i]);
  };
  for (size_t i = 0; i + 1 < m; ++i) cost[i][i + 1] = 0.0f;
  for (size_t span = 2; span < m; ++span)
    for (size_t i = 0; i + span < m; ++i) {
      const size_t j = i + span;
      cost[i][j] = kNone;
      if (span < m - 1 && !diagonal(i, j)) continue;
      const float own = span < m - 1 ? glm::length(s.vpos[loop[j]] - s.vpos[loop[i]]) : 0.0f;
      for (size_t k = i + 1; k < j; ++k) {
        if (cost[i][k] >= kNone || cost[k][j] >= kNone) continue;
        const float c = cost[i][k] + cost[k][j] + own;
        if (c >= cost[i][j] || !windsOutward(s, loop[i], loop[k], loop[j])) continue;
        cost[i][j] = c, apex[i][j] = uint8_t(k);
      }
    }
  if (cost[0][m - 1] >= kNone) return 0;
  size_t count = 0, stack[2 * kMaxExactLoop], top = 0;
  stack[top++] = 0, stack[top++] = m - 1;
  while (top > 0) {
    const size_t j = stack[--top], i = stack[--top];
    if (j - i < 2) continue;
    const size_t k = apex[i][j];
    uint32_t* ear = ears + 3 * count++;
    ear[0] = loop[i], ear[1] = loop[k], ear[2] = loop[j];
    stack[top++] = i, stack[top++] = k, stack[top++] = k, stack[top++] = j;
  }
  return count;
}

// Replaces the triangles region[0..r) (distinct, live) by another triangulation of their boundary, if the region is a
// disk whose boundary loop has at most kMaxLoop distinct vertices: by triangulateLoop for a short loop, else fanRing,
// else clipRing (every triangle winding with the surface, every new edge new; the region's own edges do not count,
// as they go). A disk with m boundary and I inner vertices has m + 2 I - 2 triangles; the new m - 2 fill the region's
// first slots and the rest are marked dead, and the inner vertices are left unused this render. Keeps the mesh closed
// and manifold: a disk is replaced by a disk with the same boundary. Returns whether it replaced (all or nothing).
constexpr size_t kMaxRegion = 160;  // the most triangles a repair region holds
bool retriangulateRegion(Tesselator::State& s, const uint32_t* region, size_t r) {
  if (r > kMaxRegion) return false;
  // The region's directed edges (sorted, as from << 32 | to); its boundary is those whose twin is not in it, and its
  // vertices are their distinct starts (every corner starts an edge of its triangle).
  uint64_t edge[3 * kMaxRegion];
  bool open[3 * kMaxRegion];
  size_t edges = 0, boundary = 0, v = 0, start = 0;
  for (size_t q = 0; q < r; ++q)
    for (size_t k = 0; k < 3; ++k)
      edge[edges++] = uint64_t(s.tris[3 * size_t(region[q]) + k]) << 32 | s.tris[3 * size_t(region[q]) + (k + 1) % 3];
  std::sort(edge, edge + edges);
  auto from = [&](size_t e) { return uint32_t(edge[e] >> 32); };
  auto to = [&](size_t e) { return uint32_t(edge[e]); };
  for (size_t e = 0; e < edges; ++e) {
    v += e == 0 || from(e) != from(e - 1);
    open[e] = !std::binary_search(edge, edge + edges, uint64_t(to(e)) << 32 | from(e));
    if (open[e]) ++boundary, start = e;
  }
  // A disk: Euler characteristic V - E + F = 1, and one boundary loop through distinct vertices.
  if (boundary < 3 || boundary > kMaxLoop || v + r != (edges + boundary) / 2 + 1) return false;
  uint32_t loop[kMaxLoop];
  size_t m = 0;
  for (size_t e = start; m < boundary;) {
    loop[m++] = from(e);
    if (to(e) == loop[0]) break;
    // The open edge out of to(e): the edges out of a vertex are adjacent in the sorted list.
    size_t f = size_t(std::lower_bound(edge, edge + edges, uint64_t(to(e)) << 32) - edge);
    while (f < edges && from(f) == to(e) && !open[f]) ++f;
    if (f == edges || from(f) != to(e)) return false;
    e = f;
  }
  if (m != boundary || std::find(loop + 1, loop + m, loop[0]) != loop + m) return false;
  // Without the region's edges while new ones are chosen (a chord of the loop may be one of them); put back if none do.
  for (size_t e = 0; e < edges; ++e) dropHalfEdge(s, from(e), to(e));
  auto restore = [&] {
    for (size_t q = 0; q < r; ++q) {
      const uint32_t* tri = &s.tris[3 * size_t(region[q])];
      for (size_t k = 0; k < 3; ++k) setHalfEdge(s, tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3], region[q], true);
    }
    return false;
  };
  uint32_t ears[3 * kMaxLoop];
  size_t count = m <= kMaxExactLoop ? triangulateLoop(s, loop, m, ears) : fanRing(s, loop, m, ears);
  if (count == 0 && m > kMaxExactLoop) count = clipRing(s, loop, m, ears);
  bool ok = count > 0;
  for (size_t i = 0; i < m && ok; ++i) {  // room in each loop vertex's half-edge table for its new edges
    size_t out = 0;
    for (size_t q = 0; q < 3 * count; ++q) out += ears[q] == loop[i];
    ok = s.heCount[loop[i]] + out <= kMaxHalfEdges;
  }
  if (!ok) return restore();
  for (size_t q = count; q < r; ++q) std::fill_n(&s.tris[3 * size_t(region[q])], 3, kDead);
  for (size_t q = 0; q < count; ++q) {
    const uint32_t t = region[q];
    const uint32_t a = ears[3 * q], b = ears[3 * q + 1], c = ears[3 * q + 2];
    uint32_t* out = &s.tris[3 * size_t(t)];
    out[0] = a, out[1] = b, out[2] = c;
    setHalfEdge(s, a, b, c, t, true);
    setHalfEdge(s, b, c, a, t, true);
    setHalfEdge(s, c, a, b, t, true);
  }
  return true;
}

// Unfolds fold t by retriangulating the region around it (retriangulateRegion): t and its three neighbours, then
// grown by the triangles across the region's boundary edges, up to kMaxGrowth times while it has at most kMaxRegion
// triangles. Indexes every half-edge's triangle first (once per render). Returns whether it did.
constexpr int kMaxGrowth = 12;
bool retriangulateAround(Tesselator::State& s, uint32_t t) {
  if (!s.heTriAll) {
    const size_t triangles = s.tris.size() / 3;
    for (uint32_t q = 0; q < triangles; ++q) {
      const uint32_t* tri = &s.tris[3 * size_t(q)];
      if (tri[0] != kDead)
        for (int k = 0; k < 3; ++k) s.heTri[halfEdgeSlot(s, tri[k], tri[(k + 1) % 3])] = q;
    }
    std::fill(s.heTriKnown.begin(), s.heTriKnown.end(), uint8_t(1));
    s.heTriAll = true;
  }
  uint32_t region[kMaxRegion];
  size_t r = 0;
  region[r++] = t;
  size_t scanned = 0;  // the triangles before it have no neighbour outside the region
  for (int grow = 0; grow < kMaxGrowth; ++grow) {
    const size_t before = r;
    for (size_t q = scanned; q < before; ++q)
      for (size_t k = 0; k < 3; ++k) {
        const uint32_t a = s.tris[3 * size_t(region[q]) + k], b = s.tris[3 * size_t(region[q]) + (k + 1) % 3];
        const uint32_t across = s.heTri[halfEdgeSlot(s, b, a)];
        if (std::find(region, region + r, across) != region + r) continue;
        if (r == kMaxRegion) return false;
        region[r++] = across;
      }
    scanned = before;
    if (retriangulateRegion(s, region, r)) return true;
  }
  return false;
}

}  // namespace

size_t unfoldTriangles(Tesselator::State& s) {
  const size_t triangles = s.tris.size() / 3;
  s.folded.clear();
  for (uint32_t t = 0; t < triangles; ++t)
    if (!windsOutward(s, s.tris[3 * size_t(t)], s.tris[3 * size_t(t) + 1], s.tris[3 * size_t(t) + 2]))
      s.folded.push_back(t);
  if (s.folded.empty()) return 0;
  // The triangle of each half-edge out of a fold's corners (the repairs look up no other, but for corners a flip
  // brings in: knowTrianglesAround), in one scan; the repairs keep them up to date.
  s.heTri.resize(s.heTo.size());
  s.heTriKnown.assign(s.vertexCount(), 0);
  s.heTriAll = false;
  for (uint32_t t : s.folded)
    for (size_t k = 0; k < 3; ++k) s.heTriKnown[s.tris[3 * size_t(t) + k]] = 1;
  for (uint32_t t = 0; t < triangles; ++t) {
    const uint32_t* tri = &s.tris[3 * size_t(t)];
    if (s.heTriKnown[tri[0]] | s.heTriKnown[tri[1]] | s.heTriKnown[tri[2]])
      for (int k = 0; k < 3; ++k) s.heTri[halfEdgeSlot(s, tri[k], tri[(k + 1) % 3])] = t;
  }
  for (size_t round = 0, before = 0; round < 3 && s.folded.size() != before; ++round) {  // while a round helps
    before = s.folded.size();
    size_t left = 0;
    for (uint32_t t : s.folded) {
      const uint32_t* tri = &s.tris[3 * size_t(t)];
      if (tri[0] == kDead || windsOutward(s, tri[0], tri[1], tri[2])) continue;  // a neighbour's repair unfolded it
      bool fixed = false;
      for (int k = 0; k < 3 && !fixed; ++k) fixed = flipToUnfold(s, t, k);
      for (int k = 0; k < 3 && !fixed; ++k) fixed = removeToUnfold(s, tri[k]);
      if (!fixed) fixed = retriangulateAround(s, t);
      if (!fixed) s.folded[left++] = t;
    }
    s.folded.resize(left);
  }
  // Compact away the dead slots.
  size_t w = 0;
  for (size_t t = 0; t < triangles; ++t)
    if (s.tris[3 * t] != kDead) {
      for (size_t k = 0; k < 3; ++k) s.tris[w + k] = s.tris[3 * t + k];
      w += 3;
    }
  s.tris.resize(w);
  return s.folded.size();
}

size_t solidPieces(const Tesselator::State& s) {
  DisjointSets pieces(s.vertexCount());
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    pieces.unite(s.tris[t], s.tris[t + 1]);
    pieces.unite(s.tris[t], s.tris[t + 2]);
  }
  // Each piece's signed volume (six times: the tetrahedra to the origin, as signedVolume), by its root.
  std::vector<double> volume(s.vertexCount(), 0.0);
  for (size_t t = 0; t < s.tris.size(); t += 3) {
    const glm::dvec3 a(s.vpos[s.tris[t]]), b(s.vpos[s.tris[t + 1]]), c(s.vpos[s.tris[t + 2]]);
    volume[pieces.find(s.tris[t])] += glm::dot(a, glm::cross(b, c));
  }
  return size_t(std::count_if(volume.begin(), volume.end(), [](double v) { return v > 0.0; }));
}

void writeMesh(const Tesselator::State& s, const TesselatorOptions& o, Mesh& mesh) {
  const size_t n = s.vertexCount();
  mesh.positions.resize(3 * n);
  mesh.normals.resize(3 * n);
  mesh.colors.resize(3 * n);
  parallelFor((n + kChunk - 1) / kChunk, o.threads, [&](size_t c) {
    for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
      for (int a = 0; a < 3; ++a) {
        mesh.positions[3 * i + size_t(a)] = s.vpos[i][a];
        mesh.normals[3 * i + size_t(a)] = s.nrm[i][a];
        mesh.colors[3 * i + size_t(a)] = std::clamp(s.vcol[i][a], 0.0f, 1.0f);
      }
  });
  mesh.indices = s.tris;
}

void writeFallbackMesh(const Tesselator::State& s, const TesselatorOptions& o, Mesh& mesh) {
  MarchingCubesOptions mc;
  mc.cellSize = o.desiredRadius;
  mc.threads = o.threads;
  mesh = polygonize(*s.field, mc);
}

void Tesselator::triangulate(Mesh& mesh) {
  State& s = *s_;
  const TesselatorOptions& o = options_;
  const auto t0 = std::chrono::steady_clock::now();
  mesh.clear();
  s.addedFrom.clear();
  stats_.surfaceRowVertices = 0;
  if (s.size() == 0 || s.field == nullptr) {
    stats_.triangles = stats_.boundaryEdges = stats_.filledTriangles = stats_.unfilledLoops = 0;
    stats_.meshMs = 0.0;
    return;
  }
  // Spatial sort and neighbour list at the current positions (kept for the next update if nothing moves before it).
  if (!s.nbrValid) findNeighbours(s, o);
  projectVertices(s, o);  // A
  buildFans(s, o);        // B
  voteTriangles(s, o);    // C
  size_t boundary = assembleTriangles(s, o);  // D
  const size_t assembled = s.tris.size() / 3;
  size_t unfilled = repairHoles(s, o, boundary);  // E
  const size_t pinched = unpinchVertices(s, o, boundary, unfilled);  // F
  stats_.filledTriangles = s.tris.size() / 3 > assembled ? s.tris.size() / 3 - assembled : 0;
  stats_.unfilledLoops = unfilled;
  stats_.pinchedVertices = pinched;
  closePockets(s, o, boundary);  // I (its hulls are closed: boundary stays)
  stats_.openEdges = boundary;
  s.lastMeshOpen = boundary > 0 || pinched > 0;
  stats_.foldedTriangles = s.lastMeshOpen || !o.unfold ? 0 : unfoldTriangles(s);  // H
  stats_.cutOffParts = 0;
  stats_.fallback = o.closedFallback && (boundary > 0 || pinched > 0);
  if (stats_.fallback) {  // G: never show a hole, nor a part off the body (docs/tesselator.md, "The fallback")
    writeFallbackMesh(s, o, mesh);
  } else {
    writeMesh(s, o, mesh);
    // J: a closed triangulation of more solid pieces than the field was last found to have may have meshed a part
    // apart from the solid it joins (a head capped at the neck): it is matched against the fallback, Marching Cubes
    // of the same field, which it then becomes (G). The solids it cut off are stats().cutOffParts.
    const size_t pieces = o.closedFallback ? solidPieces(s) : 0;
    if (pieces > 1 && pieces != s.fieldPieces) {
      Mesh fallback;
      writeFallbackMesh(s, o, fallback);
      const ComponentMatch match = matchComponents(mesh, fallback);
      stats_.cutOffParts = match.cutOff - match.cutOffCavities;
      if (stats_.cutOffParts > 0) {
        mesh = std::move(fallback);
        stats_.fallback = true;
      }
    }
    if (o.closedFallback && stats_.cutOffParts == 0) s.fieldPieces = pieces;
  }
  if (stats_.fallback) {
    ++stats_.fallbacks;
    boundary = 0;
  }
  // The surface rows' vertices were this render's: the arrays shared with the particles (s.nrm) are n long again.
  // s.addedFrom stays for carryTexcoords.
  stats_.surfaceRowVertices = stats_.fallback ? 0 : s.vertexCount() - s.size();
  if (stats_.fallback) s.addedFrom.clear();
  for (auto* v : {&s.vpos, &s.nrm, &s.vcol}) v->resize(s.size());
  s.vok.resize(s.size());
  stats_.triangles = mesh.triangleCount();
  stats_.boundaryEdges = boundary;
  stats_.meshMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace imps
