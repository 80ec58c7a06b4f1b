// SPDX-License-Identifier: MIT
// `puppeteer mesh` and `puppeteer check`: scene files to meshes, and scene validation.
#include "cli.h"
#include "cli_world.h"
#include "clip_pose.h"
#include "prop_attachment.h"
#include "imps/vrml_props.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <memory>
#include <cstdio>
#include <string>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh_io.h"
#include "imps/parallel.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "imps/texturing.h"
#include "json_output.h"
#include "progress.h"
#include "snapshot.h"
#include "textured_export.h"
#include "textures.h"
#include "world_scene.h"
#include "imps/mesh_objects.h"

namespace imps::app {
namespace {

struct MeshArgs {
  std::string scene, output;
  float cell = 0.0f;
  int res = 0;
  int threads = 0;
  bool noThin = false;
  std::string polygonizer = "mc";
  int updates = 0;  // particles: 0 = until settled
  size_t maxCells = MarchingCubesOptions{}.maxCells;
  size_t maxParticles = TesselatorOptions{}.maxParticles;
  bool check = false;
  bool json = false;
  std::vector<std::string> props;   // --prop FILE.wrl[@JOINT]: props written as objects of their own
  std::vector<std::string> drives;  // a world: --drive NAME=CLIP
  double at = 0.0;                  // a world: the time its clips are sampled at
};

// The objects of `objects` written to `output` (each its own glTF node / OBJ object; PLY merged). Prints the result.
int writeObjects(const char* command, const std::string& input, const std::vector<NamedMesh>& objects,
                 const std::string& output, bool json) {
  if (auto written = writeMeshObjects(objects, output); !written) {
    std::fprintf(stderr, "puppeteer %s: error: %s\n", command, written.error().all().front().message.c_str());
    return kExitIoError;
  }
  size_t triangles = 0;
  Json list = Json::array();
  for (const NamedMesh& o : objects) {
    triangles += o.mesh->triangleCount();
    list.push_back({{"name", o.name}, {"triangles", o.mesh->triangleCount()}});
  }
  if (json) {
    printJson(Json{{"scene", input}, {"output", output}, {"objects", std::move(list)}, {"triangles", triangles}});
  } else {
    std::printf("%s: %zu objects, %zu triangles, written to %s%s\n", input.c_str(), objects.size(), triangles,
                output.c_str(), extensionOf(output) == ".ply" ? " (merged: PLY has no objects)" : "");
  }
  return kExitOk;
}

// `mesh WORLD`: every character posed at --at and every prop, each its own object.
int runWorldMesh(const MeshArgs& a) {
  if (!a.props.empty() || a.polygonizer != "mc" || a.check) {
    std::fprintf(stderr, "puppeteer mesh: error: %s is a world: --prop, --polygonizer particles and --check apply to "
                         "one character scene\n", a.scene.c_str());
    return kExitUsage;
  }
  auto world = loadWorld(a.scene);
  if (!world) return kExitInvalidInput;
  auto sources = driveSources(*world, a.drives);
  if (!sources) return kExitUsage;
  MarchingCubesOptions options;
  options.threads = a.threads;
  options.preserveThinFeatures = !a.noThin;
  options.cellSize = a.cell;
  if (a.res > 0) options.resolution = a.res;
  options.maxCells = a.maxCells;
  auto objects = poseWorld(*world, *sources, a.at, options, nullptr, "mesh");
  if (!objects) return kExitInvalidInput;
  for (const WorldCharacter& c : world->characters)
    if (c.character.textured())
      std::fprintf(stderr, "puppeteer mesh: note: %s's textures are not written with the world's objects (its vertex "
                           "colours are)\n", c.name.c_str());
  std::vector<NamedMesh> named;
  for (const WorldObject& o : *objects) named.push_back({o.name, &o.mesh});
  return writeObjects("mesh", a.scene, named, a.output, a.json);
}

Json topologyJson(const MeshTopology& t) {
  return Json{{"closedManifold", t.closedManifold()}, {"boundaryEdges", t.boundaryEdges},
              {"nonManifoldEdges", t.nonManifoldEdges}, {"nonManifoldVertices", t.nonManifoldVertices},
              {"orientationConflicts", t.orientationConflicts}, {"components", t.components},
              {"eulerCharacteristic", t.eulerCharacteristic}};
}

// With --check: the mesh's topology, one line (or into the --json report), and whether it is a closed 2-manifold.
bool reportTopology(const Mesh& mesh, Progress& progress, Json* json) {
  progress.phase("checking the topology of " + std::to_string(mesh.triangleCount()) + " triangles");
  const MeshTopology t = analyzeTopology(mesh);
  progress.done();
  if (json) {
    (*json)["topology"] = topologyJson(t);
    return t.closedManifold();
  }
  std::printf("topology: %s: %zu boundary edges, %zu non-manifold edges, %zu non-manifold vertices, %zu orientation "
              "conflicts, %zu components, Euler characteristic %ld\n",
              t.closedManifold() ? "closed 2-manifold" : "NOT a closed 2-manifold", t.boundaryEdges,
              t.nonManifoldEdges, t.nonManifoldVertices, t.orientationConflicts, t.components, t.eulerCharacteristic);
  return t.closedManifold();
}

// The status line follows Marching Cubes' own progress ("polygonizing 42 %") when it is shown.
void followPolygonizing(Progress& progress, MarchingCubesOptions& options) {
  progress.phase("polygonizing");
  if (!progress.enabled()) return;
  options.progress = [&progress](float fraction) {
    progress.phase("polygonizing " + std::to_string(int(fraction * 100.0f)) + " %");
  };
}

// A Marching Cubes grid beyond --max-cells is refused before any work: the message says where its size came from
// (`source`: "--cell 1e-09", or the scene's cellSize / x/y/zResolution at file:line:column) and how to go further.
bool gridRefused(const char* command, const Field& field, const MarchingCubesOptions& options,
                 const std::string& source) {
  auto plan = planGrid(field, options);
  if (plan) return false;
  std::fprintf(stderr, "puppeteer %s: error: %s: %s; use larger cells, or raise the limit with --max-cells N\n",
               command, source.c_str(), plan.error().all().front().message.c_str());
  return true;
}

// Where a Marching Cubes resolution came from, for gridRefused.
std::string resolutionSource(float cell, int res, const MarchingCubesNode* node) {
  char text[64];
  if (cell > 0.0f) std::snprintf(text, sizeof text, "--cell %g", double(cell));
  else if (res > 0) std::snprintf(text, sizeof text, "--res %d", res);
  else if (node && node->resolutionLoc.line > 0)
    return node->resolutionLoc.file + ":" + std::to_string(node->resolutionLoc.line) + ":" +
           std::to_string(node->resolutionLoc.column) + ": the scene's MarchingCubes resolution";
  else std::snprintf(text, sizeof text, "the default resolution");
  return text;
}

// "1 air pocket", "2 air pockets".
std::string count(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Whether a particle mesh covers the surface: its components match those Marching Cubes finds at half desiredRadius
// one for one (matchComponents: none missing, none cut off), and at least 90 % of the particles are in a triangle (a
// settled mesh leaves out only the few particles that are off the surface this render, 0-2 %). "" if so, else what
// is wrong ("leaves 1419 of 1677 particles out of every triangle").
std::string particleCoverage(const Mesh& mesh, const Field& field, const TesselatorOptions& options,
                             Progress& progress, Json* json) {
  progress.phase("comparing the particle mesh's components with Marching Cubes");
  const MeshTopology t = analyzeTopology(mesh);
  MarchingCubesOptions mc;
  mc.cellSize = 0.5f * options.desiredRadius;
  mc.threads = options.threads;
  const ComponentMatch match = matchComponents(mesh, planGrid(field, mc) ? polygonize(field, mc) : Mesh{});
  progress.done();
  if (json) {
    (*json)["unusedParticles"] = t.unusedVertices;
    (*json)["marchingCubesComponents"] = match.referenceComponents;
    (*json)["missingComponents"] = match.missing;
    (*json)["missingCavities"] = match.missingCavities;
    (*json)["largestMissingComponent"] = match.largestMissing;
    (*json)["cutOffComponents"] = match.cutOff;
    (*json)["cutOffCavities"] = match.cutOffCavities;
  } else {
    std::string missing = std::to_string(match.missing) + " missing", cut = std::to_string(match.cutOff) + " cut off";
    char largest[64];
    std::snprintf(largest, sizeof largest, "the largest %.3g m across", double(match.largestMissing));
    if (match.missing > 0)
      missing +=
          " (" +
          (match.missingCavities > 0 ? count(match.missingCavities, "enclosed cavity", "enclosed cavities") + "; "
                                     : "") +
          largest + ")";
    if (match.cutOffCavities > 0) cut += " (" + count(match.cutOffCavities, "air pocket", "air pockets") + ", closed)";
    std::printf("coverage: %zu of %zu particles in no triangle; %zu components (Marching Cubes at %g m: %zu; %s, %s)\n",
                t.unusedVertices, mesh.vertexCount(), match.components, double(mc.cellSize), match.referenceComponents,
                missing.c_str(), cut.c_str());
  }
  std::vector<std::string> wrong;
  if (match.missing > 0)
    wrong.push_back(
        "misses " + std::to_string(match.missing) + " of the " + std::to_string(match.referenceComponents) +
        " components Marching Cubes finds" +
        (match.missingCavities > 0
             ? " (" + count(match.missingCavities, "enclosed cavity", "enclosed cavities") + ": air inside the solid)"
             : ""));
  if (match.cutOff > 0)
    wrong.push_back("cuts " + std::to_string(match.cutOff) + (match.cutOff == 1 ? " part" : " parts") +
                    " off (separate pieces where Marching Cubes finds one surface" +
                    (match.cutOffCavities > 0 ? "; " + count(match.cutOffCavities, "air pocket", "air pockets") +
                                                    " closed by the particles, open in Marching Cubes)"
                                              : ")"));
  if (t.unusedVertices * 10 > mesh.vertexCount())
    wrong.push_back("leaves " + std::to_string(t.unusedVertices) + " of " + std::to_string(mesh.vertexCount()) +
                    " particles out of every triangle (parts of the surface are missing)");
  std::string out;
  for (const std::string& w : wrong) out += (out.empty() ? "" : " and ") + w;
  return out;
}

// --polygonizer particles: the tesselator run until settled (or --updates N), its triangulation written.
int runParticleMesh(const MeshArgs& a, const Scene& scene, const SkeletonCache& skeleton,
                    const std::vector<RgbaImage>& images, Progress& progress) {
  // Without a Tesselator3MP node the lengths follow the scene's feature size (TesselatorOptions::forScene).
  const auto* node = std::get_if<Tesselator3MPNode>(&scene.polygonizer);
  TesselatorOptions options = TesselatorOptions::forScene(scene, skeleton.field());
  if (a.threads > 0) options.threads = a.threads;
  options.maxParticles = a.maxParticles;
  options.closedFallback = false;  // the particles' own triangulation is written, and checked below
  Tesselator tess(options);
  Mesh mesh;
  int updates = a.updates;
  if (updates > 0) {
    for (int u = 0; u < updates; ++u) {
      progress.phase("particle update " + std::to_string(u + 1) + "/" + std::to_string(updates));
      tess.update(skeleton);
    }
    tess.triangulate(mesh);
  } else {
    progress.phase("settling the particles");
    updates = tess.settle(skeleton, mesh);
  }
  progress.phase("writing " + a.output);
  textureMesh(mesh, skeleton, options.threads);
  tess.carryTexcoords(mesh);
  if (auto written = writeTexturedMesh(mesh, skeleton.character(), images, a.output); !written) {
    progress.done();
    std::fprintf(stderr, "puppeteer mesh: error: %s\n", written.error().all().front().message.c_str());
    return kExitIoError;
  }
  progress.done();
  Json json{{"scene", a.scene}, {"output", a.output}, {"polygonizer", "particles"},
            {"particles", mesh.vertexCount()}, {"triangles", mesh.triangleCount()}, {"updates", updates},
            {"desiredRadius", options.desiredRadius}};
  if (!a.json)
    std::printf("%s: %zu particles, %zu triangles after %d updates (desiredRadius %g m%s), written to %s\n",
                a.scene.c_str(), mesh.vertexCount(), mesh.triangleCount(), updates, double(options.desiredRadius),
                node ? "" : ", from the scene's feature size", a.output.c_str());
  if (tess.particles().size() >= options.maxParticles) {
    const SourceLoc at = node ? node->desiredRadiusLoc : SourceLoc{};
    std::fprintf(stderr,
                 "%s: warning: the particles reached their limit of %zu (desiredRadius %g m is small for this "
                 "character), so the surface is sampled more coarsely than asked; use a larger desiredRadius, or "
                 "raise the limit with --max-particles N\n",
                 at.line > 0 ? (at.file + ":" + std::to_string(at.line) + ":" + std::to_string(at.column)).c_str()
                             : a.scene.c_str(),
                 options.maxParticles, double(options.desiredRadius));
  }
  // Always checked (a particle mesh is small), --check or not: closed, and covering the whole surface.
  const bool closed = reportTopology(mesh, progress, a.json ? &json : nullptr);
  const std::string uncovered = particleCoverage(mesh, skeleton.field(), options, progress, a.json ? &json : nullptr);
  if (a.json) printJson(json);
  if (!closed) {
    std::fprintf(stderr,
                 "puppeteer mesh: error: the particle mesh is not a closed 2-manifold (written all the same)\n");
    return kExitCheckFailed;
  }
  if (!uncovered.empty()) {
    std::fprintf(stderr, "puppeteer mesh: error: the particle mesh %s (written all the same)\n", uncovered.c_str());
    return kExitCheckFailed;
  }
  return kExitOk;
}

int runMesh(const MeshArgs& a) {
  if (int rc = checkOutputPath("mesh", "-o", a.output, {".obj", ".ply", ".glb"}); rc != kExitOk) return rc;
  if (isWorldFile(a.scene)) return runWorldMesh(a);
  if (!a.drives.empty() || a.at != 0.0) {
    std::fprintf(stderr, "puppeteer mesh: error: --drive and --at need a world file (docs/world-format.md#worlds)\n");
    return kExitUsage;
  }
  if (!a.props.empty() && a.polygonizer != "mc") {
    std::fprintf(stderr, "puppeteer mesh: error: --prop is written with Marching Cubes meshes only\n");
    return kExitUsage;
  }
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Scene& scene = loaded->scene;
  const Character& character = loaded->character;
  const auto images = loadTextures(character);
  if (!images) {
    std::fputs(images.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }

  // Resolution: the command line, else the scene's MarchingCubes node, else 64 cells along the longest side.
  MarchingCubesOptions options;
  options.threads = a.threads;
  options.preserveThinFeatures = !a.noThin;
  if (const auto* mc = std::get_if<MarchingCubesNode>(&scene.polygonizer)) {
    options.cellSize = mc->cellSize;
    options.gridResolution = {mc->xResolution, mc->yResolution, mc->zResolution};
    if (a.threads == 0) options.threads = mc->numThreads;
  }
  if (a.cell > 0.0f || a.res > 0) {
    options.cellSize = a.cell;
    options.gridResolution = glm::ivec3(0);
    if (a.res > 0) options.resolution = a.res;
  }

  options.maxCells = a.maxCells;
  SkeletonCache skeleton(character);
  Progress progress("mesh");
  if (a.polygonizer == "particles") return runParticleMesh(a, scene, skeleton, *images, progress);
  if (gridRefused("mesh", skeleton.field(), options,
                  resolutionSource(a.cell, a.res, std::get_if<MarchingCubesNode>(&scene.polygonizer))))
    return a.cell > 0.0f || a.res > 0 ? kExitUsage : kExitInvalidInput;  // the command line's value, or the file's
  MarchingCubesStats stats;
  followPolygonizing(progress, options);
  Mesh mesh = polygonize(skeleton.field(), options, &stats);
  textureMesh(mesh, skeleton, options.threads);

  if (!a.props.empty()) {
    // The character and each prop its own object (glTF node, OBJ object); textures are not written then.
    Diagnostics propWarnings;
    auto props = loadProps(a.props, character, &propWarnings);
    std::fputs(propWarnings.str().c_str(), stderr);
    progress.done();
    if (!props) {
      std::fputs(props.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    std::vector<Mesh> posed;
    posed.reserve(props->size());
    for (const AttachedProp& p : *props)
      posed.push_back(p.joint >= 0 ? transformed(p.mesh, skeleton.world(p.joint)) : p.mesh);
    std::vector<NamedMesh> named{{std::filesystem::path(a.scene).stem().string(), &mesh}};
    for (size_t k = 0; k < props->size(); ++k) named.push_back({(*props)[k].name, &posed[k]});
    if (character.textured())
      std::fprintf(stderr, "puppeteer mesh: note: with --prop the character's textures are not written (its vertex "
                           "colours are)\n");
    return writeObjects("mesh", a.scene, named, a.output, a.json);
  }
  progress.phase("writing " + std::to_string(mesh.triangleCount()) + " triangles to " + a.output);
  const auto writeStart = std::chrono::steady_clock::now();
  if (auto written = writeTexturedMesh(mesh, character, *images, a.output); !written) {
    progress.done();
    std::fprintf(stderr, "puppeteer mesh: error: %s\n", written.error().all().front().message.c_str());
    return kExitIoError;
  }
  const double writeMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - writeStart).count();
  progress.done();
  if (a.json) {
    Json json{{"scene", a.scene},
              {"output", a.output},
              {"polygonizer", "mc"},
              {"vertices", mesh.vertexCount()},
              {"triangles", mesh.triangleCount()},
              {"polygonizeMs", stats.milliseconds},
              {"writeMs", writeMs},
              {"grid", {stats.cells.x, stats.cells.y, stats.cells.z}},
              {"cellSize", stats.cellSize.x},
              {"threads", resolveThreads(options.threads)},
              {"thinFeatureVertices", stats.thinFeatureVertices}};
    const bool closed = !a.check || reportTopology(mesh, progress, &json);
    printJson(json);
    return closed ? kExitOk : kExitCheckFailed;
  }
  std::printf("%s: %zu vertices, %zu triangles, polygonized in %.2f ms (grid %dx%dx%d, cell %.4g m, %d threads), "
              "written in %.1f ms to %s\n",
              a.scene.c_str(), mesh.vertexCount(), mesh.triangleCount(), stats.milliseconds, stats.cells.x,
              stats.cells.y, stats.cells.z, double(stats.cellSize.x), resolveThreads(options.threads), writeMs,
              a.output.c_str());
  if (stats.thinFeatureVertices > 0)
    std::printf("note: %zu grid vertices moved onto thin limbs to keep them (cell larger than the limb)\n",
                stats.thinFeatureVertices);
  if (a.check && !reportTopology(mesh, progress, nullptr)) return kExitCheckFailed;
  return kExitOk;
}

const char* kindName(PrimitiveKind k) {
  switch (k) {
    case PrimitiveKind::Metaball: return "Metaball";
    case PrimitiveKind::Ellipsoid: return "Ellipsoid";
    case PrimitiveKind::LineSeg: return "LineSeg";
  }
  return "?";
}

const char* blendName(BlendKind k) {
  switch (k) {
    case BlendKind::Exponential: return "ExponentialBlend";
    case BlendKind::BlancSchlick: return "BlancSchlickBlend";
    case BlendKind::Elliptical: return "EllipticalBlend";
  }
  return "?";
}

// check --json: the same listing as one document.
Json checkJson(const std::string& path, const Character& c) {
  Json joints = Json::array(), primitives = Json::array(), sets = Json::array();
  for (const Joint& joint : c.joints())
    joints.push_back({{"name", joint.name},
                      {"parent", joint.parent >= 0 ? Json(c.joints()[size_t(joint.parent)].name) : Json(nullptr)}});
  for (const CharacterPrimitive& p : c.primitives())
    primitives.push_back({{"name", p.name},
                          {"kind", kindName(p.local.kind)},
                          {"joint", p.joint >= 0 ? Json(c.joints()[size_t(p.joint)].name) : Json(nullptr)},
                          {"blendParam", p.blendParam},
                          {"color", {p.color.r, p.color.g, p.color.b}}});
  for (size_t s = 0; s < c.blendSets().count(); ++s) {
    Json members = Json::array();
    for (uint32_t m : c.blendSets().set(s)) members.push_back(c.primitives()[m].name);
    sets.push_back(std::move(members));
  }
  return Json{{"file", path},        {"valid", true},           {"hierarchical", c.hierarchical()},
              {"blend", blendName(c.blend().kind)}, {"isoValue", c.iso()}, {"joints", std::move(joints)},
              {"primitives", std::move(primitives)}, {"blendSets", std::move(sets)}};
}

int runCheck(const std::string& path, bool json) {
  if (isWorldFile(path)) return runWorldCheck(path, json);  // a VRML 97 world or clip (docs/world-format.md)
  auto loaded = loadScene(path);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;
  const Character& c = character;
  if (json) {
    printJson(checkJson(path, c));
    return kExitOk;
  }
  std::printf("%s: valid, %s scene, %s, iso-value %g\n", path.c_str(), c.hierarchical() ? "hierarchical" : "flat",
              blendName(c.blend().kind), double(c.iso()));

  std::printf("joints (%zu):\n", c.joints().size());
  std::vector<int> depth(c.joints().size(), 0);
  for (size_t j = 0; j < c.joints().size(); ++j) {
    const Joint& joint = c.joints()[j];
    if (joint.parent >= 0) depth[j] = depth[size_t(joint.parent)] + 1;
    std::printf("  %*s%s\n", 2 * depth[j], "", joint.name.c_str());
  }
  std::printf("primitives (%zu):\n", c.primitives().size());
  for (const CharacterPrimitive& p : c.primitives()) {
    std::printf("  %-14s %-9s joint %-14s blendParam %-7g colour %.2f %.2f %.2f\n", p.name.c_str(),
                kindName(p.local.kind), p.joint >= 0 ? c.joints()[size_t(p.joint)].name.c_str() : "-",
                double(p.blendParam), double(p.color.r), double(p.color.g), double(p.color.b));
  }
  std::printf("blend groups (%zu set%s: each primitive blends only within a set; the field is the maximum):\n",
              c.blendSets().count(), c.blendSets().count() == 1 ? "" : "s");
  for (size_t s = 0; s < c.blendSets().count(); ++s) {
    std::string line;
    for (uint32_t m : c.blendSets().set(s)) line += (line.empty() ? "" : " ") + c.primitives()[m].name;
    std::printf("  { %s }\n", line.c_str());
  }
  return kExitOk;
}

struct RenderArgs {
  std::string scene, output;
  float cell = 0.0f;
  int res = 96;
  int width = 800, height = 800;
  std::string view = "three-quarter";
  size_t maxCells = MarchingCubesOptions{}.maxCells;
  bool json = false;
  std::string clip, clipName, map = "names";  // --clip: pose the character from a VRML clip at --at seconds
  double at = 0.0;
  std::vector<std::string> props;  // --prop FILE.wrl[@JOINT]: polygonal props, attached to a joint or in the world
  std::vector<std::string> grabs;  // --grab FILE.wrl@JOINT@PICK:DROP: props picked up and put down (with --clip)
  std::vector<std::string> drives;  // a world: --drive NAME=CLIP
};

// Appends the props of every --grab, moved as the clip's joint carries them at --at (grabbedMotion). False after
// printing the errors.
bool addGrabbedProps(const RenderArgs& a, const Character& character, Mesh& mesh) {
  if (a.grabs.empty()) return true;
  auto driver = ClipDriver::load(a.clip, a.clipName, a.map, character);
  if (!driver) {
    std::fputs(driver.error().str().c_str(), stderr);
    return false;
  }
  for (const std::string& spec : a.grabs) {
    auto grab = parseGrab(spec, character);
    if (!grab) {
      std::fputs(grab.error().str().c_str(), stderr);
      return false;
    }
    Diagnostics warnings;
    auto props = loadProps({grab->first}, character, &warnings);
    std::fputs(warnings.str().c_str(), stderr);
    if (!props) {
      std::fputs(props.error().str().c_str(), stderr);
      return false;
    }
    auto jointWorldAt = [&](double seconds) {
      SkeletonCache posed(character);
      driver->apply(seconds, posed);
      posed.update();
      return posed.world(grab->second.joint);
    };
    const Rigid motion = grabbedMotion(grab->second, a.at, jointWorldAt);
    for (const AttachedProp& p : *props) appendMesh(mesh, transformed(p.mesh, motion));
  }
  return true;
}

glm::vec3 viewDirection(const std::string& view) {
  return view == "front" ? glm::vec3(0, 0, 1) : view == "side" ? glm::vec3(1, 0, 0)
         : view == "top" ? glm::vec3(0, 1, 0) : kFrontThreeQuarter;
}

// `render WORLD`: every character posed at --at by its clip, and every prop, in one picture.
int runWorldRender(const RenderArgs& a) {
  if (!a.clip.empty() || !a.props.empty() || !a.grabs.empty()) {
    std::fprintf(stderr, "puppeteer render: error: %s is a world: --clip, --prop and --grab apply to one character "
                         "scene (inline clips and props in the world; drive characters with --drive NAME=CLIP)\n",
                 a.scene.c_str());
    return kExitUsage;
  }
  auto world = loadWorld(a.scene);
  if (!world) return kExitInvalidInput;
  auto sources = driveSources(*world, a.drives);
  if (!sources) return kExitUsage;
  MarchingCubesOptions options;
  options.cellSize = a.cell;
  options.resolution = a.res;
  options.maxCells = a.maxCells;
  std::vector<RgbaImage> textures;
  auto objects = poseWorld(*world, *sources, a.at, options, &textures, "render");
  if (!objects) return kExitInvalidInput;
  Mesh mesh;
  for (const WorldObject& o : *objects) appendMesh(mesh, o.mesh);
  SnapshotOptions snap;
  snap.textures = &textures;
  snap.width = a.width;
  snap.height = a.height;
  snap.camera = frameMesh(mesh, viewDirection(a.view), float(a.width) / float(a.height));
  if (auto rendered = renderMeshToPng(mesh, snap, a.output); !rendered) {
    std::fprintf(stderr, "puppeteer render: error: %s\n", rendered.error().all().front().message.c_str());
    return kExitIoError;
  }
  if (a.json) {
    printJson(Json{{"scene", a.scene}, {"output", a.output}, {"triangles", mesh.triangleCount()},
                   {"characters", world->characterNames()}, {"props", world->props.size()},
                   {"width", a.width}, {"height", a.height}, {"view", a.view}});
    return kExitOk;
  }
  std::printf("%s: %zu characters, %zu props, %zu triangles rendered to %s (%dx%d, %s view, at %g s)\n",
              a.scene.c_str(), world->characters.size(), world->props.size(), mesh.triangleCount(), a.output.c_str(),
              a.width, a.height, a.view.c_str(), a.at);
  return kExitOk;
}

// Renders the scene's Marching Cubes mesh in software to a PNG: a quick look without a GPU or a display.
int runRender(const RenderArgs& a) {
  if (int rc = checkOutputPath("render", "-o", a.output, {".png"}); rc != kExitOk) return rc;
  if (isWorldFile(a.scene)) return runWorldRender(a);
  if (!a.drives.empty()) {
    std::fprintf(stderr, "puppeteer render: error: --drive needs a world file (docs/world-format.md#worlds)\n");
    return kExitUsage;
  }
  if (a.clip.empty() && a.at != 0.0) {
    std::fprintf(stderr, "puppeteer render: error: --at needs --clip (or a world file)\n");
    return kExitUsage;
  }
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;
  const auto textures = loadTextures(character);
  if (!textures) {
    std::fputs(textures.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  SkeletonCache skeleton(character);
  if (!a.clip.empty()) {
    auto driver = ClipDriver::load(a.clip, a.clipName, a.map, character);
    if (!driver) {
      std::fputs(driver.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    driver->apply(a.at, skeleton);
    skeleton.update();
  }
  MarchingCubesOptions options;
  options.cellSize = a.cell;
  options.resolution = a.res;
  options.maxCells = a.maxCells;
  if (gridRefused("render", skeleton.field(), options, resolutionSource(a.cell, a.cell > 0 ? 0 : a.res, nullptr)))
    return kExitUsage;
  Progress progress("render");
  followPolygonizing(progress, options);
  Mesh mesh = polygonize(skeleton.field(), options);
  textureMesh(mesh, skeleton);
  Diagnostics propWarnings;
  auto props = loadProps(a.props, character, &propWarnings);
  std::fputs(propWarnings.str().c_str(), stderr);
  if (!props) {
    progress.done();
    std::fputs(props.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  appendPosedProps(mesh, *props, skeleton);
  if (!addGrabbedProps(a, character, mesh)) {
    progress.done();
    return kExitInvalidInput;
  }
  progress.phase("rendering " + std::to_string(mesh.triangleCount()) + " triangles");
  SnapshotOptions snap;
  snap.textures = &*textures;
  snap.width = a.width;
  snap.height = a.height;
  snap.camera = frameMesh(mesh, viewDirection(a.view), float(a.width) / float(a.height));
  const auto rendered = renderMeshToPng(mesh, snap, a.output);
  progress.done();
  if (!rendered) {
    std::fprintf(stderr, "puppeteer render: error: %s\n", rendered.error().all().front().message.c_str());
    return kExitIoError;
  }
  if (a.json) {
    printJson(Json{{"scene", a.scene}, {"output", a.output}, {"triangles", mesh.triangleCount()},
                   {"width", a.width}, {"height", a.height}, {"view", a.view}});
    return kExitOk;
  }
  std::printf("%s: %zu triangles rendered to %s (%dx%d, %s view)\n", a.scene.c_str(), mesh.triangleCount(),
              a.output.c_str(), a.width, a.height, a.view.c_str());
  return kExitOk;
}

}  // namespace

void addSceneCommands(CLI::App& app, Commands& commands) {
  auto mesh = std::make_shared<MeshArgs>();
  CLI::App* meshCmd = app.add_subcommand("mesh", "Polygonize a scene with Marching Cubes and write OBJ, PLY or GLB");
  meshCmd->add_option("scene", mesh->scene, "Scene file (.wrl)")->required()->check(inputFile());
  meshCmd->add_option("-o,--output", mesh->output, "Output mesh: .obj, .ply or .glb")->required();
  auto* cellOpt = meshCmd->add_option("--cell", mesh->cell, "Cell size in metres")->check(positiveNumber());
  meshCmd->add_option("--res", mesh->res, "Cells along the longest side of the surface's bounds")
      ->check(CLI::Range(1, 4096))
      ->excludes(cellOpt);
  meshCmd->add_option("--threads", mesh->threads, "Worker threads (0: all cores)")->check(CLI::Range(0, 1024));
  meshCmd->add_flag("--no-thin-features", mesh->noThin, "Do not move grid vertices onto limbs thinner than a cell");
  meshCmd->add_flag("--check", mesh->check,
                    "Also verify and print the mesh's topology; exit 4 when it is not a closed 2-manifold");
  meshCmd->add_option("--polygonizer", mesh->polygonizer, "mc (Marching Cubes, default) or particles (Tesselator3MP)")
      ->check(CLI::IsMember({"mc", "particles"}));
  meshCmd->add_option("--updates", mesh->updates, "particles: updates to run (default: until settled)")
      ->check(CLI::Range(1, 1000000));
  meshCmd
      ->add_option("--max-cells", mesh->maxCells, "Marching Cubes: the most grid cells (default 2^28; more is refused)")
      ->check(positiveNumber());
  meshCmd->add_option("--max-particles", mesh->maxParticles, "particles: the most particles (default 2^18)")
      ->check(positiveNumber());
  meshCmd->add_flag("--json", mesh->json, "Print the report as JSON (for scripts)");
  meshCmd->add_option("--prop", mesh->props,
                      "Also write a VRML 97 file's props, FILE.wrl@JOINT attached to a joint, each its own object "
                      "(glTF node, OBJ object; repeatable)");
  meshCmd->add_option("--drive", mesh->drives,
                      "With a world: NAME=FILE.wrl[#TIMESENSOR] poses the character NAME by that clip (repeatable)");
  meshCmd->add_option("--at", mesh->at, "With a world: the time into the clips, seconds (looping)")
      ->check(nonNegativeNumber());
  commands.push_back({meshCmd, [mesh] { return runMesh(*mesh); }});

  auto checkPath = std::make_shared<std::string>();
  auto checkJsonFlag = std::make_shared<bool>(false);
  CLI::App* checkCmd = app.add_subcommand("check", "Validate a scene; list joints, primitives and blend groups");
  checkCmd->add_option("scene", *checkPath, "Scene file (.wrl)")->required()->check(inputFile());
  checkCmd->add_flag("--json", *checkJsonFlag, "Print the listing as JSON (for scripts)");
  commands.push_back({checkCmd, [checkPath, checkJsonFlag] { return runCheck(*checkPath, *checkJsonFlag); }});

  auto render = std::make_shared<RenderArgs>();
  CLI::App* renderCmd = app.add_subcommand("render", "Render a scene's surface to a PNG in software (no GPU needed)");
  renderCmd->add_option("scene", render->scene, "Scene file (.wrl)")->required()->check(inputFile());
  renderCmd->add_option("-o,--output", render->output, "Output image (.png)")->required();
  auto* renderCell =
      renderCmd->add_option("--cell", render->cell, "Marching Cubes cell size in metres")->check(positiveNumber());
  renderCmd->add_option("--res", render->res, "Cells along the longest side (default 96)")
      ->check(CLI::Range(1, 4096))
      ->excludes(renderCell);
  renderCmd->add_option("--width", render->width, "Image width in pixels")->check(CLI::Range(16, 8192));
  renderCmd->add_option("--height", render->height, "Image height in pixels")->check(CLI::Range(16, 8192));
  renderCmd->add_option("--max-cells", render->maxCells, "The most grid cells (default 2^28; more is refused)")
      ->check(positiveNumber());
  renderCmd->add_option("--view", render->view, "Camera direction")
      ->check(CLI::IsMember({"three-quarter", "front", "side", "top"}));
  renderCmd->add_flag("--json", render->json, "Print the report as JSON (for scripts)");
  auto* renderClip = renderCmd->add_option("--clip", render->clip, "Pose the character from a VRML 97 clip file "
                                                                   "(docs/world-format.md)")->check(inputFile());
  renderCmd->add_option("--at", render->at, "With --clip or a world: the time into the clips, seconds (looping)")
      ->check(nonNegativeNumber());
  renderCmd->add_option("--drive", render->drives,
                        "With a world: NAME=FILE.wrl[#TIMESENSOR] poses the character NAME by that clip (repeatable; "
                        "docs/world-format.md#worlds)");
  renderCmd->add_option("--clip-name", render->clipName, "With --clip: the TimeSensor to play (default: the first)")
      ->needs(renderClip);
  renderCmd->add_option("--map", render->map, "With --clip: names or a joint map FILE.json")->needs(renderClip);
  renderCmd->add_option("--prop", render->props,
                        "Polygonal props from a VRML 97 file, FILE.wrl@JOINT to attach them to a joint (repeatable)");
  renderCmd->add_option("--grab", render->grabs,
                        "With --clip: FILE.wrl@JOINT@PICK:DROP, props the joint picks up at PICK seconds and puts "
                        "down at DROP (repeatable)")
      ->needs(renderClip);
  commands.push_back({renderCmd, [render] { return runRender(*render); }});
}

}  // namespace imps::app
