// SPDX-License-Identifier: MIT
// `puppeteer check`, `mesh` and `render` (puppeteer/src/cli_scene.cpp) run as a user would: what they write reads
// back with the project's own readers and agrees with their reports, and every failure has the exit code and
// message docs/cli.md promises, with nothing left behind.
#include <gtest/gtest.h>

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "examples.h"
#include "image_file.h"
#include "imps/mesh.h"
#include "mesh_readers.h"
#include "scratch_dir.h"
#include "sim/pseudo_terminal.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliCheckFailed;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kBiped = sourceFile("examples/simple_biped.wrl");
const std::string kFlubber = sourceFile("examples/flubber.wrl");
const std::string kBeanito = sourceFile("examples/beanito.wrl");

void write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

// ---- check

TEST(CheckCommand, EveryBundledExampleIsValid) {
  for (const auto& entry : fs::directory_iterator(sourceFile("examples"))) {
    if (entry.path().extension() != ".wrl") continue;
    const test::ProgramRun run = runPuppeteer({"check", entry.path().string()});
    EXPECT_EQ(run.exitCode, kCliOk) << entry.path() << "\n" << describe(run);
    EXPECT_FALSE(run.out.empty()) << entry.path();
  }
}

// The listing describes the character the library compiles: its joints (as a tree), primitives and blend sets.
TEST(CheckCommand, ListsTheCharactersJointsPrimitivesAndBlendSets) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const test::ProgramRun text = runPuppeteer({"check", kBiped});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  EXPECT_TRUE(contains(text.out, "valid"));
  EXPECT_TRUE(contains(text.out, "joints (" + std::to_string(biped.joints().size()) + ")"));
  EXPECT_TRUE(contains(text.out, "primitives (" + std::to_string(biped.primitives().size()) + ")"));
  EXPECT_TRUE(contains(text.out, "L_Forearm"));

  const test::ProgramRun json = runPuppeteer({"check", "--json", kBiped});
  ASSERT_EQ(json.exitCode, kCliOk) << describe(json);
  const nlohmann::json report = nlohmann::json::parse(json.out);
  EXPECT_EQ(report["valid"], true);
  ASSERT_EQ(report["joints"].size(), biped.joints().size());
  // Every joint's parent is listed before it (a tree, root first).
  std::vector<std::string> seen;
  for (const nlohmann::json& joint : report["joints"]) {
    if (!joint["parent"].is_null()) {
      EXPECT_NE(std::find(seen.begin(), seen.end(), joint["parent"].get<std::string>()), seen.end()) << joint;
    }
    seen.push_back(joint["name"]);
  }
  EXPECT_EQ(report["primitives"].size(), biped.primitives().size());
  EXPECT_TRUE(report.contains("blendSets"));
  EXPECT_EQ(json.err, "");
}

// A broken scene: file:line:column errors (a misspelt field gets a suggestion), exit 1.
TEST(CheckCommand, ABrokenSceneIsAnInputErrorWithLocations) {
  const ScratchDir dir("imps_cli_scene");
  write(dir / "bad.wrl", "#VRML V2.0 utf8\nMetaball {\n  radius -2\n  centre 0 0 0\n}\n");
  const test::ProgramRun run = runPuppeteer({"check", (dir / "bad.wrl").string()});
  EXPECT_EQ(run.exitCode, kCliInvalidInput) << describe(run);
  EXPECT_TRUE(contains(run.err, "bad.wrl:3:"));
  EXPECT_TRUE(contains(run.err, ": error:"));
  EXPECT_TRUE(contains(run.err, "did you mean 'center'"));
  test::expectFailures({
      {"missing", {"check", (dir / "none.wrl").string()}, kCliInvalidInput, "no such file"},
      {"a directory", {"check", dir.path().string()}, kCliInvalidInput, "is a directory"},
      {"garbage", {"check", sourceFile("examples/flubber_face.png")}, kCliInvalidInput, "flubber_face.png"},
      {"unknown option", {"check", kBiped, "--jsn"}, kCliUsage, "did you mean '--json'?"},
      {"no scene", {"check"}, kCliUsage, "scene"},
  });
}

