// SPDX-License-Identifier: MIT
// Exporting takes on the character: the skeleton BVH reproduces the skeleton cache's pose frame for frame (by BVH
// forward kinematics after a write/read round trip), frames are resampled and cut as asked, the skinned glTF's
// weights are normalised and its skin follows the implicit surface, the Khronos validator accepts it (when node and
// gltf-validator are installed), and surface sequences are numbered files.
#include "export_gltf.h"
#include "export_surfaces.h"
#include "export_take.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <cstring>
#include <random>

#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "examples.h"
#include "failure_text.h"
#include "imps/mesh_io.h"
#include "sim/bvh.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

// A take on the biped: every joint turned by up to 40 degrees about a random axis, the pelvis walking and jumping.
Take randomTake(const Character& c, size_t frames) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Take take;
  take.frameTime = 1.0 / 25.0;
  for (size_t f = 0; f < frames; ++f) {
    std::vector<Rigid> locals;
    for (const Joint& j : c.joints()) {
      Rigid r = j.rest;
      const glm::vec3 axis = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0, 0.01f));
      r.rotation = glm::normalize(glm::angleAxis(glm::radians(40.0f) * u(rng), axis) * j.rest.rotation);
      if (j.parent < 0) r.translation += glm::vec3(0.05f * float(f), 0.2f * std::sin(float(f)), 0.0f);
      locals.push_back(r);
    }
    take.locals.push_back(locals);
  }
  return take;
}

// World positions of every joint of a BVH clip at frame f (position channels replace the OFFSET).
std::vector<glm::dvec3> bvhPositions(const sim::BvhClip& clip, size_t f) {
  std::vector<glm::dvec3> pos(clip.joints.size());
  std::vector<glm::dquat> rot(clip.joints.size());
  size_t ch = 0;
  for (size_t j = 0; j < clip.joints.size(); ++j) {
    const sim::BvhJoint& joint = clip.joints[j];
    glm::dvec3 p(joint.offset[0], joint.offset[1], joint.offset[2]);
    glm::dquat q{1.0, 0.0, 0.0, 0.0};
    for (sim::BvhChannel c : joint.channels) {
      const double v = clip.frames[f][ch++];
      if (!sim::isRotation(c)) {
        p[static_cast<int>(c)] = v;
      } else {
        glm::dvec3 axis(0.0);
        axis[static_cast<int>(c) - static_cast<int>(sim::BvhChannel::Xrotation)] = 1.0;
        q = q * glm::angleAxis(glm::radians(v), axis);
      }
    }
    const int parent = joint.parent;
    pos[j] = parent < 0 ? p : pos[size_t(parent)] + rot[size_t(parent)] * p;
    rot[j] = parent < 0 ? q : rot[size_t(parent)] * q;
  }
  return pos;
}

TEST(Export, EulerZXYRoundTrips) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const glm::dquat q = glm::normalize(glm::dquat(u(rng), u(rng), u(rng), u(rng)));
    const glm::dvec3 e = glm::radians(eulerZXYDegrees(q));
    const glm::dquat back = glm::angleAxis(e.x, glm::dvec3(0, 0, 1)) * glm::angleAxis(e.y, glm::dvec3(1, 0, 0)) *
                            glm::angleAxis(e.z, glm::dvec3(0, 1, 0));
    EXPECT_GT(std::abs(glm::dot(q, back)), 1.0 - 1e-9) << i;
  }
}

