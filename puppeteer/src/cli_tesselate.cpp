// SPDX-License-Identifier: MIT
// `puppeteer bench`: the particle tesselator's Table 3.1-style report (ms per phase, particles, triangles, boundary
// edges, accuracy) and its per-render quality (holes, non-manifold edges and vertices, folded triangles, distance of
// the vertices from the surface, fissions and fusions), for a static pose, limbs swinging at a given angular speed, or
// a recorded take / motion clip retargeted onto the character as `replay` does.
#include "cli.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "export_take.h"
#include "imps/atomic_file.h"
#include "imps/character.h"
#include "imps/field.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "json_output.h"
#include "map_option.h"
#include "progress.h"
#include "session_calibration.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

constexpr int kSettledUpdates = 30;  // stillness is measured over the last 30 of 60 static updates after settling

struct BenchArgs {
  std::vector<std::string> scenes;
  std::string motion = "static";
  std::string map = "auto";
  int renders = 0;  // 0: 300 for static and swings, the whole take for a file
  double hz = 30.0;
  int threads = -1;  // -1: the scene's numThreads
  double desiredRadius = 0;  // > 0: overrides the scene's (queryRadius and the hash cube scale with it)
  bool uniformSpacing = false;  // TesselatorOptions::resolveThinParts off: the thesis's one spacing everywhere
  std::string csv;
  bool json = false;
};

// What drives the character: nothing (static), a swing (degrees per second), or a file's take.
struct Motion {
  double degPerSecond = 0.0;
  std::string file;  // a .session or .bvh
};

// The joints a "swing" moves: the biped's limbs if it has them, else every joint below a root.
std::vector<int> swingJoints(const Character& c) {
  std::vector<int> out;
  for (const char* name : {"L_UpperArm", "R_UpperArm", "L_Thigh", "R_Thigh", "L_Forearm", "R_Forearm"})
    if (c.findJoint(name) >= 0) out.push_back(c.findJoint(name));
  if (out.empty())
    for (size_t j = 0; j < c.joints().size(); ++j)
      if (c.joints()[j].parent >= 0) out.push_back(int(j));
  return out;
}

// One render's quality (and the particle churn of the updates before it).
struct RenderRow {
  double seconds = 0;
  size_t particles = 0, triangles = 0;
  size_t boundaryEdges = 0, nonManifoldEdges = 0, nonManifoldVertices = 0, foldedTriangles = 0;
  double worstFieldError = 0;  // max |F(v) - iso| over the mesh's vertices (field units)
  double worstOffsetMm = 0;    // max |F(v) - iso| / |grad F(v)| (first-order distance to the surface, mm)
  uint64_t fissions = 0, fusions = 0;
  size_t fallback = 0;  // 1: the particle triangulation was not closed and manifold, or cut a part off; Marching
                        // Cubes was shown
  size_t particleOpenEdges = 0, particlePinchedVertices = 0;  // what the particle triangulation had left
  size_t particleCutOffParts = 0;  // solids the particle triangulation meshed apart (TesselatorStats::cutOffParts)
  // Against Marching Cubes of the same field at half desiredRadius (matchComponents): parts meshed as separate
  // pieces where the surface is one (a hand cut off at the wrist), and components not meshed at all.
  size_t cutOffParts = 0, missingComponents = 0;
  size_t cutOffSolids = 0;      // of the parts cut off, those that are not cavities (air pockets closed)
  size_t missingSolids = 0;     // of the missing, those that are not cavities (air enclosed by the solid)
  double largestMissingMm = 0;  // the largest missing component's bounding-box diagonal (0: none missing)
};

struct Report {
  std::string name;
  double sim = 0, addDel = 0, mesh = 0;
  size_t particles = 0, tris = 0;
  double worstMm = 0;
  int settleUpdates = 0;
  int updatesToStill = -1;  // updates from seeding until still (see measureSettled); -1: not within the window
  // Still means still: measured over kSettledUpdates static updates after settling (measureSettled).
  double fissionsPerUpdateSettled = 0, fusionsPerUpdateSettled = 0;
  double settledMaxMotion = 0;      // the largest move of a surviving particle in one update (desiredRadius)
  bool settledMeshIdentical = false;  // every render of the settled window gave the same triangle list
  std::vector<RenderRow> rows;
  size_t count(size_t RenderRow::*field) const {
    return size_t(std::count_if(rows.begin(), rows.end(), [&](const RenderRow& r) { return r.*field > 0; }));
  }
  size_t max(size_t RenderRow::*field) const {
    size_t m = 0;
    for (const RenderRow& r : rows) m = std::max(m, r.*field);
    return m;
  }
  size_t nonManifoldRenders() const {
    return size_t(std::count_if(rows.begin(), rows.end(),
                                [](const RenderRow& r) { return r.nonManifoldEdges + r.nonManifoldVertices > 0; }));
  }
  double worst(double RenderRow::*field) const {
    double m = 0;
    for (const RenderRow& r : rows) m = std::max(m, r.*field);
    return m;
  }
  uint64_t total(uint64_t RenderRow::*field) const {
    uint64_t n = 0;
    for (const RenderRow& r : rows) n += r.*field;
    return n;
  }
};

