// SPDX-License-Identifier: MIT
// Surface sequences (puppeteer/src/export_surfaces.cpp): file names from the pattern, one closed mesh per frame read
// back with the PLY and OBJ readers, the mesh following the take, folders created, and I/O failures reported with
// the files already written kept.
#include "export_surfaces.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "examples.h"
#include "imps/mesh.h"
#include "mesh_readers.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;

// The rest pose with the root moved `step` metres along x per frame.
Take walkingTake(const Character& c, size_t frames, float step) {
  Take take;
  take.frameTime = 0.1;
  for (size_t f = 0; f < frames; ++f) {
    std::vector<Rigid> locals;
    for (const Joint& j : c.joints()) {
      Rigid r = j.rest;
      if (j.parent < 0) r.translation.x += step * float(f);
      locals.push_back(r);
    }
    take.locals.push_back(locals);
  }
  return take;
}

float meanX(const Mesh& mesh) {
  double sum = 0;
  for (size_t v = 0; v < mesh.vertexCount(); ++v) sum += mesh.position(v).x;
  return float(sum / double(mesh.vertexCount()));
}

TEST(SequenceFileName, ReplacesTheRunOfHashesWithThePaddedFrame) {
  EXPECT_EQ(sequenceFileName("out/take_####.ply", 7), "out/take_0007.ply");
  EXPECT_EQ(sequenceFileName("take_##.obj", 123), "take_123.obj") << "a wider number is not cut";
  EXPECT_EQ(sequenceFileName("#.ply", 0), "0.ply");
  EXPECT_NE(sequenceFileName("a_###.ply", 1), sequenceFileName("a_###.ply", 2));
}

// Each frame a closed mesh in its own file, in a folder created for it, moving with the take; OBJ as PLY.
TEST(SurfaceSequence, EachFrameIsAClosedMeshFollowingTheTake) {
  const ScratchDir dir("imps_export_surfaces");
  const Character& biped = test::exampleCharacter("simple_biped");
  const Take take = walkingTake(biped, 3, 0.1f);
  SurfaceSequenceOptions options;
  options.cellSize = 0.06f;
  std::vector<size_t> progress;
  options.progress = [&](size_t done) { progress.push_back(done); };
  for (const char* ext : {"ply", "obj"}) {
    progress.clear();
    const std::string pattern = (dir / ext / "deeper" / (std::string("walk_##.") + ext)).string();
    const auto written = writeSurfaceSequence(Scene{}, biped, take, options, pattern);
    ASSERT_TRUE(written) << written.error().str();
    EXPECT_EQ(progress, (std::vector<size_t>{1, 2, 3})) << ext;
    float previousX = 0;
    for (size_t f = 0; f < take.frames(); ++f) {
      const std::string file = sequenceFileName(pattern, f);
      Mesh mesh;
      std::string error;
      ASSERT_TRUE(std::string(ext) == "ply" ? test::readPly(file, &mesh, &error) : test::readObj(file, &mesh, &error))
          << file << ": " << error;
      EXPECT_GT(mesh.triangleCount(), 50u) << file;
      EXPECT_TRUE(analyzeTopology(mesh).closedManifold()) << file;
      const float x = meanX(mesh);
      if (f > 0) {
        EXPECT_NEAR(x - previousX, 0.1f, 0.02f) << file << ": the surface walks with the root";
      }
      previousX = x;
    }
    EXPECT_FALSE(fs::exists(sequenceFileName(pattern, take.frames())));
  }
}

// A folder that cannot be created (under a file) is an I/O error.
TEST(SurfaceSequence, AnUnwritableFolderIsAnError) {
  const ScratchDir dir("imps_export_surfaces");
  writeBytes(dir / "file", "not a folder");
  const Character& biped = test::exampleCharacter("simple_biped");
  SurfaceSequenceOptions options;
  options.cellSize = 0.08f;
  const auto written =
      writeSurfaceSequence(Scene{}, biped, walkingTake(biped, 1, 0), options, (dir / "file/s_#.ply").string());
  EXPECT_FALSE(written);
  EXPECT_EQ(fileBytes(dir / "file"), "not a folder");
}

}  // namespace
}  // namespace imps::app
