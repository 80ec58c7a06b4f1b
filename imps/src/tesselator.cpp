// SPDX-License-Identifier: MIT
// The particle tesselator's simulation: differential transforms, compute phase, integration, additions/deletions.
//
// Based on: A. Witkin and P. Heckbert, "Using Particles to Sample and Control Implicit Surfaces", 1994;
//           H. Pedersen's radius update and K. Russell, "IMPS", MIT 1999, 3.4-3.8.
#include "imps/tesselator.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "imps/parallel.h"
#include "imps/skeleton_cache.h"
#include "tesselator_state.h"

namespace imps {
namespace {

// Witkin-Heckbert constants, in units where desiredRadius = 1 (see docs/tesselator.md: the radius rule is scale
// dependent in metres, so the simulation runs in units of desiredRadius).
constexpr float kRho = 15.0f;          // energy feedback
constexpr float kBeta = 10.0f;         // keeps the radius rate finite without neighbours
constexpr float kSigmaMin = 0.25f;     // radius clamp
constexpr float kSigmaMax = 1.5f;      // radius clamp; a particle this large always fissions
constexpr float kSigmaFission = 1.25f; // a particle larger than this fissions when energised (energy > nu E-hat)
constexpr float kSigmaDeath = 0.7f;    // a particle smaller than this may die
constexpr float kDeathChance = 0.25f;  // per update
constexpr float kFusionDistance = 0.35f;  // two particles closer than this fuse
constexpr float kMaxStep = 0.3f;       // the most a particle moves per update
constexpr float kMaxNewton = 0.5f;     // the longest Newton projection step
constexpr float kStrayDistance = 1.0f; // |F - iso| / |grad F| beyond this: the particle left the surface
// Thin parts (TesselatorOptions::resolveThinParts): where a particle's primitive is thinner than desiredRadius its
// local spacing is desiredRadius times thickness / desiredRadius (at least kThinScaleMin; State::scale), and the
// dynamics run in units of it (repel, integrateParticles, addAndDeleteParticles): rings of particles close round a
// wrist that particles of the full spacing would leave open.
// Between kThinScaleKnee and kThinScaleFull the scale rises linearly from kThinScaleKnee to 1 (continuous: a jump
// would split every particle crossing it), so a part just under desiredRadius thick keeps (nearly) the full spacing:
// with the scale equal to the thickness there, flubber's arms (0.05-0.07 m under a desiredRadius of 0.06 m) packed
// unevenly against its body and folded more often than with one spacing (docs/tesselator.md, "Thin parts").
constexpr float kThinScaleMin = 0.5f;
constexpr float kThinScaleKnee = 0.8f;
constexpr float kThinScaleFull = 0.95f;
// Coming to rest on a still field: after kStillAfter updates of an unchanged field with a particle count stable to
// 1 % over the last kCountWindow updates, fission, fusion and death stop and the step halves every update; after
// kCalmUpdates such updates the particles are frozen until the field moves again. Not while the last triangulation
// of the particles had a hole or a pinched vertex (State::lastMeshOpen): on a scene whose thin parts need churn to be
// covered (issue 15's swarm), the particles would otherwise freeze on a hole.
constexpr uint32_t kStillAfter = 20;
constexpr uint32_t kCalmUpdates = 12;
constexpr size_t kCountWindow = 10;

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// Particle i's local spacing in desiredRadius: 1, or less where its owner is thinner (see kThinScaleMin).
float thinScale(const Tesselator::State& s, const Field& field, const TesselatorOptions& o, size_t i) {
  const int32_t owner = s.owner[i];
  if (!o.resolveThinParts || owner < 0 || size_t(owner) >= field.size()) return 1.0f;
  const Primitive& p = field.primitive(size_t(owner));
  // The thickness is the particle's distance from its owner's core: the owner's radius there where the particle is on
  // the owner's own surface, more where a blend, or another limb buried in it, carries the surface out (a hand held
  // inside the hip owns particles on the hip's surface, which must not pack as densely as on the hand). Both vary
  // smoothly along a limb and across a joint, where the owner changes: a jump in the scale would split every particle
  // crossing it. Never less than the owner's radius there: a particle off the surface, inside its owner, is passing.
  const float t = p.thickness(s.pos[i]) / o.desiredRadius;
  if (t >= kThinScaleFull) return 1.0f;
  if (t <= kThinScaleKnee) return std::max(t, kThinScaleMin);
  return kThinScaleKnee + (1.0f - kThinScaleKnee) * (t - kThinScaleKnee) / (kThinScaleFull - kThinScaleKnee);
}

Box chunkBox(const std::vector<glm::vec3>& p, size_t begin, size_t end, float pad) {
  Box b;
  for (size_t i = begin; i < end; ++i)
    if (finite3(p[i])) b.extend(p[i]);
  if (!b.empty()) {
    b.lo -= glm::vec3(pad);
    b.hi += glm::vec3(pad);
  }
  return b;
}

// E-hat: the energy a particle of radius desiredRadius feels in a hexagonal packing of spacing desiredRadius, with
// neighbours beyond queryRadius ignored (the cache's truncation), so that the packing is the radius rule's fixpoint.
float desiredEnergy(const TesselatorOptions& o) {
  const float q = o.queryRadius / o.desiredRadius;
  float e = 0.0f;
  for (int a = -8; a <= 8; ++a)
    for (int b = -8; b <= 8; ++b) {
      if (a == 0 && b == 0) continue;
      const float x = float(a) + 0.5f * float(b), y = 0.8660254f * float(b);
      const float r2 = x * x + y * y;
      if (r2 <= q * q) e += o.energyCoeff * std::exp(-0.5f * r2);
    }
  return std::max(e, 1e-3f);
}

}  // namespace

void findNeighbours(Tesselator::State& s, const TesselatorOptions& o) {
  // Spatial sort: particles in hash-bucket order, so each chunk of the fixed partition is compact in space.
  const size_t n = s.size();
  s.hash.build(s.pos);
  {
    const auto order = s.hash.order();
    auto permute = [&](auto& v, auto& tmp) {
      tmp.resize(n);
      for (size_t k = 0; k < n; ++k) tmp[k] = v[order[k]];
      v.swap(tmp);
    };
    permute(s.pos, s.tmpV);
    permute(s.grad, s.tmpV);
    permute(s.nrm, s.tmpV);
    permute(s.sigma, s.tmpF);
    permute(s.value, s.tmpF);
    permute(s.owner, s.tmpI);
    permute(s.id, s.tmpU);
    if (s.carry) {  // two slots per particle
      auto permute2 = [&](auto& v, auto& tmp) {
        tmp.resize(2 * n);
        for (size_t k = 0; k < n; ++k) {
          tmp[2 * k] = v[2 * size_t(order[k])];
          tmp[2 * k + 1] = v[2 * size_t(order[k]) + 1];
        }
        v.swap(tmp);
      };
      permute2(s.texLayer, s.tmpI);
      permute2(s.texUv, s.tmpUv);
    }
    s.hash.adoptOrder();
    s.cacheValid = false;
  }
  // Everything within the list radius, in the hash's visiting order (deterministic); only when more than
  // kMaxNeighbours are found are they sorted by (distance, index) and the nearest kept.
  const float radius = std::max(o.queryRadius, kFanRadius * o.desiredRadius);
  const float r2 = radius * radius;
  s.nbr.resize(n * kMaxNeighbours);
  s.nbrCount.resize(n);
  const size_t chunks = (n + kChunk - 1) / kChunk;
  const float cube = s.hash.cubeSize();
  parallelFor(chunks, o.threads, [&](size_t c) {
    const size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
    constexpr size_t kFound = 512;  // a denser crowd than this keeps the first kFound visited
    uint64_t found[kFound];
    // Candidates of a run of particles sharing a hash bucket (consecutive after the sort), gathered once: SoA, so the
    // distance loop vectorises.
    constexpr size_t kGather = 2048;
    float cx[kGather], cy[kGather], cz[kGather], cd2[kGather];
    uint32_t cj[kGather];
    auto keep = [&](size_t i, size_t cnt) {
      if (cnt > kMaxNeighbours) {
        std::nth_element(found, found + kMaxNeighbours, found + cnt);
        cnt = kMaxNeighbours;
      }
      uint32_t* out = &s.nbr[i * kMaxNeighbours];
      for (size_t k = 0; k < cnt; ++k) out[k] = uint32_t(found[k]);
      s.nbrCount[i] = uint8_t(cnt);
    };
    for (size_t a = begin; a < end;) {
      // The run [a, b): one bucket, inside this chunk (the partition is fixed, so runs do not depend on threads).
      const uint32_t bucket = s.hash.bucketOf(s.pos[a]);
      size_t b = a + 1;
      Box box;
      box.extend(s.pos[a]);
      while (b < end && s.hash.bucketOf(s.pos[b]) == bucket) box.extend(s.pos[b++]);
      size_t gathered = 0;
      const glm::vec3 extent = box.size();
      bool grouped = b - a > 1 && finite3(box.lo) && finite3(box.hi) && extent.x <= cube && extent.y <= cube &&
                     extent.z <= cube;  // else far-apart cubes share the bucket: query one by one
      if (grouped) {
        s.hash.forEachInBox(box.lo - glm::vec3(radius), box.hi + glm::vec3(radius), [&](uint32_t j) {
          if (gathered == kGather) {
            grouped = false;
            return;
          }
          cx[gathered] = s.pos[j].x, cy[gathered] = s.pos[j].y, cz[gathered] = s.pos[j].z;
          cj[gathered++] = j;
        });
      }
      for (size_t i = a; i < b; ++i) {
        size_t cnt = 0;
        if (!finite3(s.pos[i])) {
        } else if (grouped) {
          const glm::vec3 p = s.pos[i];
          for (size_t k = 0; k < gathered; ++k) {
            const float dx = cx[k] - p.x, dy = cy[k] - p.y, dz = cz[k] - p.z;
            cd2[k] = dx * dx + dy * dy + dz * dz;
          }
          if (gathered <= kFound) {  // the usual case: every candidate fits, so keep them without a branch
            for (size_t k = 0; k < gathered; ++k) {
              found[cnt] = sortKey(cd2[k], cj[k]);
              cnt += size_t(cd2[k] <= r2) & size_t(cj[k] != i);
            }
          } else {
            for (size_t k = 0; k < gathered; ++k)
              if (cd2[k] <= r2 && cj[k] != i && cnt < kFound) found[cnt++] = sortKey(cd2[k], cj[k]);
          }
        } else {
          s.hash.forEachWithin(s.pos[i], radius, s.pos, [&](uint32_t j, float d2) {
            if (j == i || d2 > r2 || cnt == kFound) return;
            found[cnt++] = sortKey(d2, j);
          });
        }
        keep(i, cnt);
      }
      a = b;
    }
  });
  s.nbrValid = true;
}

TesselatorOptions TesselatorOptions::forField(const Field& field, float cellSize) {
  TesselatorOptions o;
  if (field.primitives().empty()) return o;
  float smallest = 1e30f;
  double area = 0.0;  // summed over the primitives, overlaps counted twice: an upper bound for blended scenes
  for (const Primitive& p : field.primitives()) {
    smallest = std::min(smallest, p.minRadius());
    area += primitiveSurfaceArea(p);
  }
  if (!(smallest > 0.0f) || !std::isfinite(smallest)) return o;
  // Hexagonal packing: one particle per 0.866 h^2 of surface.
  const double floorForBudget = std::sqrt(area / (0.866 * double(kDefaultParticleBudget)));
  double wanted = 0.5 * double(smallest);
  if (cellSize > 0.0f && std::isfinite(cellSize)) wanted = std::min(wanted, 2.0 * double(cellSize));
  const float h = float(std::max(wanted, floorForBudget));
  const float scale = h / o.desiredRadius;
  o.desiredRadius = h;
  o.queryRadius *= scale;
  o.cubeSize *= scale;
  const Box box = field.surfaceBounds();
  if (!box.empty()) {
    const glm::vec3 extent = box.hi - box.lo;
    const float longest = std::max(extent.x, std::max(extent.y, extent.z));
    while (o.bitsPerDim < 7 && float(1 << o.bitsPerDim) * o.cubeSize < longest) ++o.bitsPerDim;
  }
  return o;
}

TesselatorOptions TesselatorOptions::forScene(const Scene& scene, const Field& field) {
  if (const auto* node = std::get_if<Tesselator3MPNode>(&scene.polygonizer)) return fromNode(*node);
  const auto* mc = std::get_if<MarchingCubesNode>(&scene.polygonizer);
  TesselatorOptions o = forField(field, mc ? mc->cellSize : 0.0f);
  if (mc) o.threads = mc->numThreads;  // the scene's own thread count (0: all cores); results do not depend on it
  return o;
}

TesselatorOptions TesselatorOptions::fromNode(const Tesselator3MPNode& n) {
  TesselatorOptions o;
  o.deltaT = n.deltaT;
  o.desiredRadius = n.desiredRadius;
  o.queryRadius = n.queryRadius;
  o.energyCoeff = n.energyCoeff;
  o.surfaceCoeff = n.surfaceCoeff;
  o.fissioningFrac = n.fissioningFrac;
  o.useSimpleRadii = n.useSimpleRadii;
  o.threads = n.numThreads;
  o.updatesPerRender = n.updatesPerRender;
  o.colorWidth = n.colorWidth;
  o.doDifferentialTransforms = n.doDifferentialTransforms;
  o.cubeSize = n.spatialSubdivision.cubeSize;
  o.bitsPerDim = n.spatialSubdivision.bitsPerDim;
  o.seed = uint64_t(int64_t(n.seed));
  o.textureMode = n.textureMode;
  return o;
}

void Tesselator::State::resizeParticles(size_t n) {
  pos.resize(n);
  vel.resize(n);
  grad.resize(n);
  nrm.resize(n);
  sigma.resize(n);
  sigmaRate.resize(n);
  energy.resize(n);
  value.resize(n);
  owner.resize(n);
  id.resize(n);
  dead.resize(n);
  if (carry) {
    texLayer.resize(2 * n, -1);
    texUv.resize(2 * n, glm::vec2(0.0f));
  }
}

void Tesselator::State::dropTexcoords() {
  carry = false;
  carryLayers = 0;
  texLayer.clear();
  texUv.clear();
  texGens.clear();
  prevPos.clear();
}

void Tesselator::State::add(glm::vec3 p, glm::vec3 g, float s, int32_t ownerIndex) {
  pos.push_back(p);
  vel.push_back(glm::vec3(0.0f));
  grad.push_back(g);
  const float gl = glm::length(g);
  nrm.push_back(gl > 0.0f ? -g / gl : glm::vec3(0, 0, 1));
  sigma.push_back(s);
  sigmaRate.push_back(0.0f);
  energy.push_back(0.0f);
  value.push_back(0.0f);
  owner.push_back(ownerIndex);
  id.push_back(nextId++);
  dead.push_back(0);
  if (carry) {
    texLayer.insert(texLayer.end(), 2, -1);
    texUv.insert(texUv.end(), 2, glm::vec2(0.0f));
  }
}

Tesselator::Tesselator(const TesselatorOptions& options) : options_(options), s_(std::make_unique<State>(options)) {
  if (!(options_.desiredRadius > 0.0f)) options_.desiredRadius = 0.3f;
  if (!(options_.queryRadius > options_.desiredRadius)) options_.queryRadius = 2.5f * options_.desiredRadius;
  if (!(options_.colorWidth > 0.0f)) options_.colorWidth = 1.0f;
  options_.updatesPerRender = std::max(options_.updatesPerRender, 1);
  s_->eHat = desiredEnergy(options_);
}

Tesselator::~Tesselator() = default;

void Tesselator::reset() {
  s_->resizeParticles(0);
  s_->dropTexcoords();
  s_->nbrValid = false;
  s_->cacheValid = false;
  s_->lastGeneration = ~0ull;
  s_->fieldMoved = true;
  s_->stillUpdates = s_->calm = 0;
  s_->lastMeshOpen = false;
  s_->fieldPieces = 1;
  s_->recentCounts.clear();
  s_->stepScale = 1.0f;
  stats_ = {};
}

ParticleView Tesselator::particles() const {
  return {s_->pos, s_->nrm, s_->sigma, s_->owner, s_->id};
}

namespace {

// Whether the field changed shape since the skeleton's previous update: some joint moved relative to the others.
// When the particles are not carried by differential transforms (`carried` false), any motion counts.
bool skeletonMoved(const SkeletonCache& skeleton, bool carried) {
  const size_t joints = skeleton.character().joints().size();
  const Rigid first = joints > 0 ? skeleton.differential(0) : Rigid{};
  if (!carried && (std::fabs(first.rotation.w) < 1.0f - 1e-7f || glm::length(first.translation) > 1e-7f)) return true;
  for (size_t j = 1; j < joints; ++j) {
    const Rigid& d = skeleton.differential(int(j));
    if (std::fabs(glm::dot(d.rotation, first.rotation)) < 1.0f - 1e-7f ||
        glm::length(d.translation - first.translation) > 1e-6f)
      return true;
  }
  return false;
}

// The rest schedule (see kStillAfter): counts the still updates and sets s.calm and s.stepScale for this update.
// Returns whether the particles are frozen (this update does nothing).
bool comeToRest(Tesselator::State& s) {
  s.recentCounts.push_back(s.size());
  if (s.recentCounts.size() > kCountWindow) s.recentCounts.erase(s.recentCounts.begin());
  s.stillUpdates = s.fieldMoved ? 0 : s.stillUpdates + 1;
  if (s.stillUpdates == 0) s.calm = 0;
  const auto [lo, hi] = std::minmax_element(s.recentCounts.begin(), s.recentCounts.end());
  const bool stable = s.recentCounts.size() == kCountWindow && double(*hi - *lo) <= 0.01 * double(*hi);
  if (s.size() == 0 || s.lastMeshOpen) s.calm = 0;  // never rest on a mesh with a hole: the dynamics may close it
  else if (s.calm > 0 || (s.stillUpdates >= kStillAfter && stable)) ++s.calm;
  s.stepScale = s.calm > 0 ? std::ldexp(1.0f, -int(std::min(s.calm, kCalmUpdates))) : 1.0f;
  return s.calm > kCalmUpdates;
}

}  // namespace

void Tesselator::update(const SkeletonCache& skeleton) {
  State& s = *s_;
  const auto t0 = Clock::now();
  s.character = &skeleton.character();
  // 1. Differential transforms (thesis 3.7): particles follow their owners' joints rigidly.
  if (options_.doDifferentialTransforms && s.character->hierarchical() && s.lastGeneration != ~0ull &&
      skeleton.generation() != s.lastGeneration) {
    const size_t prims = skeleton.field().size();
    std::vector<Rigid>& d = s.differentials;
    d.resize(prims);
    for (size_t i = 0; i < prims; ++i) d[i] = skeleton.primitiveDifferential(i);
    for (size_t i = 0; i < s.size(); ++i)
      if (s.owner[i] >= 0 && size_t(s.owner[i]) < prims) s.pos[i] = d[size_t(s.owner[i])].apply(s.pos[i]);
    s.nbrValid = false;
    s.cacheValid = false;
  }
  if (s.carry) updateTexGens(s, skeleton);
  const bool carried = options_.doDifferentialTransforms && s.character->hierarchical();
  s.fieldMoved =
      s.lastGeneration == ~0ull || (skeleton.generation() != s.lastGeneration && skeletonMoved(skeleton, carried));
  s.lastGeneration = skeleton.generation();
  s.fieldStamp = skeleton.generation();
  stats_.simulateMs = msSince(t0);
  step(skeleton.field(), &skeleton);
}

void Tesselator::update(const Field& field) {
  s_->character = nullptr;
  s_->fieldMoved = true;  // a bare field may have changed in place: never at rest
  s_->fieldStamp = ~0ull;
  stats_.simulateMs = 0.0;
  step(field, nullptr);
}

namespace {

// Particle i's ownership: the field's owner `want`, but only the current owner's blend neighbours may take it over
// (any owner without a hierarchy). Counts the change or refusal.
void transferOwnership(Tesselator::State& s, size_t i, int32_t want, uint64_t& transferred, uint64_t& blocked) {
  if (want < 0 || want == s.owner[i]) return;
  const bool ok = s.owner[i] < 0 || s.character == nullptr || s.character->blends(size_t(s.owner[i]), size_t(want));
  if (ok) {
    s.owner[i] = want;
    ++transferred;
  } else {
    ++blocked;
  }
}

// Particle i's neighbours within queryRadius into (nd2, ni) (squared distances, indices), the nearest kMaxRepulsion
// of them in a crowd; its kMaxFuse nearest by (distance, index) into s.fuse for the add/delete phase. Returns the
// count.
size_t repulsionNeighbours(Tesselator::State& s, size_t i, float q2, float* nd2, uint32_t* ni) {
  const glm::vec3 p = s.pos[i];
  const uint32_t* nl = &s.nbr[i * kMaxNeighbours];
  size_t cnt = 0;
  for (size_t k = 0; k < s.nbrCount[i]; ++k) {  // branch-free: about half are kept, unpredictably
    const glm::vec3 d = s.pos[nl[k]] - p;
    const float d2 = d.x * d.x + d.y * d.y + d.z * d.z;
    nd2[cnt] = d2;
    ni[cnt] = nl[k];
    cnt += size_t(d2 <= q2);
  }
  uint64_t nearest[kMaxFuse];
  size_t nearCount = 0;
  for (size_t k = 0; k < cnt; ++k) {
    const uint64_t key = sortKey(nd2[k], ni[k]);
    if (nearCount == kMaxFuse && key >= nearest[kMaxFuse - 1]) continue;
    size_t q = nearCount < kMaxFuse ? nearCount++ : kMaxFuse - 1;
    for (; q > 0 && nearest[q - 1] > key; --q) nearest[q] = nearest[q - 1];
    nearest[q] = key;
  }
  for (size_t k = 0; k < nearCount; ++k) s.fuse[i * kMaxFuse + k] = uint32_t(nearest[k]);
  s.fuseCount[i] = uint8_t(nearCount);
  if (cnt > kMaxRepulsion) {
    uint64_t keys[kMaxNeighbours];
    for (size_t k = 0; k < cnt; ++k) keys[k] = sortKey(nd2[k], ni[k]);
    std::nth_element(keys, keys + kMaxRepulsion, keys + cnt);
    cnt = kMaxRepulsion;
    for (size_t k = 0; k < cnt; ++k) {
      ni[k] = uint32_t(keys[k]);
      const glm::vec3 d = s.pos[ni[k]] - p;
      nd2[k] = d.x * d.x + d.y * d.y + d.z * d.z;
    }
  }
  return cnt;
}

// Particle i's repulsion (Witkin-Heckbert, in units of desiredRadius) from its neighbours (nd2, ni): the velocity
// constrained to the surface with feedback towards F = iso, its energy and radius rate. fs: its field sample.
void repel(Tesselator::State& s, size_t i, const FieldSample& fs, float iso, const TesselatorOptions& o,
           const float* nd2, const uint32_t* ni, size_t cnt) {
  const float invH = 1.0f / o.desiredRadius, alpha = o.energyCoeff;
  const glm::vec3 p = s.pos[i], g = fs.gradient;
  const float g2 = glm::dot(g, g);
  // Radii and distances in units of the local spacing (desiredRadius times the thin-part scale): a pair's distance in
  // units of their mean spacing, so that a wrist packed at a smaller spacing than its forearm is in equilibrium, not
  // pushing particles out across the border for ever.
  const float si = s.sigma[i] * invH / s.scale[i];
  const float inv2si = 0.5f / (si * si);
  glm::vec3 P(0.0f);
  float D = 0.0f, Ds = 0.0f;
  for (size_t k = 0; k < cnt; ++k) {
    const uint32_t j = ni[k];
    const float sj = s.sigma[j] * invH / s.scale[j];
    const float spacing = 0.5f * (s.scale[i] + s.scale[j]);
    const float r2 = nd2[k] * invH * invH / (spacing * spacing);
    const float ei = alpha * expAccurate(-r2 * inv2si);
    const float ej = alpha * expAccurate(-r2 * 0.5f / (sj * sj));
    D += ei;
    Ds += r2 * ei;
    P += (p - s.pos[j]) * (ei + (si * si) / (sj * sj) * ej);
  }
  // Velocity constrained to the surface, with feedback towards F = iso.
  glm::vec3 v = P - (glm::dot(g, P) + o.surfaceCoeff * (fs.value - iso)) / g2 * g;
  if (!finite3(v)) v = glm::vec3(0.0f);
  s.vel[i] = v;
  s.energy[i] = D;
  // Radius rate: D-dot = -rho (D - E-hat); Pedersen divides by beta + D / sigma^3 (Witkin-Heckbert by
  // beta + sum |r|^2 E / sigma^3).
  const float dDot = -kRho * (D - s.eHat);
  const float denom = kBeta + (o.useSimpleRadii ? D : Ds) / (si * si * si);
  s.sigmaRate[i] = dDot / denom;
}

// Particle i's fission into two of radius sigma / sqrt(2), displaced a quarter of its local spacing in a random tangent
// direction (the child is appended).
void fission(Tesselator::State& s, size_t i, const TesselatorOptions& o) {
  const float h = o.desiredRadius * s.scale[i];
  glm::vec3 b0, b1;
  tangentBasis(s.nrm[i], b0, b1);
  const float a = 6.2831853f * uniform01(o.seed, s.id[i], s.update, 1);
  const glm::vec3 off = 0.25f * h * (std::cos(a) * b0 + std::sin(a) * b1);
  const float child = s.sigma[i] * 0.70710678f;
  s.sigma[i] = child;
  const glm::vec3 p = s.pos[i];
  s.pos[i] = p - off;
  s.add(p + off, s.grad[i], child, s.owner[i]);
  if (s.carry) {  // the two halves take the parent's coordinates moved by what their offsets map to
    const size_t c = s.size() - 1;
    for (size_t k = 0; k < 2; ++k) {
      const size_t from = 2 * i + k, to = 2 * c + k;
      const int32_t l = s.texLayer[from];
      s.texLayer[to] = l;
      s.texUv[to] = s.texUv[from];
      if (l < 0 || size_t(l) >= s.texGens.size()) continue;
      const TexGen& gen = s.texGens[size_t(l)];
      glm::vec2 mid = gen.map(p), ahead = gen.map(p + off), behind = gen.map(p - off);
      ahead.x -= std::round(ahead.x - mid.x);  // a sphere generator's u wraps
      behind.x -= std::round(behind.x - mid.x);
      s.texUv[to] += ahead - mid;
      s.texUv[from] += behind - mid;
    }
  }
}

// Whether particle i fuses into an older, living one of its kMaxFuse nearest (recorded by the compute phase).
bool fuses(const Tesselator::State& s, size_t i, float fuse2) {
  for (size_t k = 0; k < s.fuseCount[i]; ++k) {
    const uint32_t j = s.fuse[i * kMaxFuse + k];
    if (s.dead[j] || s.id[j] > s.id[i]) continue;
    const glm::vec3 d = s.pos[j] - s.pos[i];
    if (glm::dot(d, d) < fuse2) return true;
  }
  return false;
}

// Drops the dead particles, keeping the others' order (children were appended after every parent).
void compactParticles(Tesselator::State& s) {
  size_t w = 0;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s.dead[i]) continue;
    if (w != i) {
      s.pos[w] = s.pos[i];
      s.grad[w] = s.grad[i];
      s.nrm[w] = s.nrm[i];
      s.sigma[w] = s.sigma[i];
      s.owner[w] = s.owner[i];
      s.id[w] = s.id[i];
      if (s.carry)
        for (size_t k = 0; k < 2; ++k) {
          s.texLayer[2 * w + k] = s.texLayer[2 * i + k];
          s.texUv[2 * w + k] = s.texUv[2 * i + k];
        }
    }
    ++w;
  }
  s.resizeParticles(w);
}

}  // namespace