// The mesh's defects as the viewer would show them: topology (analyzeTopology), triangles whose winding disagrees
// with the field's outward normal at their centroid, how far the used vertices are from F = iso, and its components
// against `reference` (Marching Cubes of the same field at a finer cell).
void measureRender(const Mesh& mesh, const Field& field, const Mesh& reference, RenderRow& row) {
  const ComponentMatch match = matchComponents(mesh, reference);
  row.cutOffParts = match.cutOff;
  row.missingComponents = match.missing;
  row.missingSolids = match.missing - match.missingCavities;
  row.cutOffSolids = match.cutOff - match.cutOffCavities;
  row.largestMissingMm = 1000.0 * double(match.largestMissing);
  const MeshTopology t = analyzeTopology(mesh);
  row.boundaryEdges = t.boundaryEdges;
  row.nonManifoldEdges = t.nonManifoldEdges;
  row.nonManifoldVertices = t.nonManifoldVertices;
  row.triangles = mesh.triangleCount();
  std::vector<uint8_t> used(mesh.vertexCount(), 0);
  for (size_t k = 0; k < mesh.triangleCount(); ++k) {
    const uint32_t* tri = &mesh.indices[3 * k];
    const glm::vec3 a = mesh.position(tri[0]), b = mesh.position(tri[1]), c = mesh.position(tri[2]);
    used[tri[0]] = used[tri[1]] = used[tri[2]] = 1;
    const FieldSample s = field.sample((a + b + c) / 3.0f);
    if (glm::dot(glm::cross(b - a, c - a), -s.gradient) < 0.0f) ++row.foldedTriangles;
  }
  for (size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    const FieldSample s = field.sample(mesh.position(v));
    const double error = std::fabs(double(s.value) - double(field.iso()));
    const double g = glm::length(s.gradient);
    row.worstFieldError = std::max(row.worstFieldError, error);
    row.worstOffsetMm = std::max(row.worstOffsetMm, g > 0.0 ? 1000.0 * error / g : 1e9);
  }
}

// A take from a .bvh or a .session on the character, resampled to `hz` (the retargeting `replay` does for clips and
// for sessions made from clips; other sessions through their recorded calibration). Prints errors; nullopt then.
std::optional<Take> loadTake(const std::string& path, const std::string& map, const Character& character, double hz) {
  FrameSelection selection;
  selection.fps = hz;
  std::optional<sim::BvhClip> clip;
  std::optional<sim::Session> session;
  if (extensionOf(path) == ".bvh") {
    Diagnostics warnings;
    auto c = sim::readBvh(path, &warnings);
    std::fputs(warnings.str().c_str(), stderr);
    if (!c) return std::fputs(c.error().str().c_str(), stderr), std::nullopt;
    clip = std::move(*c);
  } else {
    auto s = sim::readSession(path);
    if (!s) return std::fputs(s.error().str().c_str(), stderr), std::nullopt;
    if (s->skeleton) {
      auto c = sim::sessionToBvh(*s);
      if (!c) return std::fputs(c.error().str().c_str(), stderr), std::nullopt;
      clip = std::move(*c);
    } else {
      session = std::move(*s);
    }
  }
  std::expected<Take, Diagnostics> take = std::unexpected(Diagnostics());
  if (clip) {
    const auto options = retargetOptionsFor(map, *clip, character);
    if (!options) return std::nullopt;
    auto r = Retargeter::create(*clip, character, *options);
    if (!r)
      return std::fprintf(stderr, "puppeteer bench: error: %s: %s\n", path.c_str(),
                          r.error().all().front().message.c_str()),
             std::nullopt;
    take = takeFromClip(*clip, *r, character, selection);
  } else {
    auto c = calibrationForSample(*session, session->samples.size(), &character, path);
    if (!c) return std::fputs(c.error().str().c_str(), stderr), std::nullopt;
    if (!*c)
      return std::fprintf(stderr, "puppeteer bench: error: %s has no recorded calibration and no skeleton\n",
                          path.c_str()),
             std::nullopt;
    take = takeFromSession(*session, **c, character, selection);
  }
  if (!take)
    return std::fprintf(stderr, "puppeteer bench: error: %s: %s\n", path.c_str(),
                        take.error().all().front().message.c_str()),
           std::nullopt;
  return std::move(*take);
}