// Each scene warning is printed once — also when the scene has errors too — and "1 set" is singular.
TEST(CheckCommand, PrintsEachWarningOnceInGoodGrammar) {
  const ScratchDir dir("imps_cli_scene");
  const std::string lineSeg = "LineSeg {\n  point1 0 0 0  point2 0.1 0 0  radius1 0.5  radius2 0.1\n}\n";
  write(dir / "contained.wrl", "#VRML V2.0 utf8\n" + lineSeg);
  write(dir / "contained_bad.wrl", "#VRML V2.0 utf8\n" + lineSeg + "Metaball { radius -2 }\n");
  for (const char* name : {"contained.wrl", "contained_bad.wrl"}) {
    const test::ProgramRun run = runPuppeteer({"check", (dir / name).string()});
    EXPECT_EQ(run.exitCode, std::string(name) == "contained.wrl" ? kCliOk : kCliInvalidInput) << run.err;
    EXPECT_EQ(test::occurrences(run.err, "warning:"), 1u) << name << ":\n" << run.err;
  }
  const test::ProgramRun run = runPuppeteer({"check", (dir / "contained.wrl").string()});
  EXPECT_TRUE(contains(run.out, "(1 set:"));
}

// ---- mesh

// Each format reads back with an independent reader and holds what the report says: vertices, triangles, a closed
// surface.
TEST(MeshCommand, EachFormatReadsBackAsTheReportedClosedMesh) {
  const ScratchDir dir("imps_cli_scene");
  for (const char* ext : {"obj", "ply", "glb"}) {
    const std::string out = (dir / (std::string("biped.") + ext)).string();
    const test::ProgramRun run = runPuppeteer({"mesh", kBiped, "--res", "32", "--check", "--json", "-o", out});
    ASSERT_EQ(run.exitCode, kCliOk) << ext << "\n" << describe(run);
    const nlohmann::json report = nlohmann::json::parse(run.out);
    EXPECT_EQ(report["output"], out);
    EXPECT_EQ(report["topology"]["closedManifold"], true) << ext;
    Mesh mesh;
    std::string error;
    const bool read = std::string(ext) == "obj"   ? test::readObj(out, &mesh, &error)
                      : std::string(ext) == "ply" ? test::readPly(out, &mesh, &error)
                                                  : test::readGlb(out, &mesh, &error);
    ASSERT_TRUE(read) << ext << ": " << error;
    EXPECT_EQ(mesh.vertexCount(), report["vertices"].get<size_t>()) << ext;
    EXPECT_EQ(mesh.triangleCount(), report["triangles"].get<size_t>()) << ext;
    EXPECT_GT(mesh.triangleCount(), 100u) << ext;
    const MeshTopology topology = analyzeTopology(mesh);
    EXPECT_TRUE(topology.closedManifold()) << ext;
    EXPECT_EQ(long(topology.components), report["topology"]["components"].get<long>()) << ext;
    EXPECT_GT(signedVolume(mesh), 0.0) << ext << ": triangles face outward";
    EXPECT_EQ(mesh.colors.size(), mesh.positions.size()) << ext << ": vertex colours";
  }
  // The text report says the same.
  const test::ProgramRun text =
      runPuppeteer({"mesh", kBiped, "--res", "32", "--check", "-o", (dir / "t.ply").string()});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  EXPECT_TRUE(contains(text.out, "topology: closed 2-manifold"));
}

// The mesh is identical for any number of threads: the files are byte for byte the same.
TEST(MeshCommand, OneAndTwoThreadsWriteIdenticalFiles) {
  const ScratchDir dir("imps_cli_scene");
  for (const char* threads : {"1", "2"}) {
    const test::ProgramRun run = runPuppeteer({"mesh", kBiped, "--cell", "0.03", "--threads", threads, "-o",
                                               (dir / (std::string(threads) + ".ply")).string()});
    ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  }
  const std::string one = fileBytes(dir / "1.ply");
  EXPECT_GT(one.size(), 1000u);
  EXPECT_EQ(one, fileBytes(dir / "2.ply"));
}

