// `puppeteer mesh` and `puppeteer check`: scene files to meshes, and scene validation.
#include "cli.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <memory>
#include <cstdio>
#include <string>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh_io.h"
#include "imps/parallel.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "snapshot.h"

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
  bool check = false;
};

// With --check: the mesh's topology, one line, and whether it is a closed 2-manifold.
bool reportTopology(const Mesh& mesh) {
  const MeshTopology t = analyzeTopology(mesh);
  std::printf("topology: %s: %zu boundary edges, %zu non-manifold edges, %zu non-manifold vertices, %zu orientation "
              "conflicts, %zu components, Euler characteristic %ld\n",
              t.closedManifold() ? "closed 2-manifold" : "NOT a closed 2-manifold", t.boundaryEdges,
              t.nonManifoldEdges, t.nonManifoldVertices, t.orientationConflicts, t.components, t.eulerCharacteristic);
  return t.closedManifold();
}

// --polygonizer particles: the tesselator run until settled (or --updates N), its triangulation written.
int runParticleMesh(const MeshArgs& a, const Scene& scene, const SkeletonCache& skeleton) {
  TesselatorOptions options;
  if (const auto* node = std::get_if<Tesselator3MPNode>(&scene.polygonizer)) options = TesselatorOptions::fromNode(*node);
  if (a.threads > 0) options.numThreads = a.threads;
  Tesselator tess(options);
  Mesh mesh;
  int updates = a.updates;
  if (updates > 0) {
    for (int u = 0; u < updates; ++u) tess.update(skeleton);
    tess.triangulate(mesh);
  } else {
    updates = tess.settle(skeleton, mesh);
  }
  std::string error;
  if (!writeMesh(mesh, a.output, &error)) {
    std::fprintf(stderr, "puppeteer mesh: error: %s\n", error.c_str());
    return kExitIoError;
  }
  std::printf("%s: %zu particles, %zu triangles after %d updates, written to %s\n", a.scene.c_str(),
              mesh.vertexCount(), mesh.triangleCount(), updates, a.output.c_str());
  if (a.check && !reportTopology(mesh)) return kExitCheckFailed;
  return kExitOk;
}

int runMesh(const MeshArgs& a) {
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Scene& scene = loaded->scene;
  const Character& character = loaded->character;

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

  SkeletonCache skeleton(character);
  if (a.polygonizer == "particles") return runParticleMesh(a, scene, skeleton);
  MarchingCubesStats stats;
  const Mesh mesh = polygonize(skeleton.field(), options, &stats);

  std::string error;
  const auto writeStart = std::chrono::steady_clock::now();
  if (!writeMesh(mesh, a.output, &error)) {
    std::fprintf(stderr, "puppeteer mesh: error: %s\n", error.c_str());
    return kExitIoError;
  }
  const double writeMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - writeStart).count();
  std::printf("%s: %zu vertices, %zu triangles, polygonized in %.2f ms (grid %dx%dx%d, cell %.4g m, %d threads), "
              "written in %.1f ms to %s\n",
              a.scene.c_str(), mesh.vertexCount(), mesh.triangleCount(), stats.milliseconds, stats.cells.x,
              stats.cells.y, stats.cells.z, double(stats.cellSize.x), resolveThreads(options.threads), writeMs,
              a.output.c_str());
  if (stats.thinFeatureVertices > 0)
    std::printf("note: %zu grid vertices moved onto thin limbs to keep them (cell larger than the limb)\n",
                stats.thinFeatureVertices);
  if (a.check && !reportTopology(mesh)) return kExitCheckFailed;
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

int runCheck(const std::string& path) {
  auto loaded = loadScene(path);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;
  const Character& c = character;
  std::printf("%s: valid, %s scene, %s, iso-value %g\n", path.c_str(), c.hierarchical() ? "hierarchical" : "flat",
              blendName(c.blend().kind), double(c.isoValue()));

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
  std::printf("blend groups (%zu sets: each primitive blends only within a set; the field is the maximum):\n",
              c.blendSets().count());
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
};

// Renders the scene's Marching Cubes mesh in software to a PNG: a quick look without a GPU or a display.
int runRender(const RenderArgs& a) {
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;
  SkeletonCache skeleton(character);
  MarchingCubesOptions options;
  options.cellSize = a.cell;
  options.resolution = a.res;
  const Mesh mesh = polygonize(skeleton.field(), options);
  SnapshotOptions snap;
  snap.width = a.width;
  snap.height = a.height;
  const glm::vec3 direction = a.view == "front" ? glm::vec3(0, 0, 1) : a.view == "side" ? glm::vec3(1, 0, 0)
                              : a.view == "top" ? glm::vec3(0, 1, 0) : kFrontThreeQuarter;
  snap.camera = frameMesh(mesh, direction, float(a.width) / float(a.height));
  std::string error;
  if (!renderMeshToPng(mesh, snap, a.output, &error)) {
    std::fprintf(stderr, "puppeteer render: error: %s\n", error.c_str());
    return kExitIoError;
  }
  std::printf("%s: %zu triangles rendered to %s (%dx%d, %s view)\n", a.scene.c_str(), mesh.triangleCount(),
              a.output.c_str(), a.width, a.height, a.view.c_str());
  return kExitOk;
}

}  // namespace

void addSceneCommands(CLI::App& app, Commands& commands) {
  auto mesh = std::make_shared<MeshArgs>();
  CLI::App* meshCmd = app.add_subcommand("mesh", "Polygonize a scene with Marching Cubes and write OBJ, PLY or GLB");
  meshCmd->add_option("scene", mesh->scene, "Scene file (.wrl)")->required()->check(CLI::ExistingFile);
  meshCmd->add_option("-o,--output", mesh->output, "Output mesh: .obj, .ply or .glb")->required();
  auto* cellOpt = meshCmd->add_option("--cell", mesh->cell, "Cell size in metres")->check(CLI::PositiveNumber);
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
  commands.push_back({meshCmd, [mesh] { return runMesh(*mesh); }});

  auto checkPath = std::make_shared<std::string>();
  CLI::App* checkCmd = app.add_subcommand("check", "Validate a scene; list joints, primitives and blend groups");
  checkCmd->add_option("scene", *checkPath, "Scene file (.wrl)")->required();
  commands.push_back({checkCmd, [checkPath] { return runCheck(*checkPath); }});

  auto render = std::make_shared<RenderArgs>();
  CLI::App* renderCmd = app.add_subcommand("render", "Render a scene's surface to a PNG in software (no GPU needed)");
  renderCmd->add_option("scene", render->scene, "Scene file (.wrl)")->required()->check(CLI::ExistingFile);
  renderCmd->add_option("-o,--output", render->output, "Output image (.png)")->required();
  auto* renderCell = renderCmd->add_option("--cell", render->cell, "Marching Cubes cell size in metres")->check(CLI::PositiveNumber);
  renderCmd->add_option("--res", render->res, "Cells along the longest side (default 96)")->check(CLI::Range(1, 4096))->excludes(renderCell);
  renderCmd->add_option("--width", render->width, "Image width in pixels")->check(CLI::Range(16, 8192));
  renderCmd->add_option("--height", render->height, "Image height in pixels")->check(CLI::Range(16, 8192));
  renderCmd->add_option("--view", render->view, "Camera direction")->check(CLI::IsMember({"three-quarter", "front", "side", "top"}));
  commands.push_back({renderCmd, [render] { return runRender(*render); }});
}

}  // namespace imps::app
