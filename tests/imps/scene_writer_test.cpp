// SPDX-License-Identifier: MIT
// Tests for writeScene / saveSceneFile: the canonical layout, exact round trips, and atomic saving.
#include "imps/scene_writer.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "imps/scene_reader.h"

namespace imps {
namespace {

namespace fs = std::filesystem;

std::string scenePath(const std::string& name) { return std::string(IMPS_SOURCE_DIR) + "/tests/data/scenes/" + name; }

Scene readOrFail(const std::string& text, const std::string& name = "t.wrl") {
  auto result = readScene(text, name);
  EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().str()) << "\n" << text;
  return result.has_value() ? *result : Scene{};
}

// read(write(s)) == s and write(read(write(s))) == write(s), byte for byte.
void expectRoundTrip(const Scene& scene) {
  const std::string written = writeScene(scene);
  const Scene again = readOrFail(written);
  EXPECT_EQ(again, scene) << written;
  EXPECT_EQ(writeScene(again), written);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(SceneWriter, FigureA1InCanonicalForm) {
  auto figure = readSceneFile(scenePath("figure_a1.wrl"));
  ASSERT_TRUE(figure.has_value()) << figure.error().str();
  EXPECT_EQ(writeScene(*figure), R"(#VRML V2.0 utf8

Tesselator3MP {
  deltaT 0.045
  desiredRadius 0.3
  queryRadius 0.8
  energyCoeff 10
  surfaceCoeff 30
  fissioningFrac 0.5
  isoValue 1
  useSimpleRadii TRUE
  numThreads 3
  updatesPerRender 3
  colorWidth 3
  doDifferentialTransforms TRUE
  seed 1
  blendingFunction ExponentialBlend {
    variance 2
    fastExp FALSE
  }
  spatialSubdivision UniformHash {
    cubeSize 0.6
    bitsPerDim 3
  }
  sceneGraph RigidTransform {
    translation 0 0 0
    rotation 0 0 1 0
    children [
      Metaball {
        center 0 0 0
        radius 1
        material Material {
          diffuseColor 0.29 0.41 0.44
        }
      }
      RigidTransform {
        translation 2 2 0
        rotation 0 0 1 0
        children [
          Metaball {
            center 0 0 0
            radius 1
            material Material {
              diffuseColor 0.8 0.2 0.2
            }
          }
        ]
      }
    ]
  }
}
)");
}

TEST(SceneWriter, RoundTripsEveryTestScene) {
  for (const char* name : {"figure_a1.wrl", "flat_exponential.wrl", "hierarchical_blanc_schlick.wrl",
                           "marching_cubes_elliptical.wrl", "single_metaball.wrl"}) {
    SCOPED_TRACE(name);
    auto scene = readSceneFile(scenePath(name));
    ASSERT_TRUE(scene.has_value()) << scene.error().str();
    expectRoundTrip(*scene);
  }
}

TEST(SceneWriter, TexGensAndTexturesRoundTrip) {
  const Scene scene = readOrFail(R"(#VRML V2.0 utf8
DEF Body RigidTransform { children [
  Metaball { radius 0.5 texGen TexGenSphere { translation 0 0.25 0 rotation 0 1 0 3.1415927 }
             texture ImageTexture { url "suit \"1\".png" } }
  DEF Head RigidTransform { translation 0 1 0 children [
    Ellipsoid { texGen TexGenPlane { translation 0 0 1 width 0.7 height 0.3 } texture ImageTexture { url "/abs/face.exr" } }
    LineSeg { texture ImageTexture { url "tie.jpg" } }
  ] }
] }
)");
  expectRoundTrip(scene);
  const std::string text = writeScene(scene);
  EXPECT_NE(text.find("      texGen TexGenSphere {\n        translation 0 0.25 0\n        rotation 0 1 0 3.1415927\n"
                      "      }\n      texture ImageTexture {\n        url \"suit \\\"1\\\".png\"\n      }\n"),
            std::string::npos) << text;
  EXPECT_NE(text.find("texGen TexGenPlane {\n"), std::string::npos) << text;
  EXPECT_NE(text.find("width 0.7\n"), std::string::npos) << text;
  // A different generator is a different scene.
  Scene moved = scene;
  std::get<ShapeNode>(std::get<TransformNode>(*moved.root).children[0]).texGen->translation.y = 0.5f;
  EXPECT_NE(moved, scene);
}

TEST(SceneWriter, UseIsWrittenAsUseAndDefOnce) {
  auto scene = readSceneFile(scenePath("flat_exponential.wrl"));
  ASSERT_TRUE(scene.has_value());
  const std::string text = writeScene(*scene);
  EXPECT_NE(text.find("DEF Body ExponentialBlend {"), std::string::npos) << text;
  EXPECT_NE(text.find("material DEF Skin Material {\n"), std::string::npos) << text;
  EXPECT_NE(text.find("material USE Skin\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("DEF Skin"), text.rfind("DEF Skin"));
  EXPECT_NE(text.find("children [\n        DEF Arm LineSeg {"), std::string::npos) << text;
}

TEST(SceneWriter, BuiltScenesRoundTrip) {
  // Every blend as a flat root, every shape, unusual floats, empty children, BlendGroups with escapes.
  for (BlendKind kind : {BlendKind::Exponential, BlendKind::BlancSchlick, BlendKind::Elliptical}) {
    Scene scene;
    BlendNode root;
    root.kind = kind;
    root.name = "Root";
    root.variance = 0.1f;
    root.hardness = 3.0f;
    root.blendRange = 1.0f / 3.0f;
    const float sign = kind == BlendKind::Exponential ? -1.0f : 1.0f;
    ShapeNode ball;
    ball.name = "Ball";
    ball.center = {std::numeric_limits<float>::max(), -std::numeric_limits<float>::min(), 1e-7f};
    ball.radius = std::numeric_limits<float>::denorm_min();
    ball.blendParam = sign * 0.1f;
    ShapeNode ellipsoid;
    ellipsoid.kind = ShapeKind::Ellipsoid;
    ellipsoid.orientation = {{0.0f, 0.0f, 0.0f}, 0.0f};
    ellipsoid.radii = {1.0f / 3.0f, 2.0f / 3.0f, 123456789.0f};
    Material material;
    material.name = "Mat";
    material.diffuseColor = {0.1f, 0.2f, 0.3f};
    material.transparency = 1.0f;
    ellipsoid.material = material;
    ShapeNode seg;
    seg.kind = ShapeKind::LineSeg;
    seg.point1 = {-1, -2, -3};
    seg.point2 = {4, 5, 6};
    seg.radius1 = 0.25f;
    seg.radius2 = 0.75f;
    Material copy = material;
    copy.name.clear();
    copy.useOf = "Mat";
    seg.material = copy;
    TransformNode joint;
    joint.name = "Joint";
    joint.rotation = {{0.0f, 1.0f, 0.0f}, -3.14159265f};
    joint.children.push_back(seg);
    ShapeNode ballCopy = ball;
    ballCopy.name.clear();
    ballCopy.useOf = "Ball";
    root.children = {ball, ellipsoid, joint, TransformNode{}, ballCopy};
    scene.root = root;
    scene.blendGroups.push_back({{"Ball", "Joint"}, false, {}});
    scene.blendGroups.push_back({{}, true, {}});
    SCOPED_TRACE(static_cast<int>(kind));
    expectRoundTrip(scene);
  }
}

TEST(SceneWriter, PolygonizersRoundTrip) {
  Scene tess;
  Tesselator3MPNode t;
  t.seed = -7;
  t.numThreads = 0;
  t.useSimpleRadii = false;
  t.sceneGraph = ShapeNode{};
  tess.polygonizer = t;  // no blendingFunction
  expectRoundTrip(tess);

  Scene mc;
  MarchingCubesNode m;  // cellSize unset (0): not written
  m.xResolution = 7;
  BlendNode f;
  f.kind = BlendKind::Elliptical;
  f.blendRange = 2.0f;
  m.blendingFunction = f;
  mc.polygonizer = m;
  expectRoundTrip(mc);
  EXPECT_EQ(writeScene(mc).find("cellSize"), std::string::npos);

  // A blendingFunction that USEs a blend DEF'd in the sceneGraph is written after it, so it reads back.
  for (const char* polygonizer : {"Tesselator3MP", "MarchingCubes"}) {
    const Scene shared = readOrFail(std::string("#VRML V2.0 utf8\n") + polygonizer +
                                    " { sceneGraph DEF B BlancSchlickBlend { } blendingFunction USE B }");
    expectRoundTrip(shared);
    const std::string text = writeScene(shared);
    EXPECT_LT(text.find("sceneGraph DEF B"), text.find("blendingFunction USE B")) << text;
  }

  expectRoundTrip(Scene{});
  EXPECT_EQ(writeScene(Scene{}), "#VRML V2.0 utf8\n");
}

// ---- saveSceneFile ----

class SceneSave : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("imps_scene_save_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  size_t entries() const { return static_cast<size_t>(std::distance(fs::directory_iterator(dir_), {})); }
  fs::path dir_;
};

TEST_F(SceneSave, SavesAndReadsBack) {
  auto scene = readSceneFile(scenePath("hierarchical_blanc_schlick.wrl"));
  ASSERT_TRUE(scene.has_value());
  const std::string path = (dir_ / "out.wrl").string();
  const auto saved = saveSceneFile(*scene, path);
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_EQ(slurp(path), writeScene(*scene));
  auto again = readSceneFile(path);
  ASSERT_TRUE(again.has_value()) << again.error().str();
  EXPECT_EQ(*again, *scene);
  EXPECT_EQ(entries(), 1u);  // no temporary file left behind
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
}

TEST_F(SceneSave, OverwritesKeepingPermissions) {
  const std::string path = (dir_ / "out.wrl").string();
  { std::ofstream(path) << "old contents"; }
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  Scene scene;
  scene.root = ShapeNode{};
  const auto saved = saveSceneFile(scene, path);
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_EQ(slurp(path), writeScene(scene));
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
}

TEST_F(SceneSave, FailedRenameLeavesTheTargetAndNoTemporaryFile) {
  // The target is a non-empty directory: everything succeeds up to the rename, which must fail.
  const fs::path target = dir_ / "scene.wrl";
  fs::create_directories(target / "inside");
  Scene scene;
  scene.root = ShapeNode{};
  const auto saved = saveSceneFile(scene, target.string());
  ASSERT_FALSE(saved);
  const std::string& error = saved.error().message;
  EXPECT_EQ(error.rfind("cannot save '" + target.string() + "': renaming the temporary file over it: ", 0), 0u)
      << error;
  EXPECT_TRUE(fs::is_directory(target / "inside"));
  EXPECT_EQ(entries(), 1u);
}

TEST_F(SceneSave, UnwritableDirectoryLeavesTheTarget) {
  const std::string path = (dir_ / "missing" / "scene.wrl").string();
  const auto saved = saveSceneFile(Scene{}, path);
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().message, "cannot save '" + path + "': creating a temporary file: No such file or directory");
  EXPECT_EQ(saved.error().path, path);
  EXPECT_FALSE(fs::exists(path));

  // An existing file in a directory that refuses new files keeps its contents (when not running as root,
  // which ignores permissions).
  if (::geteuid() != 0) {
    const std::string kept = (dir_ / "kept.wrl").string();
    { std::ofstream(kept) << "precious"; }
    ASSERT_EQ(::chmod(dir_.c_str(), 0555), 0);
    EXPECT_FALSE(saveSceneFile(Scene{}, kept));
    ::chmod(dir_.c_str(), 0755);
    EXPECT_EQ(slurp(kept), "precious");
  }
}

}  // namespace
}  // namespace imps