// Every failure: exit code, message, and the output (an existing file included) untouched.
TEST(MeshCommand, FailuresHaveTheirExitCodesAndLeaveOutputsAlone) {
  const ScratchDir dir("imps_cli_scene");
  write(dir / "bad.wrl", "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n");
  write(dir / "keep.txt", "precious");
  write(dir / "keep.ply", "precious");
  const std::string ply = (dir / "m.ply").string();
  test::expectFailures({
      {"missing scene", {"mesh", (dir / "none.wrl").string(), "-o", ply}, kCliInvalidInput, "no such file"},
      {"bad scene", {"mesh", (dir / "bad.wrl").string(), "-o", ply}, kCliInvalidInput, "bad.wrl:3:"},
      {"bad scene over an existing file",
       {"mesh", (dir / "bad.wrl").string(), "-o", (dir / "keep.ply").string()},
       kCliInvalidInput,
       "bad.wrl:3:"},
      {"unknown extension",
       {"mesh", kBiped, "-o", (dir / "keep.txt").string()},
       kCliUsage,
       "expected a .obj, .ply or .glb file, not '.txt'"},
      {"no output", {"mesh", kBiped}, kCliUsage, "--output"},
      {"missing directory", {"mesh", kBiped, "-o", (dir / "no/such/dir/x.ply").string()}, kCliIo, "does not exist"},
      {"cell and res", {"mesh", kBiped, "-o", ply, "--cell", "0.1", "--res", "10"}, kCliUsage, "excludes"},
      {"cell 0", {"mesh", kBiped, "-o", ply, "--cell", "0"}, kCliUsage, "expected a number > 0, got '0'"},
      {"cell text", {"mesh", kBiped, "-o", ply, "--cell", "fine"}, kCliUsage, "got 'fine'"},
      {"res 0", {"mesh", kBiped, "-o", ply, "--res", "0"}, kCliUsage, "--res"},
      {"threads", {"mesh", kBiped, "-o", ply, "--threads", "-1"}, kCliUsage, "--threads"},
      {"polygonizer", {"mesh", kBiped, "-o", ply, "--polygonizer", "dual"}, kCliUsage, "--polygonizer"},
      {"updates", {"mesh", kBiped, "-o", ply, "--updates", "0"}, kCliUsage, "--updates"},
      {"misspelt option",
       {"mesh", kBiped, "-o", ply, "--cel", "0.1"},
       kCliUsage,
       "unknown option '--cel' for mesh; did you mean '--cell'?"},
      {"--at without a world", {"mesh", kBiped, "-o", ply, "--at", "1"}, kCliUsage, "need a world file"},
      {"--prop with particles",
       {"mesh", kBiped, "-o", ply, "--prop", sourceFile("examples/beanito_hat.wrl"), "--polygonizer", "particles"},
       kCliUsage,
       "--prop"},
  });
  EXPECT_FALSE(fs::exists(ply));
  EXPECT_EQ(fileBytes(dir / "keep.txt"), "precious");
  EXPECT_EQ(fileBytes(dir / "keep.ply"), "precious");
}

