// `puppeteer bench`: the particle tesselator's Table 3.1-style report (ms per phase, particles, triangles, boundary
// edges, accuracy), for a static pose or limbs swinging at a given angular speed.
#include "cli.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/parallel.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "json_output.h"
#include "progress.h"

namespace imps::app {
namespace {

struct BenchArgs {
  std::vector<std::string> scenes;
  std::string motion = "static";
  int updates = 300;
  int threads = -1;  // -1: the scene's numThreads
  bool json = false;
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

struct Report {
  std::string name;
  double sim = 0, addDel = 0, mesh = 0;
  size_t particles = 0, tris = 0, maxBoundary = 0, framesWithHoles = 0, frames = 0;
  double worstMm = 0;
  int settleUpdates = 0;
};

std::optional<Report> benchScene(const std::string& path, double degPerSecond, int frames, int threads,
                                 Progress& progress) {
  const auto loaded = loadScene(path);
  if (!loaded) return std::nullopt;
  const Character& ch = loaded->character;
  TesselatorOptions o;
  if (const auto* node = std::get_if<Tesselator3MPNode>(&loaded->scene.polygonizer)) o = TesselatorOptions::fromNode(*node);
  if (threads >= 0) o.numThreads = threads;
  SkeletonCache skel(ch);
  Tesselator tess(o);
  Mesh mesh;
  Report r;
  r.name = path.substr(path.find_last_of('/') + 1);
  progress.phase(r.name + ": settling");
  r.settleUpdates = tess.settle(skel, mesh, 400);

  const std::vector<int> joints = swingJoints(ch);
  std::vector<glm::quat> rest;
  for (int j : joints) rest.push_back(skel.local(j).rotation);
  const double frameSeconds = 1.0 / 30.0;  // the motion advances one 30 Hz frame per render
  const double amplitude = 45.0;           // degrees: a triangle wave between -45 and +45
  double angle = 0.0, direction = 1.0;
  for (int f = 0; f < frames; ++f) {
    if (f % 10 == 0) progress.phase(r.name + ": render " + std::to_string(f + 1) + "/" + std::to_string(frames));
    if (degPerSecond > 0.0) {
      angle += direction * degPerSecond * frameSeconds;
      if (angle > amplitude) angle = 2 * amplitude - angle, direction = -1.0;
      if (angle < -amplitude) angle = -2 * amplitude - angle, direction = 1.0;
      for (size_t k = 0; k < joints.size(); ++k) {
        const float a = float(glm::radians(angle)) * (k % 2 == 0 ? 1.0f : -1.0f);
        skel.setRotation(joints[k], rest[k] * glm::angleAxis(a, glm::vec3(0, 0, 1)));
      }
      skel.update();
    }
    for (int u = 0; u < o.updatesPerRender; ++u) {
      tess.update(skel);
      r.sim += tess.stats().simulateMs;
      r.addDel += tess.stats().addDeleteMs;
    }
    tess.triangulate(mesh);
    r.mesh += tess.stats().meshMs;
    r.maxBoundary = std::max(r.maxBoundary, tess.stats().boundaryEdges);
    r.framesWithHoles += tess.stats().boundaryEdges > 0 ? 1 : 0;
    ++r.frames;
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

int runBench(const BenchArgs& a) {
  double rate = 0.0;
  if (a.motion != "static") {
    if (a.motion.rfind("swing:", 0) != 0) {
      std::fprintf(stderr, "puppeteer bench: error: --motion must be static or swing:DEG_PER_S, got '%s'\n",
                   a.motion.c_str());
      return kExitUsage;
    }
    try {
      rate = std::stod(a.motion.substr(6));
    } catch (...) {
      std::fprintf(stderr, "puppeteer bench: error: bad angular speed in '%s'\n", a.motion.c_str());
      return kExitUsage;
    }
    if (!(rate >= 0.0 && rate < 1e5)) {
      std::fprintf(stderr, "puppeteer bench: error: angular speed out of range in '%s'\n", a.motion.c_str());
      return kExitUsage;
    }
  }
  std::vector<Report> reports;
  {
    Progress progress("bench");
    for (const std::string& s : a.scenes) {
      auto r = benchScene(s, rate, a.updates, a.threads, progress);
      progress.done();
      if (!r) return kExitInvalidInput;
      reports.push_back(*r);
    }
  }
  if (a.json) {
    Json scenes = Json::array();
    for (const Report& r : reports)
      scenes.push_back({{"scene", r.name},
                        {"simulateMsPerUpdate", r.sim},
                        {"addDeleteMsPerUpdate", r.addDel},
                        {"meshMsPerRender", r.mesh},
                        {"particles", r.particles},
                        {"triangles", r.tris},
                        {"maxBoundaryEdges", r.maxBoundary},
                        {"rendersWithHoles", r.framesWithHoles},
                        {"renders", r.frames},
                        {"worstSampleDistanceMm", r.worstMm},
                        {"updatesToSettle", r.settleUpdates}});
    printJson(Json{{"motion", a.motion}, {"renders", a.updates}, {"scenes", std::move(scenes)}});
    return kExitOk;
  }
  std::printf("Tesselator (particles), motion %s, %d renders each after settling; wall-clock ms (machine may be "
              "shared)\n", a.motion.c_str(), a.updates);
  auto row = [&](const char* label, auto value) {
    std::printf("%-26s", label);
    for (const Report& r : reports) std::printf(" %18s", value(r).c_str());
    std::printf("\n");
  };
  auto fmt = [](const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return std::string(b);
  };
  row("", [](const Report& r) { return r.name; });
  row("Particle sim (ms/update)", [&](const Report& r) { return fmt("%.3f", r.sim); });
  row("Add/Del (ms/update)", [&](const Report& r) { return fmt("%.3f", r.addDel); });
  row("Mesh update (ms/render)", [&](const Report& r) { return fmt("%.3f", r.mesh); });
  row("Update+mesh (ms)", [&](const Report& r) { return fmt("%.3f", r.sim + r.addDel + r.mesh); });
  row("Updates+mesh per second", [&](const Report& r) { return fmt("%.0f", 1000.0 / (r.sim + r.addDel + r.mesh)); });
  row("Num particles", [&](const Report& r) { return fmt("%.0f", double(r.particles)); });
  row("Num tris", [&](const Report& r) { return fmt("%.0f", double(r.tris)); });
  row("Boundary edges (max)", [&](const Report& r) { return fmt("%.0f", double(r.maxBoundary)); });
  row("Renders with holes", [&](const Report& r) { return fmt("%.0f", double(r.framesWithHoles)); });
  row("Renders with holes (%)",
      [&](const Report& r) { return fmt("%.1f", 100.0 * double(r.framesWithHoles) / double(std::max<size_t>(r.frames, 1))); });
  row("Worst sample dist (mm)", [&](const Report& r) { return fmt("%.2f", r.worstMm); });
  row("Updates to settle", [&](const Report& r) { return fmt("%.0f", double(r.settleUpdates)); });
  return kExitOk;
}

}  // namespace

void addTesselatorCommands(CLI::App& app, Commands& commands) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* cmd = app.add_subcommand("bench", "Time the particle tesselator on scenes (thesis Table 3.1 report)");
  cmd->add_option("scenes", a->scenes, "Scene files (.wrl)")->required()->check(inputFile());
  cmd->add_option("--motion", a->motion, "static, or swing:DEG_PER_S (limbs swing +-45 degrees, 30 Hz renders)");
  cmd->add_option("--updates", a->updates, "Renders to time after settling")->check(CLI::Range(1, 1000000));
  cmd->add_option("--threads", a->threads, "Worker threads (0: all cores; default: the scene's numThreads)")
      ->check(CLI::Range(0, 1024));
  cmd->add_flag("--json", a->json, "Print the report as JSON (for scripts)");
  commands.push_back({cmd, [a] { return runBench(*a); }});
}

}  // namespace imps::app