void computeForces(Tesselator::State& s, const Field& field, const TesselatorOptions& o, bool cached) {
  const size_t n = s.size(), chunks = (n + kChunk - 1) / kChunk;
  const float h = o.desiredRadius, iso = field.iso();
  const float q2 = o.queryRadius * o.queryRadius;
  s.vel.resize(n);
  s.fuse.resize(n * kMaxFuse);
  s.fuseCount.resize(n);
  s.sigmaRate.resize(n);
  s.energy.resize(n);
  s.value.resize(n);
  s.dead.assign(n, 0);
  if (s.scratch.size() < chunks) s.scratch.resize(chunks);
  s.scale.resize(n);
  parallelFor(chunks, o.threads, [&](size_t c) {
    for (size_t i = c * kChunk, end = std::min(n, (c + 1) * kChunk); i < end; ++i)
      s.scale[i] = thinScale(s, field, o, i);
  });
  s.chunkTransfers.assign(chunks, 0);
  s.chunkBlocked.assign(chunks, 0);
  parallelFor(chunks, o.threads, [&](size_t c) {
    const size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
    FieldScratch& scratch = s.scratch[c];
    if (!cached) field.prepare(chunkBox(s.pos, begin, end, 0.0f), scratch);
    float nd2[kMaxNeighbours];
    uint32_t ni[kMaxNeighbours];
    for (size_t i = begin; i < end; ++i) {
      const glm::vec3 p = s.pos[i];
      s.vel[i] = glm::vec3(0.0f);
      s.sigmaRate[i] = 0.0f;
      s.fuseCount[i] = 0;
      if (!finite3(p)) {
        s.dead[i] = 1;
        continue;
      }
      FieldSample fs;
      if (cached) {
        fs.value = s.cacheValue[i];
        fs.gradient = s.cacheGrad[i];
        fs.owner = s.cacheOwner[i];
      } else {
        fs = field.sample(p, scratch);
      }
      const glm::vec3 g = fs.gradient;
      const float g2 = glm::dot(g, g);
      if (!(g2 > 1e-20f) || !std::isfinite(fs.value) ||
          std::fabs(fs.value - iso) > kStrayDistance * h * std::sqrt(g2)) {
        s.dead[i] = 1;  // stray: left the surface (or the field vanished); fission refills the gap
        continue;
      }
      s.value[i] = fs.value;
      s.grad[i] = g;
      s.nrm[i] = -g / std::sqrt(g2);
      transferOwnership(s, i, fs.owner, s.chunkTransfers[c], s.chunkBlocked[c]);
      const size_t cnt = repulsionNeighbours(s, i, q2, nd2, ni);
      repel(s, i, fs, iso, o, nd2, ni, cnt);
    }
  });
}