// Poses the skeleton for render f: the swing's triangle wave (±45°, advancing degPerSecond / hz per render) or the
// take's frame f.
class Driver {
 public:
  Driver(SkeletonCache& skel, const Motion& motion, const Take* take, double hz)
      : skel_(skel), motion_(motion), take_(take), hz_(hz), joints_(swingJoints(skel.character())) {
    for (int j : joints_) rest_.push_back(skel.local(j).rotation);
  }
  void pose(int f) {
    if (take_) {
      const auto& locals = take_->locals[size_t(f) % take_->frames()];
      for (size_t j = 0; j < locals.size(); ++j) {
        skel_.setRotation(int(j), locals[j].rotation);
        skel_.setTranslation(int(j), locals[j].translation);
      }
      skel_.update();
      return;
    }
    if (motion_.degPerSecond <= 0.0) return;
    constexpr double amplitude = 45.0;
    angle_ += direction_ * motion_.degPerSecond / hz_;
    if (angle_ > amplitude) angle_ = 2 * amplitude - angle_, direction_ = -1.0;
    if (angle_ < -amplitude) angle_ = -2 * amplitude - angle_, direction_ = 1.0;
    for (size_t k = 0; k < joints_.size(); ++k) {
      const float a = float(glm::radians(angle_)) * (k % 2 == 0 ? 1.0f : -1.0f);
      skel_.setRotation(joints_[k], rest_[k] * glm::angleAxis(a, glm::vec3(0, 0, 1)));
    }
    skel_.update();
  }

 private:
  SkeletonCache& skel_;
  Motion motion_;
  const Take* take_;
  double hz_;
  std::vector<int> joints_;
  std::vector<glm::quat> rest_;
  double angle_ = 0.0, direction_ = 1.0;
};

// After settling: 2 kSettledUpdates static updates, each triangulated. Over the last kSettledUpdates: fissions,
// fusions, the largest move of a particle that survives an update (matched by id, units of desiredRadius), and
// whether the triangle lists stayed the same. "Still" from the first update after which every update has no fission
// or fusion, moves no particle by 1 % of desiredRadius or more and gives the same triangles as the one before.
void measureSettled(Tesselator& tess, const SkeletonCache& skel, Mesh& mesh, Report& r) {
  const float h = tess.options().desiredRadius;
  std::unordered_map<uint64_t, glm::vec3> before;
  std::vector<uint32_t> previous;
  int stillFrom = -1;
  r.settledMeshIdentical = true;
  uint64_t fissions = 0, fusions = 0;
  for (int u = 0; u < 2 * kSettledUpdates; ++u) {
    before.clear();
    const ParticleView p0 = tess.particles();
    for (size_t i = 0; i < p0.size(); ++i) before.emplace(p0.ids[i], p0.positions[i]);
    const uint64_t fissions0 = tess.stats().fissions, fusions0 = tess.stats().fusions;
    tess.update(skel);
    tess.triangulate(mesh);
    const ParticleView p1 = tess.particles();
    double motion = 0;
    for (size_t i = 0; i < p1.size(); ++i)
      if (auto it = before.find(p1.ids[i]); it != before.end())
        motion = std::max(motion, double(glm::length(p1.positions[i] - it->second) / h));
    const uint64_t fis = tess.stats().fissions - fissions0, fus = tess.stats().fusions - fusions0;
    const bool same = u > 0 && mesh.indices == previous;
    const bool still = fis == 0 && fus == 0 && motion < 0.01 && (same || u == 0);
    stillFrom = still ? (stillFrom < 0 ? u : stillFrom) : -1;
    if (u >= kSettledUpdates) {
      fissions += fis, fusions += fus;
      r.settledMaxMotion = std::max(r.settledMaxMotion, motion);
      r.settledMeshIdentical = r.settledMeshIdentical && same;
    }
    previous = mesh.indices;
  }
  r.fissionsPerUpdateSettled = double(fissions) / kSettledUpdates;
  r.fusionsPerUpdateSettled = double(fusions) / kSettledUpdates;
  r.updatesToStill = stillFrom < 0 ? -1 : r.settleUpdates + stillFrom + 1;
}

