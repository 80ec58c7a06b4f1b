// SPDX-License-Identifier: MIT
// Tests for worlds on the command line: `render WORLD` draws every character where its Transform placed it,
// `--drive NAME=CLIP` poses one character, bad worlds and bad --drive specs fail with file:line:column or a clear
// message, `mesh WORLD` writes each character and prop as its own glTF node (checked by the Khronos validator when
// installed) and OBJ object, and `mesh SCENE --prop` writes the prop beside the character.
#include "world_scene.h"

#include <gtest/gtest.h>
#include <unistd.h>
#include <sys/wait.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "subprocess.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
const std::string kSource = IMPS_SOURCE_DIR;
fs::path puppeteer() { return IMPS_PUPPETEER_BINARY; }

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;
  const uint8_t* at(int x, int y) const { return &rgba[4 * (size_t(y) * size_t(width) + size_t(x))]; }
};

Image readImage(const std::string& path) {
  Image image;
  auto in = OIIO::ImageInput::open(path);
  if (!in) return image;
  image.width = in->spec().width, image.height = in->spec().height;
  image.rgba.resize(size_t(image.width) * size_t(image.height) * 4);
  if (in->spec().nchannels != 4 || !in->read_image(0, 0, 0, 4, OIIO::TypeDesc::UINT8, image.rgba.data())) image = {};
  return image;
}

// Mean x (pixels) of the strongly red and the strongly blue pixels, and how many there are.
struct Silhouettes {
  double redX = 0, blueX = 0;
  size_t red = 0, blue = 0;
};
Silhouettes silhouettes(const Image& image) {
  Silhouettes s;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.at(x, y);
      if (p[0] > 120 && p[0] > 2 * p[1] && p[0] > 2 * p[2]) s.redX += x, ++s.red;
      if (p[2] > 120 && p[2] > 2 * p[0] && p[2] > 2 * p[1]) s.blueX += x, ++s.blue;
    }
  if (s.red) s.redX /= double(s.red);
  if (s.blue) s.blueX /= double(s.blue);
  return s;
}

class WorldCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("imps_world_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // Two one-joint characters, a red and a blue ball; a clip that lifts the joint by 1 m.
    for (const auto& [name, color] : {std::pair{"red", "1 0 0"}, std::pair{"blue", "0 0 1"}})
      write(std::string(name) + ".wrl", "#VRML V2.0 utf8\nDEF ROOT RigidTransform { children [ Metaball { radius 0.5 "
                                        "material Material { diffuseColor " + std::string(color) + " } } ] }\n");
    write("lift.wrl",
          "#VRML V2.0 utf8\nDEF ROOT Transform { }\nDEF LIFT TimeSensor { cycleInterval 1 }\n"
          "DEF P PositionInterpolator { key [ 0 1 ] keyValue [ 0 0 0, 0 2 0 ] }\n"
          "ROUTE LIFT.fraction_changed TO P.set_fraction\nROUTE P.value_changed TO ROOT.set_translation\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  // A world with the red ball at x = redX and the blue one at x = blueX.
  std::string world(float redX, float blueX, const std::string& extra = "") {
    return write("w.wrl", "#VRML V2.0 utf8\nDEF RED Transform { translation " + std::to_string(redX) +
                              " 0 0 children [ Inline { url \"red.wrl\" } ] }\nDEF BLUE Transform { translation " +
                              std::to_string(blueX) + " 0 0 children [ Inline { url \"blue.wrl\" } " + extra +
                              "] }\n");
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(WorldCli, RenderDrawsEveryCharacterWhereItsTransformPlacesIt) {
  const std::vector<std::string> common{"--res", "24", "--width", "160", "--height", "80", "--view", "front"};
  auto render = [&](const std::string& w, const std::string& out, std::vector<std::string> more = {}) {
    std::vector<std::string> args{"render", w, "-o", out};
    args.insert(args.end(), common.begin(), common.end());
    args.insert(args.end(), more.begin(), more.end());
    return test::runProgram(puppeteer(), args);
  };
  const auto a = render(world(-1.5f, 1.5f), path("a.png"));
  ASSERT_EQ(a.exitCode, 0) << a.err;
  EXPECT_NE(a.out.find("2 characters"), std::string::npos) << a.out;
  const Silhouettes left = silhouettes(readImage(path("a.png")));
  ASSERT_GT(left.red, 100u) << "the red character is drawn";
  ASSERT_GT(left.blue, 100u) << "the blue character is drawn";
  EXPECT_LT(left.redX, 80.0) << "red at x = -1.5 is on the left";
  EXPECT_GT(left.blueX, 80.0) << "blue at x = +1.5 is on the right";
  EXPECT_NEAR(double(left.red), double(left.blue), 0.25 * double(left.red)) << "equal balls, equal areas";

  // Swapped Transforms swap the silhouettes.
  const auto b = render(world(1.5f, -1.5f), path("b.png"));
  ASSERT_EQ(b.exitCode, 0) << b.err;
  const Silhouettes swapped = silhouettes(readImage(path("b.png")));
  EXPECT_GT(swapped.redX, 80.0);
  EXPECT_LT(swapped.blueX, 80.0);
}

// Vertical centre (pixels) of the strongly red (channel 0) or blue (channel 2) pixels; -1 without any.
double centreY(const Image& image, int channel) {
  double sum = 0;
  size_t n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const uint8_t* p = image.at(x, y);
      const int a = channel == 0 ? 1 : 0, b = channel == 0 ? 2 : 1;
      if (p[channel] > 120 && p[channel] > 2 * p[a] && p[channel] > 2 * p[b]) sum += y, ++n;
    }
  return n ? sum / double(n) : -1.0;
}

TEST_F(WorldCli, DrivePosesOneCharacterAndAnInlinedClipPlaysByItself) {
  const std::vector<std::string> common{"--res", "24", "--width", "120", "--height", "120", "--view", "front"};
  auto render = [&](const std::string& w, const std::string& out, std::vector<std::string> more) {
    std::vector<std::string> args{"render", w, "-o", out};
    args.insert(args.end(), common.begin(), common.end());
    args.insert(args.end(), more.begin(), more.end());
    return test::runProgram(puppeteer(), args);
  };
  const std::string w = world(-1.0f, 1.0f);
  const auto rest = render(w, path("rest.png"), {});
  const auto lifted = render(w, path("lifted.png"), {"--drive", "BLUE=" + path("lift.wrl"), "--at", "0.5"});
  ASSERT_EQ(rest.exitCode, 0) << rest.err;
  ASSERT_EQ(lifted.exitCode, 0) << lifted.err;
  const Image restImage = readImage(path("rest.png")), liftedImage = readImage(path("lifted.png"));
  ASSERT_GE(centreY(restImage, 2), 0.0);
  ASSERT_GE(centreY(liftedImage, 0), 0.0);
  EXPECT_NEAR(centreY(restImage, 2), centreY(restImage, 0), 3.0) << "undriven, both stand at the same height";
  // Lifted by 1 m at t = 0.5 s: the blue ball sits higher than the red one (image y grows downwards).
  EXPECT_LT(centreY(liftedImage, 2) + 5.0, centreY(liftedImage, 0)) << "the driven character moved up";

  // The same clip inlined beside BLUE plays without --drive.
  const std::string inlined = world(-1.0f, 1.0f, "Inline { url \"lift.wrl\" } ");
  const auto byWorld = render(inlined, path("inlined.png"), {"--at", "0.5"});
  ASSERT_EQ(byWorld.exitCode, 0) << byWorld.err;
  EXPECT_NEAR(centreY(readImage(path("inlined.png")), 2), centreY(liftedImage, 2), 1.0);

  // A --drive naming no character, or a source render cannot sample.
  const auto typo = render(w, path("never.png"), {"--drive", "BLEU=" + path("lift.wrl")});
  EXPECT_EQ(typo.exitCode, 2);
  EXPECT_NE(typo.err.find("w.wrl: error: --drive BLEU="), std::string::npos) << typo.err;
  EXPECT_NE(typo.err.find("the world places no character 'BLEU' (did you mean 'BLUE'?)"), std::string::npos)
      << typo.err;
  const auto session =
      render(w, path("never.png"), {"--drive", "BLUE=" + kSource + "/examples/simple_biped_wave.session"});
  EXPECT_EQ(session.exitCode, 1);
  EXPECT_NE(session.err.find("samples VRML clips only"), std::string::npos) << session.err;
  const auto twice = render(w, path("never.png"), {"--drive", "BLUE=" + path("lift.wrl"), "--drive",
                                                   "BLUE=" + path("lift.wrl")});
  EXPECT_EQ(twice.exitCode, 2);
  EXPECT_FALSE(fs::exists(path("never.png")));
}

// A prop on a character's joint (a Transform named after the joint, beside the character) moves with the joint
// when the character's clip lifts it; a prop of the world stays.
TEST_F(WorldCli, PropsOnAJointFollowItsClip) {
  const std::string w = write("w.wrl",
                              "#VRML V2.0 utf8\nDEF BLUE Transform { translation 1 0 0 children [\n"
                              "  Inline { url \"blue.wrl\" } Inline { url \"lift.wrl\" }\n"
                              "  DEF ROOT Transform { children [ Shape { geometry Box { size 0.2 0.2 0.2 } } ] } ] }\n"
                              "Shape { geometry Sphere { radius 0.1 } }\n");
  auto world = readWorldFile(w);
  ASSERT_TRUE(world.has_value()) << world.error().str();
  MarchingCubesOptions options;
  options.resolution = 16;
  const std::vector<std::string> noDrives(world->characters.size());
  auto start = poseWorld(*world, noDrives, 0.0, options, nullptr, "test");
  auto half = poseWorld(*world, noDrives, 0.5, options, nullptr, "test");
  ASSERT_TRUE(start && half);
  auto centreOf = [](const std::vector<WorldObject>& objects, const std::string& name) {
    for (const WorldObject& o : objects)
      if (o.name == name) return 0.5f * (bounds(o.mesh).min + bounds(o.mesh).max);
    return glm::vec3(-999.0f);
  };
  ASSERT_EQ(start->size(), 3u);
  const std::string box = (*start)[1].name, sphere = (*start)[2].name;
  EXPECT_NEAR(glm::length(centreOf(*start, box) - glm::vec3(1, 0, 0)), 0.0f, 1e-4f) << box;
  // lift.wrl raises ROOT by 2 m over 1 s: 1 m at 0.5 s, the box with it; the world's sphere stays.
  EXPECT_NEAR(glm::length(centreOf(*half, box) - glm::vec3(1, 1, 0)), 0.0f, 1e-4f);
  EXPECT_NEAR(glm::length(centreOf(*half, sphere) - centreOf(*start, sphere)), 0.0f, 1e-6f);
}

TEST_F(WorldCli, BadWorldsFailWithTheirPosition) {
  const std::string missing =
      write("m.wrl", "#VRML V2.0 utf8\nTransform {\n  children [ Inline { url \"gone.wrl\" } ] }\n");
  const std::string notScene = write("n.wrl", "#VRML V2.0 utf8\nInline { url \"red.png\" }\n");
  write("red.png", "\x89PNG not really");
  for (const std::string command : {"render", "mesh", "check"}) {
    std::vector<std::string> args{command, missing};
    if (command != "check") args.insert(args.end(), {"-o", path(command == "render" ? "x.png" : "x.glb")});
    const auto run = test::runProgram(puppeteer(), args);
    EXPECT_EQ(run.exitCode, 1) << command << run.out;
    EXPECT_NE(run.err.find("m.wrl:3:27: error: Inline: no url names a file that can be read"), std::string::npos)
        << command << ": " << run.err;
  }
  const auto run = test::runProgram(puppeteer(), {"render", notScene, "-o", path("x.png")});
  EXPECT_EQ(run.exitCode, 1);
  EXPECT_NE(run.err.find("n.wrl:2:14: error: Inline 'red.png'"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("neither an IMPS character scene nor a VRML 97 file"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(path("x.png")));
}

nlohmann::json glbJson(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (bytes.size() < 20) return {};
  uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return nlohmann::json::parse(std::string(bytes.data() + 20, length));
}

// Runs the Khronos validator on `glb`: 0 valid, 1 errors, anything else: not available.
int validate(const std::string& glb, std::string* report) {
  const std::string script = kSource + "/tests/puppeteer/validate_gltf.js";
  const std::string out = glb + ".report.txt";
  const std::string command = "command -v node >/dev/null 2>&1 && NODE_PATH=\"$(npm root -g 2>/dev/null)\" node '" +
                              script + "' '" + glb + "' > '" + out + "' 2>&1";
  const int status = std::system(command.c_str());
  std::ifstream in(out);
  *report = std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(WorldCli, MeshWritesEachCharacterAndPropAsItsOwnNode) {
  const std::string w = world(-1.0f, 1.0f, "Shape { geometry Box { size 0.2 0.2 0.2 } } ");
  const auto glb = test::runProgram(puppeteer(), {"mesh", w, "--res", "16", "-o", path("w.glb")});
  ASSERT_EQ(glb.exitCode, 0) << glb.err;
  const auto json = glbJson(path("w.glb"));
  ASSERT_EQ(json["nodes"].size(), 3u) << json.dump();
  EXPECT_EQ(json["nodes"][0]["name"], "RED");
  EXPECT_EQ(json["nodes"][1]["name"], "BLUE");
  EXPECT_EQ(json["scenes"][0]["nodes"].size(), 3u);
  for (const auto& node : json["nodes"]) EXPECT_TRUE(node.contains("mesh")) << node.dump();
  // RED's vertices are where its Transform put them.
  const auto& red = json["accessors"][size_t(json["meshes"][0]["primitives"][0]["attributes"]["POSITION"])];
  EXPECT_LT(double(red["max"][0]), -0.3);
  EXPECT_GT(double(red["min"][0]), -1.7);
  std::string report;
  const int valid = validate(path("w.glb"), &report);
  if (valid == 0 || valid == 1) {
    EXPECT_EQ(valid, 0) << report;
  }

  const auto obj = test::runProgram(puppeteer(), {"mesh", w, "--res", "16", "-o", path("w.obj")});
  ASSERT_EQ(obj.exitCode, 0) << obj.err;
  std::ifstream in(path("w.obj"));
  std::string line;
  size_t objects = 0;
  while (std::getline(in, line)) objects += line.starts_with("o ") ? 1 : 0;
  EXPECT_EQ(objects, 3u);

  // One character scene with a prop on a joint: two nodes, the prop where the joint is.
  const auto withProp = test::runProgram(
      puppeteer(), {"mesh", kSource + "/examples/beanito.wrl", "--res", "16", "--prop",
                    kSource + "/examples/beanito_hat.wrl@BEAN_TOP", "-o", path("hat.glb")});
  ASSERT_EQ(withProp.exitCode, 0) << withProp.err;
  const auto hat = glbJson(path("hat.glb"));
  EXPECT_GE(hat["nodes"].size(), 2u);
  EXPECT_EQ(hat["nodes"][0]["name"], "beanito");
  const int hatValid = validate(path("hat.glb"), &report);
  if (hatValid == 0 || hatValid == 1) {
    EXPECT_EQ(hatValid, 0) << report;
  }
}

}  // namespace
}  // namespace imps::app