// --max-cells: a grid beyond it is refused before any work, with the grid and where its size came from (exit 2 for
// the command line's --cell or --res, exit 1 at file:line:column for the scene's cellSize); scene values out of
// range are input errors at their location.
TEST(MeshCommand, GridsBeyondTheLimitAreRefusedWithTheirSource) {
  const ScratchDir dir("imps_cli_scene");
  write(dir / "tiny.wrl",
        "#VRML V2.0 utf8\nMarchingCubes {\n  cellSize 1e-7\n  sceneGraph Metaball { radius 0.2 }\n}\n");
  write(dir / "threads.wrl",
        "#VRML V2.0 utf8\nMarchingCubes { numThreads 2147483647 sceneGraph Metaball { radius 0.2 } }\n");
  const std::string out = (dir / "x.ply").string();
  test::expectFailures({
      {"--cell 1e-9",
       {"mesh", kFlubber, "--cell", "1e-9", "-o", out},
       kCliUsage,
       "puppeteer mesh: error: --cell 1e-09: a grid of "},
      {"scene cellSize",
       {"mesh", (dir / "tiny.wrl").string(), "-o", out},
       kCliInvalidInput,
       "tiny.wrl:3:12: the scene's MarchingCubes resolution: a grid of"},
      {"raised limit",
       {"mesh", kFlubber, "--res", "64", "--max-cells", "1000", "-o", out},
       kCliUsage,
       "is more than the limit of 1000 cells"},
      {"scene numThreads",
       {"mesh", (dir / "threads.wrl").string(), "-o", out},
       kCliInvalidInput,
       "threads.wrl:2:28: error: field 'numThreads' of MarchingCubes must be between 0 and 1024"},
  });
  const test::ProgramRun run = runPuppeteer({"mesh", kFlubber, "--cell", "1e-9", "-o", out});
  EXPECT_TRUE(contains(run.err,
                       "is more than the limit of 268435456 cells; use larger cells, or raise the limit "
                       "with --max-cells N"));
  EXPECT_FALSE(fs::exists(out));
}

// The particle polygonizer always checks its mesh: particles too far apart to connect (stopped at --max-particles,
// with a warning at the scene's value) exit 4, with or without --check, and the mesh is written all the same.
TEST(MeshCommand, AnIncompleteParticleMeshExits4AndIsWrittenAllTheSame) {
  const ScratchDir dir("imps_cli_scene");
  write(dir / "fine.wrl",
        "#VRML V2.0 utf8\nTesselator3MP {\n  desiredRadius 0.001\n  sceneGraph Metaball { radius 0.2 }\n}\n");
  for (const bool check : {true, false}) {
    const std::string out = (dir / (check ? "checked.ply" : "unchecked.ply")).string();
    std::vector<std::string> args = {"mesh", (dir / "fine.wrl").string(), "--polygonizer", "particles", "--updates",
                                     "2",    "--max-particles",           "300",           "-o",        out};
    if (check) args.push_back("--check");
    const test::ProgramRun run = runPuppeteer(args);
    EXPECT_EQ(run.exitCode, kCliCheckFailed) << describe(run);
    EXPECT_TRUE(contains(run.err, "fine.wrl:3:17: warning: the particles reached their limit of 300"));
    EXPECT_TRUE(contains(run.err, "--max-particles N"));
    EXPECT_TRUE(contains(run.err, "puppeteer mesh: error: the particle mesh"));
    Mesh mesh;
    std::string error;
    EXPECT_TRUE(test::readPly(out, &mesh, &error)) << error;
  }
}