void integrateParticles(Tesselator::State& s, const Field& field, const TesselatorOptions& o) {
  const size_t n = s.size();
  const float h = o.desiredRadius, invH = 1.0f / h, iso = field.iso();
  parallelFor((n + kChunk - 1) / kChunk, o.threads, [&](size_t c) {
    const size_t begin = c * kChunk, end = std::min(n, begin + kChunk);
    FieldScratch& scratch = s.scratch[c];
    for (size_t i = begin; i < end; ++i) {
      if (s.dead[i]) continue;
      glm::vec3 step = o.deltaT * s.vel[i];
      const float len = glm::length(step);
      if (len > kMaxStep * h) step *= kMaxStep * h / len;
      s.pos[i] += s.stepScale * step;
      const float si =
          std::clamp(s.sigma[i] * invH / s.scale[i] + s.stepScale * o.deltaT * s.sigmaRate[i], kSigmaMin, kSigmaMax);
      s.sigma[i] = si * h * s.scale[i];
    }
    field.prepare(chunkBox(s.pos, begin, end, 0.0f), scratch);
    for (size_t i = begin; i < end; ++i) {
      if (s.dead[i]) continue;
      const float F = field.value(s.pos[i], scratch);
      const glm::vec3 g = s.grad[i];  // the gradient from the compute phase: a chord step, accurate near the surface
      const float g2 = glm::dot(g, g);
      glm::vec3 d = (iso - F) / g2 * g;
      const float len = glm::length(d);
      if (!(len <= kStrayDistance * h)) {
        s.dead[i] = 1;  // the step carried it off the surface (into a limb it does not blend with): a stray
        continue;
      }
      if (len > kMaxNewton * h) d *= kMaxNewton * h / len;
      s.pos[i] += d;
      if (!finite3(s.pos[i])) s.dead[i] = 1;
    }
  });
  s.nbrValid = false;  // particles moved
  s.cacheValid = false;
}