std::optional<Report> benchScene(const std::string& path, const Motion& motion, const BenchArgs& a,
                                 Progress& progress) {
  const auto loaded = loadScene(path);
  if (!loaded) return std::nullopt;
  const Character& ch = loaded->character;
  std::optional<Take> take;
  if (!motion.file.empty()) {
    take = loadTake(motion.file, a.map, ch, a.hz);
    if (!take) return std::nullopt;
  }
  SkeletonCache skel(ch);
  TesselatorOptions o = TesselatorOptions::forScene(loaded->scene, skel.field());
  if (a.threads >= 0) o.threads = a.threads;
  o.resolveThinParts = !a.uniformSpacing;
  if (a.desiredRadius > 0) {
    const float scale = float(a.desiredRadius) / o.desiredRadius;
    o.desiredRadius *= scale;
    o.queryRadius *= scale;
    o.cubeSize *= scale;
  }
  Driver driver(skel, motion, take ? &*take : nullptr, a.hz);
  Tesselator tess(o);
  Mesh mesh;
  Report r;
  r.name = std::filesystem::path(path).filename().string();
  progress.phase(r.name + ": settling");
  if (take) driver.pose(0);  // settle on the take's first pose
  r.settleUpdates = tess.settle(skel, mesh, 400);
  measureSettled(tess, skel, mesh, r);

  const int frames = a.renders > 0 ? a.renders : take ? int(take->frames()) : 300;
  MarchingCubes marchingCubes;  // every render's reference for the components
  MarchingCubesOptions reference;
  reference.cellSize = 0.5f * o.desiredRadius;
  reference.threads = o.threads;
  Mesh referenceMesh;
  for (int f = 0; f < frames; ++f) {
    if (f % 10 == 0) progress.phase(r.name + ": render " + std::to_string(f + 1) + "/" + std::to_string(frames));
    driver.pose(f);
    RenderRow row;
    const uint64_t fissions0 = tess.stats().fissions, fusions0 = tess.stats().fusions;
    for (int u = 0; u < o.updatesPerRender; ++u) {
      tess.update(skel);
      r.sim += tess.stats().simulateMs;
      r.addDel += tess.stats().addDeleteMs;
    }
    tess.triangulate(mesh);
    r.mesh += tess.stats().meshMs;
    row.seconds = double(f) / a.hz;
    row.particles = tess.stats().particles;
    row.fissions = tess.stats().fissions - fissions0;
    row.fusions = tess.stats().fusions - fusions0;
    row.fallback = tess.stats().fallback ? 1 : 0;
    row.particleOpenEdges = tess.stats().openEdges;
    row.particlePinchedVertices = tess.stats().pinchedVertices;
    row.particleCutOffParts = tess.stats().cutOffParts;
    marchingCubes.polygonize(skel.field(), reference, referenceMesh);
    measureRender(mesh, skel.field(), referenceMesh, row);
    r.rows.push_back(row);
  }
  const double renders = std::max(1, frames), updates = renders * o.updatesPerRender;
  r.sim /= updates;
  r.addDel /= updates;
  r.mesh /= renders;
  r.particles = tess.stats().particles;
  r.tris = tess.stats().triangles;
  // Accuracy: dense surface samples (Marching Cubes vertices at a third of desiredRadius) to the particle mesh.
  progress.phase(r.name + ": accuracy against dense samples");
  MarchingCubesOptions mc;
  mc.cellSize = o.desiredRadius / 3.0f;
  const Mesh dense = polygonize(skel.field(), mc);
  std::vector<glm::vec3> samples(dense.vertexCount());
  for (size_t v = 0; v < samples.size(); ++v) samples[v] = dense.position(v);
  r.worstMm = 1000.0 * worstDistanceToMesh(mesh, samples, 4.0f * o.desiredRadius);
  return r;
}