// Two metaballs joined by a neck (Marching Cubes finds one surface, at half desiredRadius and at 5 mm), meshed by
// particles 0.1 m apart. With the balls 0.6 m apart the neck's ring of particles makes no triangle, and the hole
// repair joins the two rims left (capping each would cut one ball off): one component, exit 0. With them 0.64 m apart
// the neck is too thin for that: each ball is closed on its own, a closed 2-manifold with the right number of
// components for two balls. The component match (matchComponents) sees the part cut off; a count would not. Exit 4,
// the mesh written all the same.
TEST(MeshCommand, AParticleMeshThatCutsAPartOffExits4) {
  const ScratchDir dir("imps_cli_scene");
  for (const char* centre : {"0.3", "0.32"}) {
    const bool cut = std::string(centre) == "0.32";
    write(dir / "dumbbell.wrl",
          std::string("#VRML V2.0 utf8\nTesselator3MP {\n  desiredRadius 0.1\n  sceneGraph ExponentialBlend {\n") +
              "    variance 0.25\n    children [\n      Metaball { center -" + centre + " 0 0 radius 0.3 }\n" +
              "      Metaball { center " + centre + " 0 0 radius 0.3 }\n    ]\n  }\n}\n");
    const test::ProgramRun fine = runPuppeteer(
        {"mesh", (dir / "dumbbell.wrl").string(), "--cell", "0.005", "--check", "-o", (dir / "mc.ply").string()});
    ASSERT_EQ(fine.exitCode, kCliOk) << describe(fine);
    EXPECT_TRUE(contains(fine.out, " 1 components")) << fine.out;
    const test::ProgramRun run = runPuppeteer(
        {"mesh", (dir / "dumbbell.wrl").string(), "--polygonizer", "particles", "-o", (dir / "dumbbell.ply").string()});
    EXPECT_EQ(run.exitCode, cut ? kCliCheckFailed : kCliOk) << centre << describe(run);
    EXPECT_TRUE(contains(run.out, "closed 2-manifold")) << run.out;
    EXPECT_TRUE(contains(run.out, cut ? "2 components (Marching Cubes at 0.05 m: 1; 0 missing, 1 cut off)"
                                      : "1 components (Marching Cubes at 0.05 m: 1; 0 missing, 0 cut off)"))
        << run.out;
    EXPECT_EQ(contains(run.err, "cuts 1 part off"), cut) << run.err;
    EXPECT_TRUE(fs::exists(dir / "dumbbell.ply"));
  }
}

// mesh --polygonizer particles always checks its mesh: a scene where the particles miss small blobs that Marching
// Cubes finds (twelve metaballs, a desiredRadius of 0.45 m against radii of 0.15-0.35 m: 4 components of 12) exits 4
// and says so; the mesh is written all the same. The same scene without its Tesselator3MP node gets a desiredRadius from its smallest
// metaball (issue 15) and meshes closed with every component, exit 0.
TEST(MeshCommand, AParticleMeshMissingPartOfTheSurfaceExits4) {
  const ScratchDir dir("imps_cli_scene");
  const std::string balls =
      "ExponentialBlend {\n  variance 0.25\n  children [\n"
      "    Metaball { center 0.939 -1.308 0.851 radius 0.267 }\n"
      "    Metaball { center 0.146 -1.031 -0.394 radius 0.176 }\n"
      "    Metaball { center 1.202 -0.405 0.604 radius 0.250 }\n"
      "    Metaball { center -0.659 -0.226 1.153 radius 0.262 }\n"
      "    Metaball { center 0.598 1.372 0.434 radius 0.230 }\n"
      "    Metaball { center -1.395 -0.707 -1.069 radius 0.155 }\n"
      "    Metaball { center 1.166 0.646 -1.215 radius 0.313 }\n"
      "    Metaball { center -0.913 1.281 -0.251 radius 0.189 }\n"
      "    Metaball { center 0.302 0.066 1.391 radius 0.337 }\n"
      "    Metaball { center -1.275 0.467 0.285 radius 0.214 }\n"
      "    Metaball { center 0.016 0.553 -0.792 radius 0.158 }\n"
      "    Metaball { center -0.388 -1.448 0.955 radius 0.296 }\n  ]\n}\n";
  write(dir / "blobs12.wrl", "#VRML V2.0 utf8\nTesselator3MP {\n  desiredRadius 0.45\n  sceneGraph " + balls + "}\n");
  const test::ProgramRun run = runPuppeteer(
      {"mesh", (dir / "blobs12.wrl").string(), "--polygonizer", "particles", "-o", (dir / "blobs12.ply").string()});
  EXPECT_EQ(run.exitCode, kCliCheckFailed) << run.err;
  EXPECT_TRUE(contains(run.err, "Marching Cubes finds"));
  EXPECT_TRUE(contains(run.out, " missing (the largest 0.")) << run.out;  // balls 0.3-0.7 m across
  EXPECT_TRUE(fs::exists(dir / "blobs12.ply"));
  write(dir / "blobs12_default.wrl", "#VRML V2.0 utf8\n" + balls);
  const test::ProgramRun fine = runPuppeteer({"mesh", (dir / "blobs12_default.wrl").string(), "--polygonizer",
                                              "particles", "-o", (dir / "blobs12_default.ply").string()});
  EXPECT_EQ(fine.exitCode, kCliOk) << describe(fine);
  EXPECT_TRUE(contains(fine.out, "from the scene's feature size"));
  EXPECT_TRUE(contains(fine.out, "closed 2-manifold"));
  EXPECT_TRUE(contains(fine.out, "12 components (Marching Cubes at"));
  const test::ProgramRun biped = runPuppeteer(
      {"mesh", kBiped, "--polygonizer", "particles", "--updates", "3", "-o", (dir / "biped.ply").string()});
  EXPECT_EQ(biped.exitCode, kCliOk) << biped.err;
  EXPECT_TRUE(contains(biped.out, "closed 2-manifold"));
}