void addAndDeleteParticles(Tesselator::State& s, const TesselatorOptions& o, TesselatorStats& stats) {
  const float h = o.desiredRadius, invH = 1.0f / h;
  const size_t before = s.size();
  for (size_t i = 0; i < before; ++i) {
    if (s.dead[i]) {
      ++stats.strays;
      continue;
    }
    if (s.calm > 0) continue;  // coming to rest: only strays die
    const float scale = s.scale[i];  // radii and lengths in units of the local spacing, as in repel()
    if (fuses(s, i, kFusionDistance * kFusionDistance * h * h * scale * scale)) {
      s.dead[i] = 1;
      ++stats.fusions;
      continue;
    }
    const float si = s.sigma[i] * invH / scale;
    if (si < kSigmaDeath && uniform01(o.seed, s.id[i], s.update, 0) < kDeathChance) {
      s.dead[i] = 1;
      ++stats.deaths;
      continue;
    }
    const bool split = si >= kSigmaMax - 1e-4f || (si > kSigmaFission && s.energy[i] > o.fissioningFrac * s.eHat);
    if (split && s.size() < o.maxParticles) {
      fission(s, i, o);
      ++stats.fissions;
    }
  }
  compactParticles(s);
}

void Tesselator::step(const Field& field, const SkeletonCache*) {
  State& s = *s_;
  const TesselatorOptions& o = options_;
  auto t0 = Clock::now();
  if (s.size() == 0) {
    s.nbrValid = false;
    s.cacheValid = false;
    seedParticles(s, field, o);
    if (s.size() > 0) ++stats_.reseeds;
  }
  if (comeToRest(s)) {  // frozen on a still field: nothing moves, is born or dies (the mesh stays the same)
    s.field = &field;
    ++s.update;
    ++stats_.updates;
    stats_.particles = s.size();
    stats_.simulateMs += msSince(t0);
    stats_.addDeleteMs = 0.0;
    return;
  }
  // Spatial sort and neighbour list (unless nothing moved since the last triangulation built them).
  if (!s.nbrValid) findNeighbours(s, o);
  const size_t n = s.size();
  // The vertex pass of the last triangulate() sampled the field at exactly these positions (nothing moved since) and
  // the field is the same: reuse its samples.
  const bool cached = s.cacheValid && s.field == &field && s.fieldStamp != ~0ull && s.cacheStamp == s.fieldStamp &&
                      s.cacheValue.size() == n;
  s.field = &field;
  computeForces(s, field, o, cached);
  for (size_t c = 0; c < s.chunkTransfers.size(); ++c) {
    stats_.transfers += s.chunkTransfers[c];
    stats_.blockedTransfers += s.chunkBlocked[c];
  }
  if (s.carry) s.prevPos = s.pos;
  integrateParticles(s, field, o);
  if (s.carry) advectTexcoords(s, o);
  stats_.simulateMs += msSince(t0);

  t0 = Clock::now();
  addAndDeleteParticles(s, o, stats_);
  ++s.update;
  ++stats_.updates;
  stats_.particles = s.size();
  stats_.addDeleteMs = msSince(t0);
}

