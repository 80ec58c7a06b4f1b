// SPDX-License-Identifier: MIT
// `puppeteer stretch` (puppeteer/src/cli_stretch.cpp) through the real program: the figures for each mode asked
// for, the pictures at rest, bent and back (read back with the project's PNG reader), and docs/cli.md's exit codes.
#include <gtest/gtest.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "image_file.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kTextured = sourceFile("examples/textured_biped.wrl");

// Both modes by default: a figure of each kind per mode, in metres and in particle radii that agree.
TEST(StretchCommand, ReportsEachModesFigures) {
  const test::ProgramRun run =
      runPuppeteer({"stretch", kTextured, "--json", "--frames", "2", "--rest-frames", "0", "--threads", "2"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json report = nlohmann::json::parse(run.out);
  ASSERT_EQ(report["modes"].size(), 2u);
  EXPECT_EQ(report["modes"][0]["mode"], "projective");
  EXPECT_EQ(report["modes"][1]["mode"], "carried");
  for (const nlohmann::json& mode : report["modes"]) {
    for (const char* figure : {"roundTrip", "slideBent", "slideBack"}) {
      const double metres = mode[figure].get<double>(), radii = mode[std::string(figure) + "Radii"].get<double>();
      EXPECT_GE(metres, 0.0) << mode["mode"] << " " << figure;
      EXPECT_LT(metres, 0.1) << mode["mode"] << " " << figure << ": the dot stays near the elbow";
      if (metres > 0) {
        EXPECT_GT(radii, 0.0) << mode["mode"] << " " << figure;
      }
    }
  }
}

// `stretch --pictures` paints the dot and renders the joint at rest, bent and back: three pictures of one size, the
// bent one different; only the mode asked for.
TEST(StretchCommand, PicturesShowTheJointAtRestBentAndBack) {
  const ScratchDir dir("imps_cli_stretch");
  const std::string prefix = (dir / "elbow").string();
  const test::ProgramRun run = runPuppeteer(
      {"stretch", kTextured, "--frames", "2", "--rest-frames", "0", "--mode", "carried", "--pictures", prefix});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  EXPECT_TRUE(contains(run.out, "carried"));
  std::optional<test::ImageFile> images[3];
  const char* stages[3] = {"rest", "bent", "back"};
  for (int i = 0; i < 3; ++i) {
    images[i] = test::readImageFile(prefix + "_carried_" + stages[i] + ".png");
    ASSERT_TRUE(images[i]) << stages[i];
    EXPECT_EQ(images[i]->width, 640) << stages[i];
    EXPECT_EQ(images[i]->height, 480) << stages[i];
  }
  EXPECT_NE(images[0]->pixels, images[1]->pixels) << "the joint is bent";
  EXPECT_FALSE(fs::exists(prefix + "_projective_rest.png"));
}

// A scene it cannot measure is an input error; a bad mode or number a usage error; the pictures' directory is
// checked before any work (exit 3).
TEST(StretchCommand, Failures) {
  const ScratchDir dir("imps_cli_stretch");
  test::expectFailures({
      {"missing scene", {"stretch", (dir / "none.wrl").string()}, kCliInvalidInput, "no such file"},
      {"untextured",
       {"stretch", sourceFile("examples/simple_biped.wrl")},
       kCliInvalidInput,
       "no primitive has a texture generator"},
      {"joint", {"stretch", kTextured, "--joint", "Elbow"}, kCliInvalidInput, "no joint named 'Elbow'"},
      {"mode", {"stretch", kTextured, "--mode", "sliding"}, kCliUsage, "--mode"},
      {"degrees", {"stretch", kTextured, "--degrees", "270"}, kCliUsage, "--degrees"},
      {"frames", {"stretch", kTextured, "--frames", "0"}, kCliUsage, "--frames"},
      {"axis", {"stretch", kTextured, "--axis", "0,1"}, kCliUsage, "--axis"},
      {"pictures directory",
       {"stretch", kTextured, "--pictures", (dir / "nodir/p").string()},
       kCliIo,
       "does not exist"},
      {"misspelt option", {"stretch", kTextured, "--degree", "45"}, kCliUsage, "did you mean '--degrees'?"},
  });
}

}  // namespace
}  // namespace imps::app