// The exported BVH, written and read back, puts every joint where the skeleton cache does, frame after frame.
TEST(Export, CharacterBvhMatchesTheSkeletonCacheFrameForFrame) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const Take take = randomTake(biped, 10);
  const sim::BvhClip written = characterClip(biped, take);
  auto clip = sim::readBvhText(sim::writeBvh(written).value(), "biped.bvh");
  ASSERT_TRUE(clip.has_value()) << clip.error().str();
  ASSERT_EQ(clip->joints.size(), biped.joints().size());
  ASSERT_EQ(clip->frames.size(), 10u);
  EXPECT_NEAR(clip->frameTime, 0.04, 1e-12);
  SkeletonCache skeleton(biped);
  double worst = 0;
  for (size_t f = 0; f < take.frames(); ++f) {
    for (size_t j = 0; j < biped.joints().size(); ++j) {
      skeleton.setRotation(static_cast<int>(j), take.locals[f][j].rotation);
      skeleton.setTranslation(static_cast<int>(j), take.locals[f][j].translation);
    }
    skeleton.update();
    const std::vector<glm::dvec3> pos = bvhPositions(*clip, f);
    for (size_t b = 0; b < clip->joints.size(); ++b) {
      const int j = biped.findJoint(clip->joints[b].name);
      ASSERT_GE(j, 0) << clip->joints[b].name;
      worst = std::max(worst, glm::length(pos[b] - glm::dvec3(skeleton.world(j).translation)));
    }
  }
  EXPECT_LT(worst, 1e-4) << "metres";
  // Only the root moves, so only the root has position channels.
  for (const sim::BvhJoint& j : clip->joints) EXPECT_EQ(j.channels.size(), j.parent < 0 ? 6u : 3u) << j.name;
}

TEST(Export, FramesAreResampledAndCut) {
  const std::vector<double> times = {0.0, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10};  // 100 fps
  double frameTime = 0;
  auto all = selectFrames(times, 0.01, {}, &frameTime);
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(all->size(), 11u);
  EXPECT_DOUBLE_EQ(frameTime, 0.01);
  auto half = selectFrames(times, 0.01, {50, 0, -1}, &frameTime);
  ASSERT_TRUE(half.has_value());
  EXPECT_EQ(*half, (std::vector<size_t>{0, 2, 4, 6, 8, 10}));
  EXPECT_DOUBLE_EQ(frameTime, 0.02);
  auto cut = selectFrames(times, 0.01, {50, 1, 3}, &frameTime);
  ASSERT_TRUE(cut.has_value());
  EXPECT_EQ(*cut, (std::vector<size_t>{2, 4, 6}));
  EXPECT_FALSE(selectFrames(times, 0.01, {0, 5, 20}, &frameTime).has_value());
  EXPECT_FALSE(selectFrames(times, 0.01, {0, 4, 3}, &frameTime).has_value());
  EXPECT_FALSE(selectFrames({}, 0.01, {}, &frameTime).has_value());
}

struct Glb {
  nlohmann::json json;
  std::vector<uint8_t> bin;
};

Glb parseGlb(const std::vector<uint8_t>& bytes) {
  auto u32 = [&](size_t at) {
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= uint32_t(bytes[at + size_t(k)]) << (8 * k);
    return v;
  };
  EXPECT_EQ(u32(0), 0x46546C67u);
  EXPECT_EQ(u32(8), bytes.size());
  const uint32_t jsonLength = u32(12);
  Glb g;
  g.json = nlohmann::json::parse(std::string(bytes.begin() + 20, bytes.begin() + 20 + jsonLength));
  const size_t binAt = 20 + jsonLength;
  g.bin.assign(bytes.begin() + static_cast<std::ptrdiff_t>(binAt + 8), bytes.end());
  return g;
}

template <typename T>
std::vector<T> accessorData(const Glb& g, int accessor, size_t components) {
  const auto& a = g.json["accessors"][size_t(accessor)];
  const auto& v = g.json["bufferViews"][a["bufferView"].get<size_t>()];
  const size_t count = a["count"].get<size_t>() * components;
  std::vector<T> out(count);
  std::memcpy(out.data(), g.bin.data() + v["byteOffset"].get<size_t>(), count * sizeof(T));
  return out;
}