// Particle runs with more threads than the machine has cores used to print oneTBB's "The number of workers is
// currently limited to …" warning.
TEST(MeshCommand, ParticleRunsPrintNoThreadingWarnings) {
  const ScratchDir dir("imps_cli_scene");
  for (const char* threads : {"2", "3", "8"}) {
    const test::ProgramRun run = runPuppeteer({"mesh", kBiped, "--polygonizer", "particles", "--updates", "2",
                                               "--threads", threads, "-o", (dir / "t.ply").string()});
    EXPECT_EQ(run.exitCode, kCliOk) << run.err;
    EXPECT_EQ(run.err.find("TBB"), std::string::npos) << threads << " threads:\n" << run.err;
    EXPECT_EQ(run.err.find("limited to"), std::string::npos) << threads << " threads:\n" << run.err;
  }
}

// `mesh SCENE --prop FILE@JOINT`: the character and each prop its own object (OBJ `o` lines), merged in PLY.
TEST(MeshCommand, PropsAreObjectsOfTheirOwn) {
  const ScratchDir dir("imps_cli_scene");
  const std::string obj = (dir / "hat.obj").string();
  const test::ProgramRun run = runPuppeteer({"mesh", kBeanito, "--res", "24", "--json", "--prop",
                                             sourceFile("examples/beanito_hat.wrl") + "@BEAN_TOP", "-o", obj});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  ASSERT_GE(report["objects"].size(), 2u) << run.out;
  EXPECT_EQ(test::occurrences(fileBytes(obj), "\no "), report["objects"].size());
  Mesh mesh;
  std::string error;
  ASSERT_TRUE(test::readObj(obj, &mesh, &error)) << error;
  EXPECT_EQ(mesh.triangleCount(), report["triangles"].get<size_t>());
  test::expectFailures({
      {"unknown joint",
       {"mesh", kBeanito, "--prop", sourceFile("examples/beanito_hat.wrl") + "@NOPE", "-o", obj},
       kCliInvalidInput,
       "no joint 'NOPE'"},
      {"missing prop",
       {"mesh", kBeanito, "--prop", (dir / "none.wrl").string(), "-o", obj},
       kCliInvalidInput,
       "none.wrl"},
  });
}