void Tesselator::frame(const SkeletonCache& skeleton, Mesh& mesh) {
  for (int u = 0; u < options_.updatesPerRender; ++u) update(skeleton);
  triangulate(mesh);
}

int Tesselator::settle(const SkeletonCache& skeleton, Mesh& mesh, int maxUpdates) {
  std::vector<size_t> counts;
  const TesselatorOptions& o = options_;
  auto cancelled = [&] { return o.cancel && o.cancel->load(std::memory_order_relaxed); };
  stats_.cancelled = false;
  for (int u = 1; u <= maxUpdates; ++u) {
    if (cancelled()) {
      mesh.clear();
      stats_.cancelled = true;
      return u - 1;
    }
    update(skeleton);
    if (o.progress) o.progress(float(u) / float(maxUpdates));
    counts.push_back(stats_.particles);
    if (u >= 20 && u % 5 == 0) {
      const auto [lo, hi] = std::minmax_element(counts.end() - 10, counts.end());
      if (double(*hi - *lo) <= 0.01 * double(*hi)) {
        triangulate(mesh);
        if (stats_.boundaryEdges == 0 && !stats_.fallback) {
          if (o.progress) o.progress(1.0f);
          return u;
        }
      }
    }
  }
  triangulate(mesh);
  return maxUpdates;
}

}  // namespace imps