// Weights: at most four joints, normalised; skinned by the exported skin, the rest mesh follows the posed implicit
// surface (linear blend skinning stays within a few cells of the true surface where the primitives are rigid).
TEST(Export, SkinnedGlbWeightsAreNormalisedAndTheSkinFollowsTheSurface) {
  const Character& biped = test::exampleCharacter("simple_biped");
  const Take take = randomTake(biped, 4);
  GltfExportOptions o;
  o.cellSize = 0.03f;
  const auto encoded = encodeSkinnedGlb(biped, take, o);
  ASSERT_TRUE(encoded) << encoded.error().str();
  const std::vector<uint8_t>& bytes = *encoded;
  ASSERT_FALSE(bytes.empty());
  const Glb g = parseGlb(bytes);
  const auto& prim = g.json["meshes"][0]["primitives"][0];
  const auto positions = accessorData<float>(g, prim["attributes"]["POSITION"].get<int>(), 3);
  const auto joints = accessorData<uint16_t>(g, prim["attributes"]["JOINTS_0"].get<int>(), 4);
  const auto weights = accessorData<float>(g, prim["attributes"]["WEIGHTS_0"].get<int>(), 4);
  const auto ibm = accessorData<float>(g, g.json["skins"][0]["inverseBindMatrices"].get<int>(), 16);
  const size_t vertices = positions.size() / 3, n = biped.joints().size();
  ASSERT_GT(vertices, 1000u);
  for (size_t v = 0; v < vertices; ++v) {
    float sum = 0;
    for (int k = 0; k < 4; ++k) {
      EXPECT_GE(weights[4 * v + size_t(k)], 0.0f);
      EXPECT_LT(joints[4 * v + size_t(k)], n);
      sum += weights[4 * v + size_t(k)];
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f) << v;
  }
  EXPECT_EQ(g.json["skins"][0]["joints"].size(), n);
  EXPECT_EQ(g.json["animations"][0]["channels"].size(), n + 1) << "every rotation, and the pelvis' translation";
  // Pose the rest mesh with the skin at the last frame and measure its distance to the posed surface.
  SkeletonCache skeleton(biped);
  const auto& last = take.locals.back();
  for (size_t j = 0; j < n; ++j) {
    skeleton.setRotation(static_cast<int>(j), last[j].rotation);
    skeleton.setTranslation(static_cast<int>(j), last[j].translation);
  }
  skeleton.update();
  std::vector<float> off;
  for (size_t v = 0; v < vertices; ++v) {
    glm::vec3 x(0.0f);
    for (int k = 0; k < 4; ++k) {
      const size_t j = joints[4 * v + size_t(k)];
      glm::mat4 inv;
      std::memcpy(&inv[0][0], &ibm[16 * j], 64);
      const Rigid& w = skeleton.world(static_cast<int>(j));
      const glm::vec3 local =
          glm::vec3(inv * glm::vec4(positions[3 * v], positions[3 * v + 1], positions[3 * v + 2], 1));
      x += weights[4 * v + size_t(k)] * w.apply(local);
    }
    const FieldSample fs = skeleton.field().sample(x);
    off.push_back(std::fabs(fs.value - skeleton.field().iso()) / std::max(glm::length(fs.gradient), 1e-3f));
  }
  std::sort(off.begin(), off.end());
  const float median = off[off.size() / 2], p90 = off[off.size() * 9 / 10];
  std::printf("skinned rest mesh vs posed surface: median %.4f m, 90th percentile %.4f m (cell %.3f m)\n", median, p90,
              o.cellSize);
  EXPECT_LT(median, o.cellSize);
  EXPECT_LT(p90, 3 * o.cellSize);

  // The Khronos validator, when it is installed (npm install -g gltf-validator).
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "imps_export_test";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "take.glb").string();
  const auto written = writeSkinnedGlb(biped, take, o, path);
  ASSERT_TRUE(written) << written.error().str();
  const std::string script = std::string(IMPS_SOURCE_DIR) + "/tests/puppeteer/validate_gltf.js";
  const std::string command = "command -v node >/dev/null 2>&1 && NODE_PATH=\"$(npm root -g 2>/dev/null)\" node '" +
                              script + "' '" + path + "' > '" + (dir / "report.txt").string() + "' 2>&1";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream report(dir / "report.txt");
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  if (code != 0 && code != 1) GTEST_SKIP() << "node or gltf-validator not available: " << text;
  std::printf("gltf-validator: %s", text.c_str());
  EXPECT_EQ(code, 0) << text;
}