// A file-size limit (ulimit -f) fails the save like a full disk: a message, exit 3, the existing file untouched
// and no temporary file left (was: killed by SIGXFSZ, leaving existing.glb.tmp-PID-0).
TEST(MeshCommand, AFileSizeLimitFailsTheSaveLikeAFullDisk) {
  const ScratchDir dir("imps_cli_scene");
  const std::string existing = (dir / "existing.glb").string();
  write(existing, "precious");
  const test::ProgramRun run =
      test::runProgram("/bin/bash", {"-c", "ulimit -f 1; exec \"$0\" mesh \"$1\" --res 48 -o \"$2\"",
                                     test::puppeteerProgram().string(), kBiped, existing});
  EXPECT_EQ(run.exitCode, kCliIo) << describe(run);
  EXPECT_TRUE(contains(run.err, "cannot save '" + existing + "': writing: File too large"));
  EXPECT_EQ(fileBytes(existing), "precious");
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

// Progress: a status line on a terminal, erased before the report; nothing when stderr is a pipe.
TEST(MeshCommand, LongWorkShowsProgressOnATerminalOnly) {
  const ScratchDir dir("imps_cli_scene");
  const std::vector<std::string> args = {"mesh", kBiped, "--res", "48", "-o", (dir / "progress.ply").string()};
  const test::ProgramRun piped = runPuppeteer(args);
  ASSERT_EQ(piped.exitCode, kCliOk) << piped.err;
  EXPECT_EQ(piped.err, "");
  auto pty = sim::PseudoTerminal::open();
  ASSERT_TRUE(pty) << pty.error().str();
  test::ProgramOptions onTerminal;
  onTerminal.stderrPath = pty->slavePath();
  const test::ProgramRun shown = runPuppeteer(args, onTerminal);
  ASSERT_EQ(shown.exitCode, kCliOk);
  std::string terminal;
  char buffer[4096];
  for (pollfd ready{pty->master(), POLLIN, 0}; ::poll(&ready, 1, 200) > 0;) {
    const ssize_t n = ::read(pty->master(), buffer, sizeof buffer);
    if (n <= 0) break;
    terminal.append(buffer, size_t(n));
  }
  ASSERT_GE(terminal.size(), 4u);
  EXPECT_TRUE(contains(terminal, "puppeteer mesh: polygonizing"));
  EXPECT_TRUE(contains(terminal, "puppeteer mesh: writing"));
  EXPECT_EQ(terminal.substr(terminal.size() - 4), "\r\033[K") << "the line is erased at the end";
}

// ---- render

// A PNG of the size asked for, read back with the project's reader: not blank (the surface is drawn over the
// background), and the same picture again for the same command.
TEST(RenderCommand, WritesThePictureAskedFor) {
  const ScratchDir dir("imps_cli_scene");
  const std::string png = (dir / "b.png").string();
  const test::ProgramRun run =
      runPuppeteer({"render", kBeanito, "--res", "24", "--width", "64", "--height", "48", "--json", "-o", png});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  EXPECT_GT(report["triangles"].get<size_t>(), 0u);
  const std::optional<test::ImageFile> image = test::readImageFile(png);
  ASSERT_TRUE(image) << png;
  EXPECT_EQ(image->width, 64);
  EXPECT_EQ(image->height, 48);
  const size_t n = size_t(image->channels);
  ASSERT_GE(n, 3u);
  size_t differing = 0;
  for (size_t i = 0; i < image->pixels.size(); i += n)
    if (!std::equal(&image->pixels[i], &image->pixels[i] + 3, &image->pixels[0])) ++differing;
  EXPECT_GT(differing, 64u * 48u / 20) << "the character covers some of the picture";
  // Another view is another picture.
  const std::string top = (dir / "top.png").string();
  ASSERT_EQ(
      runPuppeteer({"render", kBeanito, "--res", "24", "--width", "64", "--height", "48", "--view", "top", "-o", top})
          .exitCode,
      kCliOk);
  const std::optional<test::ImageFile> topImage = test::readImageFile(top);
  ASSERT_TRUE(topImage) << top;
  EXPECT_NE(topImage->pixels, image->pixels);
}

TEST(RenderCommand, FailuresHaveTheirExitCodesAndLeaveOutputsAlone) {
  const ScratchDir dir("imps_cli_scene");
  write(dir / "bad.wrl", "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n");
  const std::string png = (dir / "r.png").string(), clip = sourceFile("examples/beanito_jump.wrl");
  const std::string hat = sourceFile("examples/beanito_hat.wrl");
  const std::vector<std::string> small = {"--res", "12", "--width", "32", "--height", "32"};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.end(), small.begin(), small.end());
    return args;
  };
  test::expectFailures({
      {"missing scene", {"render", (dir / "none.wrl").string(), "-o", png}, kCliInvalidInput, "no such file"},
      {"bad scene", {"render", (dir / "bad.wrl").string(), "-o", png}, kCliInvalidInput, "bad.wrl:3:"},
      {"extension", {"render", kBeanito, "-o", (dir / "r.jpg").string()}, kCliUsage, "expected a .png file"},
      {"directory", {"render", kBeanito, "-o", (dir / "nodir/r.png").string()}, kCliIo, "does not exist"},
      {"width", {"render", kBeanito, "-o", png, "--width", "1"}, kCliUsage, "--width"},
      {"view", {"render", kBeanito, "-o", png, "--view", "bogus"}, kCliUsage, "--view"},
      {"--at without --clip", {"render", kBeanito, "-o", png, "--at", "1"}, kCliUsage, "--at needs --clip"},
      {"--drive without a world",
       {"render", kBeanito, "-o", png, "--drive", "A=" + clip},
       kCliUsage,
       "--drive needs a world file"},
      {"missing clip",
       {"render", kBeanito, "-o", png, "--clip", (dir / "none.wrl").string()},
       kCliInvalidInput,
       "no such file"},
      {"clip driving no joint", with({"render", kBiped, "-o", png, "--clip", clip}), kCliInvalidInput,
       "drives no joint of the character"},
      {"prop on no joint", with({"render", kBeanito, "-o", png, "--prop", hat + "@NOPE"}), kCliInvalidInput,
       "no joint 'NOPE'"},
      {"grab spec", with({"render", kBeanito, "-o", png, "--clip", clip, "--grab", "nonsense"}), kCliInvalidInput,
       "expected FILE.wrl@JOINT@PICK:DROP"},
      {"grab PICK > DROP", with({"render", kBeanito, "-o", png, "--clip", clip, "--grab", hat + "@BEAN_TOP@2:1"}),
       kCliInvalidInput, "PICK <= DROP"},
      {"misspelt option", {"render", kBeanito, "-o", png, "--widht", "64"}, kCliUsage, "did you mean '--width'?"},
  });
  EXPECT_FALSE(fs::exists(png));
}