// --motion: static, swing:DEG_PER_S, or a .session / .bvh file. Prints the error and returns the exit code.
int parseMotion(const std::string& text, Motion& m) {
  if (text == "static") return kExitOk;
  const std::string ext = extensionOf(text);
  if (ext == ".session" || ext == ".bvh") {
    if (!std::filesystem::is_regular_file(text)) {
      std::fprintf(stderr, "puppeteer bench: error: %s: no such file\n", text.c_str());
      return kExitInvalidInput;
    }
    m.file = text;
    return kExitOk;
  }
  if (text.rfind("swing:", 0) != 0) {
    std::fprintf(stderr,
                 "puppeteer bench: error: --motion must be static, swing:DEG_PER_S, FILE.session or FILE.bvh, got "
                 "'%s'\n", text.c_str());
    return kExitUsage;
  }
  try {
    size_t used = 0;
    m.degPerSecond = std::stod(text.substr(6), &used);
    if (used != text.size() - 6) throw std::invalid_argument("trailing text");
  } catch (...) {
    std::fprintf(stderr, "puppeteer bench: error: bad angular speed in '%s'\n", text.c_str());
    return kExitUsage;
  }
  if (!(m.degPerSecond >= 0.0 && m.degPerSecond < 1e5)) {
    std::fprintf(stderr, "puppeteer bench: error: angular speed out of range in '%s'\n", text.c_str());
    return kExitUsage;
  }
  return kExitOk;
}

std::string csvText(const std::vector<Report>& reports) {
  std::string out =
      "scene,render,seconds,particles,triangles,boundary_edges,nonmanifold_edges,nonmanifold_vertices,"
      "folded_triangles,worst_f_minus_iso,worst_offset_mm,fissions,fusions,fallback,particle_open_edges,"
      "particle_pinched_vertices,cut_off_parts,cut_off_cavities,missing_components,missing_cavities,"
      "largest_missing_mm,particle_cut_off_parts\n";
  char line[512];
  for (const Report& r : reports)
    for (size_t f = 0; f < r.rows.size(); ++f) {
      const RenderRow& w = r.rows[f];
      std::snprintf(line, sizeof line,
                    "%s,%zu,%.4f,%zu,%zu,%zu,%zu,%zu,%zu,%.6g,%.4g,%llu,%llu,%zu,%zu,%zu,%zu,%zu,%zu,%zu,%.4g,%zu\n",
                    r.name.c_str(), f, w.seconds, w.particles, w.triangles, w.boundaryEdges, w.nonManifoldEdges,
                    w.nonManifoldVertices, w.foldedTriangles, w.worstFieldError, w.worstOffsetMm,
                    (unsigned long long)w.fissions, (unsigned long long)w.fusions, w.fallback, w.particleOpenEdges,
                    w.particlePinchedVertices, w.cutOffParts, w.cutOffParts - w.cutOffSolids, w.missingComponents,
                    w.missingComponents - w.missingSolids, w.largestMissingMm, w.particleCutOffParts);
      out += line;
    }
  return out;
}

Json reportJson(const Report& r) {
  return Json{{"scene", r.name},
              {"simulateMsPerUpdate", r.sim},
              {"addDeleteMsPerUpdate", r.addDel},
              {"meshMsPerRender", r.mesh},
              {"particles", r.particles},
              {"triangles", r.tris},
              {"maxBoundaryEdges", r.max(&RenderRow::boundaryEdges)},
              {"rendersWithHoles", r.count(&RenderRow::boundaryEdges)},
              {"renders", r.rows.size()},
              {"worstSampleDistanceMm", r.worstMm},
              {"updatesToSettle", r.settleUpdates},
              {"renders_with_holes", r.count(&RenderRow::boundaryEdges)},
              {"max_boundary_edges", r.max(&RenderRow::boundaryEdges)},
              {"renders_with_nonmanifold", r.nonManifoldRenders()},
              {"max_nonmanifold_edges", r.max(&RenderRow::nonManifoldEdges)},
              {"max_nonmanifold_vertices", r.max(&RenderRow::nonManifoldVertices)},
              {"renders_with_folds", r.count(&RenderRow::foldedTriangles)},
              {"max_folded_triangles", r.max(&RenderRow::foldedTriangles)},
              {"worst_f_minus_iso", r.worst(&RenderRow::worstFieldError)},
              {"worst_offset_mm", r.worst(&RenderRow::worstOffsetMm)},
              {"fissions", r.total(&RenderRow::fissions)},
              {"fusions", r.total(&RenderRow::fusions)},
              {"renders_with_fallback", r.count(&RenderRow::fallback)},
              {"max_particle_open_edges", r.max(&RenderRow::particleOpenEdges)},
              {"max_particle_pinched_vertices", r.max(&RenderRow::particlePinchedVertices)},
              {"renders_with_particle_cut_off_parts", r.count(&RenderRow::particleCutOffParts)},
              {"renders_with_cut_off_parts", r.count(&RenderRow::cutOffParts)},
              {"max_cut_off_parts", r.max(&RenderRow::cutOffParts)},
              {"renders_with_cut_off_solids", r.count(&RenderRow::cutOffSolids)},
              {"renders_with_missing_components", r.count(&RenderRow::missingComponents)},
              {"max_missing_components", r.max(&RenderRow::missingComponents)},
              {"renders_with_missing_solids", r.count(&RenderRow::missingSolids)},
              {"largest_missing_component_mm", r.worst(&RenderRow::largestMissingMm)},
              {"updates_to_settle", r.settleUpdates},
              {"updates_to_still", r.updatesToStill},
              {"fissions_per_update_settled", r.fissionsPerUpdateSettled},
              {"fusions_per_update_settled", r.fusionsPerUpdateSettled},
              {"settled_max_motion", r.settledMaxMotion},
              {"settled_mesh_identical", r.settledMeshIdentical}};
}

