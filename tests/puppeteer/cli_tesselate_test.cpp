// SPDX-License-Identifier: MIT
// `puppeteer bench` (puppeteer/src/cli_tesselate.cpp) through the real program: every render's mesh checked on a
// swing, a clip and a session, reported as JSON and as one CSV line per render; one report per scene; every failure
// with docs/cli.md's exit code.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kBiped = sourceFile("examples/simple_biped.wrl");
const std::vector<std::string> kCoarse = {"--desired-radius", "0.0432", "--json"};  // ~900 particles on the biped

// --uniform-spacing turns the thin parts' local spacing off: on the ~900-particle biped the wrists, hands and feet
// (thinner than the spacing) then have fewer particles, and the settled count is smaller.
TEST(BenchCommand, UniformSpacingGivesThinPartsFewerParticles) {
  auto particles = [](bool uniform) {
    std::vector<std::string> args = {"bench", kBiped, "--renders", "2"};
    args.insert(args.end(), kCoarse.begin(), kCoarse.end());
    if (uniform) args.push_back("--uniform-spacing");
    const test::ProgramRun run = runPuppeteer(args);
    EXPECT_EQ(run.exitCode, kCliOk) << describe(run);
    return nlohmann::json::parse(run.out)["scenes"][0]["particles"].get<double>();
  };
  const double local = particles(false), uniform = particles(true);
  EXPECT_GT(local, uniform * 1.03) << local << " particles with the local spacing, " << uniform << " without";
}

// bench checks every render's mesh: on a fast swing, on the project's own small clip (retargeted as replay does) and
// on a recorded session, each render closed and manifold, reported as JSON and one CSV line per render.
TEST(BenchCommand, ChecksEveryRenderOfASwingAClipAndASession) {
  const ScratchDir dir("imps_cli_tesselate");
  const std::string csvPath = (dir / "bench.csv").string();
  struct Case {
    std::string motion;
    int renders;
  } cases[] = {{"swing:720", 12},
               {sourceFile("tests/data/bvh/biped_wave.bvh"), 4},
               {sourceFile("examples/simple_biped_wave.session"), 4}};
  for (const Case& c : cases) {
    std::vector<std::string> args = {
        "bench", kBiped, "--motion", c.motion, "--hz", "60", "--renders", std::to_string(c.renders), "--csv", csvPath};
    args.insert(args.end(), kCoarse.begin(), kCoarse.end());
    const test::ProgramRun run = runPuppeteer(args);
    ASSERT_EQ(run.exitCode, kCliOk) << c.motion << ": " << describe(run);
    const nlohmann::json report = nlohmann::json::parse(run.out);
    const nlohmann::json& scene = report["scenes"][0];
    for (const char* key :
         {"renders", "renders_with_holes", "max_boundary_edges", "renders_with_nonmanifold", "max_nonmanifold_edges",
          "max_nonmanifold_vertices", "renders_with_folds", "fissions_per_update_settled", "worst_f_minus_iso",
          "renders_with_fallback", "renders_with_cut_off_parts", "max_cut_off_parts", "renders_with_missing_components",
          "max_missing_components", "renders_with_missing_solids", "renders_with_cut_off_solids",
          "largest_missing_component_mm", "renders_with_particle_cut_off_parts"})
      EXPECT_TRUE(scene.contains(key)) << c.motion << ": " << key;
    EXPECT_EQ(scene["renders"], c.renders) << c.motion;
    EXPECT_EQ(scene["renders_with_holes"], 0) << c.motion;
    EXPECT_EQ(scene["renders_with_nonmanifold"], 0) << c.motion;
    std::ifstream csv(csvPath);
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line.rfind("scene,render,seconds,particles,triangles,boundary_edges,", 0), 0u) << line;
    EXPECT_TRUE(
        line.ends_with(",cut_off_parts,cut_off_cavities,missing_components,missing_cavities,largest_missing_mm,"
                       "particle_cut_off_parts"))
        << line;
    // The five columns before the last are each render's parts cut off and how many of those are cavities, components
    // missing (against Marching Cubes) and how many of those are cavities, and the largest missing one's size: the
    // JSON counts the renders with parts cut off, with solids (not cavities) cut off, with components missing and with
    // solids missing, and gives the largest size. The last: the solids the particles' own triangulation cut off, which
    // makes the render fall back to Marching Cubes (the "fallback" column, the 14th).
    int rows = 0, cut = 0, cutSolids = 0, missing = 0, solids = 0, particlesCut = 0;
    double largest = 0;
    while (std::getline(csv, line)) {
      ++rows;
      std::vector<std::string> cells;
      for (size_t at = 0, comma; at <= line.size(); at = comma + 1) {
        comma = std::min(line.find(',', at), line.size());
        cells.push_back(line.substr(at, comma - at));
      }
      ASSERT_EQ(cells.size(), 22u) << line;
      const size_t k = cells.size() - 6;
      if (std::stoi(cells[21]) > 0) {
        ++particlesCut;
        EXPECT_EQ(cells[13], "1") << "a render whose particles cut a part off falls back: " << line;
      }
      const int cutHere = std::stoi(cells[k]), pocketsHere = std::stoi(cells[k + 1]);
      EXPECT_LE(pocketsHere, cutHere) << line;
      cut += cutHere > 0;
      cutSolids += cutHere > pocketsHere;
      const int missingHere = std::stoi(cells[k + 2]), cavitiesHere = std::stoi(cells[k + 3]);
      EXPECT_LE(cavitiesHere, missingHere) << line;
      missing += missingHere > 0;
      solids += missingHere > cavitiesHere;
      const double sizeHere = std::stod(cells[k + 4]);
      EXPECT_EQ(sizeHere > 0, missingHere > 0) << line;
      largest = std::max(largest, sizeHere);
    }
    EXPECT_EQ(rows, c.renders) << c.motion;
    EXPECT_EQ(scene["renders_with_cut_off_parts"], cut) << c.motion;
    EXPECT_EQ(scene["renders_with_particle_cut_off_parts"], particlesCut) << c.motion;
    EXPECT_EQ(scene["renders_with_cut_off_solids"], cutSolids) << c.motion;
    EXPECT_EQ(scene["renders_with_missing_components"], missing) << c.motion;
    EXPECT_EQ(scene["renders_with_missing_solids"], solids) << c.motion;
    EXPECT_NEAR(scene["largest_missing_component_mm"].get<double>(), largest, 1e-3 * largest) << c.motion;
  }
}