// --clip poses the character: a clip at two times gives two pictures; --prop draws the hat.
TEST(RenderCommand, AClipPosesTheCharacterAndPropsAreDrawn) {
  const ScratchDir dir("imps_cli_scene");
  const std::vector<std::string> common = {"render", kBeanito, "--res", "16", "--width", "48", "--height", "48"};
  auto render = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args = common;
    args.insert(args.end(), extra.begin(), extra.end());
    args.insert(args.end(), {"-o", (dir / name).string()});
    const test::ProgramRun run = runPuppeteer(args);
    EXPECT_EQ(run.exitCode, kCliOk) << name << "\n" << describe(run);
    const std::optional<test::ImageFile> image = test::readImageFile((dir / name).string());
    EXPECT_TRUE(image) << name;
    return image ? image->pixels : std::vector<uint8_t>{};
  };
  const std::string clip = sourceFile("examples/beanito_jump.wrl");
  const std::vector<uint8_t> rest = render("rest.png", {});
  const std::vector<uint8_t> early = render("early.png", {"--clip", clip, "--at", "0"});
  const std::vector<uint8_t> jump = render("jump.png", {"--clip", clip, "--at", "0.36"});
  const std::vector<uint8_t> hat = render("hat.png", {"--prop", sourceFile("examples/beanito_hat.wrl") + "@BEAN_TOP"});
  EXPECT_NE(early, jump) << "the clip moves the character";
  EXPECT_NE(rest, hat) << "the hat is drawn";
}

}  // namespace
}  // namespace imps::app