void printTable(const BenchArgs& a, const std::vector<Report>& reports) {
  std::printf("Tesselator (particles), motion %s, %zu renders each at %.4g Hz after settling; wall-clock ms (machine "
              "may be shared)\n", a.motion.c_str(), reports.empty() ? size_t(0) : reports[0].rows.size(), a.hz);
  auto row = [&](const char* label, auto value) {
    std::printf("%-30s", label);
    for (const Report& r : reports) std::printf(" %18s", value(r).c_str());
    std::printf("\n");
  };
  auto fmt = [](const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return std::string(b);
  };
  auto num = [&](size_t v) { return fmt("%.0f", double(v)); };
  auto pct = [&](const Report& r, size_t n) {
    return num(n) + fmt(" (%.1f%%)", 100.0 * double(n) / double(std::max<size_t>(r.rows.size(), 1)));
  };
  row("", [](const Report& r) { return r.name; });
  row("Particle sim (ms/update)", [&](const Report& r) { return fmt("%.3f", r.sim); });
  row("Add/Del (ms/update)", [&](const Report& r) { return fmt("%.3f", r.addDel); });
  row("Mesh update (ms/render)", [&](const Report& r) { return fmt("%.3f", r.mesh); });
  row("Update+mesh (ms)", [&](const Report& r) { return fmt("%.3f", r.sim + r.addDel + r.mesh); });
  row("Updates+mesh per second", [&](const Report& r) { return fmt("%.0f", 1000.0 / (r.sim + r.addDel + r.mesh)); });
  row("Num particles", [&](const Report& r) { return num(r.particles); });
  row("Num tris", [&](const Report& r) { return num(r.tris); });
  row("Renders with holes", [&](const Report& r) { return pct(r, r.count(&RenderRow::boundaryEdges)); });
  row("Boundary edges (max)", [&](const Report& r) { return num(r.max(&RenderRow::boundaryEdges)); });
  row("Renders non-manifold", [&](const Report& r) { return pct(r, r.nonManifoldRenders()); });
  row("Non-manifold edges (max)", [&](const Report& r) { return num(r.max(&RenderRow::nonManifoldEdges)); });
  row("Non-manifold vertices (max)", [&](const Report& r) { return num(r.max(&RenderRow::nonManifoldVertices)); });
  row("Renders with folds", [&](const Report& r) { return pct(r, r.count(&RenderRow::foldedTriangles)); });
  row("Folded triangles (max)", [&](const Report& r) { return num(r.max(&RenderRow::foldedTriangles)); });
  row("Renders with MC fallback", [&](const Report& r) { return pct(r, r.count(&RenderRow::fallback)); });
  row("  of them for a part cut off",
      [&](const Report& r) { return pct(r, r.count(&RenderRow::particleCutOffParts)); });
  row("Renders with parts cut off", [&](const Report& r) { return pct(r, r.count(&RenderRow::cutOffParts)); });
  row("Renders with solids cut off", [&](const Report& r) { return pct(r, r.count(&RenderRow::cutOffSolids)); });
  row("Renders missing components", [&](const Report& r) { return pct(r, r.count(&RenderRow::missingComponents)); });
  row("Renders missing solids", [&](const Report& r) { return pct(r, r.count(&RenderRow::missingSolids)); });
  row("Largest missing (mm across)",
      [&](const Report& r) { return fmt("%.3g", r.worst(&RenderRow::largestMissingMm)); });
  row("Worst |F-iso| at a vertex", [&](const Report& r) { return fmt("%.3g", r.worst(&RenderRow::worstFieldError)); });
  row("Worst vertex offset (mm)", [&](const Report& r) { return fmt("%.3g", r.worst(&RenderRow::worstOffsetMm)); });
  row("Worst sample dist (mm)", [&](const Report& r) { return fmt("%.2f", r.worstMm); });
  row("Updates to settle", [&](const Report& r) { return num(size_t(r.settleUpdates)); });
  row("Updates to still",
      [&](const Report& r) { return r.updatesToStill < 0 ? std::string("never") : num(size_t(r.updatesToStill)); });
  row("Settled fissions/update", [&](const Report& r) { return fmt("%.2f", r.fissionsPerUpdateSettled); });
  row("Settled fusions/update", [&](const Report& r) { return fmt("%.2f", r.fusionsPerUpdateSettled); });
  row("Settled max motion (dR/upd)", [&](const Report& r) { return fmt("%.3f", r.settledMaxMotion); });
  row("Settled mesh identical", [&](const Report& r) { return std::string(r.settledMeshIdentical ? "yes" : "no"); });
}