// Several scenes: one report each, in the order given, each with its own particles and triangles.
TEST(BenchCommand, ReportsEachScene) {
  std::vector<std::string> args = {"bench", kBiped, sourceFile("examples/beanito.wrl"), "--renders", "1"};
  args.insert(args.end(), kCoarse.begin(), kCoarse.end());
  const test::ProgramRun run = runPuppeteer(args);
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  ASSERT_EQ(report["scenes"].size(), 2u);
  EXPECT_EQ(report["scenes"][0]["scene"], "simple_biped.wrl");
  EXPECT_EQ(report["scenes"][1]["scene"], "beanito.wrl");
  for (const nlohmann::json& scene : report["scenes"]) {
    EXPECT_GT(scene["particles"].get<double>(), 0) << scene["scene"];
    EXPECT_GT(scene["triangles"].get<double>(), 0) << scene["scene"];
    EXPECT_EQ(scene["renders"], 1) << scene["scene"];
  }
  // The text report has the thesis's Table 3.1 columns.
  const test::ProgramRun text = runPuppeteer({"bench", kBiped, "--renders", "1", "--desired-radius", "0.0432"});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  EXPECT_TRUE(test::contains(text.out, "simple_biped.wrl"));
}

TEST(BenchCommand, Failures) {
  const ScratchDir dir("imps_cli_tesselate");
  std::ofstream(dir / "garbage.bvh") << "HIERARCHY\nROOT {\n";
  std::ofstream(dir / "bad.wrl") << "#VRML V2.0 utf8\nMetaball {\n  radius -2\n}\n";
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"bench", kBiped, "--renders", "1"};
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  test::expectFailures({
      {"missing scene", {"bench", (dir / "none.wrl").string()}, kCliInvalidInput, "no such file"},
      {"bad scene", {"bench", (dir / "bad.wrl").string()}, kCliInvalidInput, "bad.wrl:3:"},
      {"missing motion", with({"--motion", (dir / "missing.bvh").string()}), kCliInvalidInput, "no such file"},
      {"garbage motion", with({"--motion", (dir / "garbage.bvh").string()}), kCliInvalidInput, "garbage.bvh"},
      {"swing speed", with({"--motion", "swing:fast"}), kCliUsage, "swing:fast"},
      {"motion word", with({"--motion", "wobble"}), kCliUsage, "--motion"},
      {"csv extension", with({"--csv", (dir / "report.txt").string()}), kCliUsage, "--csv"},
      {"csv directory", with({"--csv", (dir / "nodir/report.csv").string()}), kCliIo, "nodir"},
      {"hz", with({"--hz", "0"}), kCliUsage, "--hz"},
      {"renders", {"bench", kBiped, "--renders", "0"}, kCliUsage, "--renders"},
      {"desired radius", with({"--desired-radius", "-1"}), kCliUsage, "--desired-radius"},
      {"no scene", {"bench"}, kCliUsage, "scenes"},
      {"misspelt option", with({"--render", "2"}), kCliUsage, "did you mean '--renders'?"},
  });
}

}  // namespace
}  // namespace imps::app