// A session split over two devices: a calibration channel on device 1 drives its joint in every exported frame
// (the frame of each device-0 sample includes the device-1 sample recorded after it).
TEST(Export, SessionChannelsOfTheSecondDeviceDriveTheTake) {
  const Character& biped = test::exampleCharacter("simple_biped");
  sim::Session session;
  for (int d = 0; d < 2; ++d) {
    drivers::DeviceInfo info;
    info.name = "part " + std::to_string(d);
    info.channelCount = 2;
    info.bitsPerChannel = 12;
    info.channelNames = {"a" + std::to_string(d), "b" + std::to_string(d)};
    info.hasDeviceTimestamp = true;
    session.devices.push_back(info);
  }
  for (uint32_t f = 0; f < 5; ++f)
    for (uint16_t d = 0; d < 2; ++d) {
      drivers::Sample s;
      s.sequence = f;
      s.deviceTimeNs = s.arrivalTimeNs = int64_t(f) * 10'000'000;
      s.channelCount = 2;
      s.counts[0] = 2048;
      s.counts[1] = d == 1 ? 2048 + 100 * f : 2048;
      session.samples.push_back(s);
      session.sampleDevice.push_back(d);
    }
  const std::string json = R"({"version": 1, "bits": 12, "joints": [
    {"joint": "L_Forearm", "channels": [{"channel": "b1", "axis": "y", "sign": 1, "offset": 2048}]}]})";
  auto cal = calibration::Calibration::parse(json, "cal.json", &biped, &session.devices[0], session.devices);
  ASSERT_TRUE(cal.has_value()) << cal.error().str();
  EXPECT_EQ(cal->rigMap().channels[0].device, 1);
  auto take = takeFromSession(session, *cal, biped, {});
  ASSERT_TRUE(take.has_value()) << take.error().str();
  ASSERT_EQ(take->frames(), 5u);
  EXPECT_NEAR(take->frameTime, 0.01, 1e-12);
  const size_t fore = size_t(biped.findJoint("L_Forearm"));
  for (size_t f = 0; f < 5; ++f) {
    const glm::quat relative = glm::inverse(biped.joints()[fore].rest.rotation) * take->locals[f][fore].rotation;
    EXPECT_NEAR(glm::angle(relative), 100.0 * double(f) * 2 * 3.14159265358979 / 4096, 1e-4) << f;
  }
}

TEST(Export, SurfaceSequencesAreNumberedFiles) {
  EXPECT_EQ(sequenceFileName("out/take_####.ply", 7), "out/take_0007.ply");
  EXPECT_EQ(sequenceFileName("f#.obj", 12), "f12.obj");
  const Character& biped = test::exampleCharacter("simple_biped");
  const Take take = randomTake(biped, 2);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "imps_export_seq";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  SurfaceSequenceOptions o;
  o.cellSize = 0.04f;
  size_t progress = 0;
  o.progress = [&](size_t done) { progress = done; };
  ASSERT_EQ(test::failureText(writeSurfaceSequence(Scene{}, biped, take, o, (dir / "take_###.ply").string())), "");
  EXPECT_EQ(progress, 2u);
  EXPECT_TRUE(std::filesystem::exists(dir / "take_000.ply"));
  EXPECT_TRUE(std::filesystem::exists(dir / "take_001.ply"));
  EXPECT_NE(std::filesystem::file_size(dir / "take_000.ply"), std::filesystem::file_size(dir / "take_001.ply"));
  EXPECT_FALSE(writeSurfaceSequence(Scene{}, biped, take, o, "/dev/null/take_#.ply"));
}

}  // namespace
}  // namespace imps::app