int runBench(const BenchArgs& a) {
  Motion motion;
  if (int code = parseMotion(a.motion, motion); code != kExitOk) return code;
  if (!a.csv.empty())
    if (int code = checkOutputPath("bench", "--csv", a.csv, {".csv"}); code != kExitOk) return code;
  std::vector<Report> reports;
  {
    Progress progress("bench");
    for (const std::string& s : a.scenes) {
      auto r = benchScene(s, motion, a, progress);
      progress.done();
      if (!r) return kExitInvalidInput;
      reports.push_back(std::move(*r));
    }
  }
  if (!a.csv.empty()) {
    if (auto saved = writeFileAtomically(a.csv, csvText(reports)); !saved) {
      std::fprintf(stderr, "puppeteer bench: error: %s\n", saved.error().message.c_str());
      return kExitIoError;
    }
  }
  if (a.json) {
    Json scenes = Json::array();
    for (const Report& r : reports) scenes.push_back(reportJson(r));
    printJson(Json{{"motion", a.motion},
                   {"hz", a.hz},
                   {"renders", reports.empty() ? size_t(0) : reports[0].rows.size()},
                   {"scenes", std::move(scenes)}});
    return kExitOk;
  }
  printTable(a, reports);
  return kExitOk;
}

}  // namespace

void addTesselatorCommands(CLI::App& app, Commands& commands) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("bench", "Time the particle tesselator on scenes (thesis Table 3.1 report) and "
                                              "check every render's mesh");
  cmd->add_option("scenes", a->scenes, "Scene files (.wrl)")->required()->check(inputFile());
  cmd->add_option("--motion", a->motion,
                  "static, swing:DEG_PER_S (limbs swing +-45 degrees), or a take: FILE.session or FILE.bvh "
                  "(retargeted as replay does)");
  cmd->add_option("--map", a->map, "For a clip: auto, names or a joint map FILE.json (docs/calibration.md)")
      ->capture_default_str();
  cmd->add_option("--renders,--updates", a->renders,
                  "Renders after settling (default 300; a take: all its frames at --hz, looping if more)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--hz", a->hz, "Renders per second of motion (the swing's step, the take's resampling)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--threads", a->threads, "Worker threads (0: all cores; default: the scene's numThreads)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--desired-radius", a->desiredRadius,
                  "Particle spacing (m) instead of the scene's; queryRadius and the hash cube scale with it")
      ->check(positiveNumber());
  cmd->add_flag("--uniform-spacing", a->uniformSpacing,
                "One particle spacing everywhere, as the thesis (default: a smaller one on parts thinner than it)");
  cmd->add_option("--csv", a->csv, "Write one line per render (topology, folds, |F-iso|, particles, fissions) here");
  cmd->add_flag("--json", a->json, "Print the report as JSON (for scripts)");
  commands.push_back({cmd, [a] { return runBench(*a); }});
}

}  // namespace imps::app
