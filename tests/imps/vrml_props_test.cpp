// SPDX-License-Identifier: MIT
// Tests for readProps and the primitive meshes: volumes and orientation, fan triangulation, transforms, bad data.
#include "imps/vrml_props.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

namespace imps {
namespace {

const std::string kHeader = "#VRML V2.0 utf8\n";
constexpr double kPi = std::numbers::pi;

std::vector<Prop> propsOf(const std::string& text, Diagnostics* warnings = nullptr) {
  auto file = readVrml(text, "p.wrl");
  EXPECT_TRUE(file.has_value()) << (file ? "" : file.error().str());
  return file ? readProps(*file, warnings) : std::vector<Prop>{};
}

TEST(Props, PrimitivesAreClosedAndFaceOutwards) {
  // The signed volume of a closed surface facing outwards is its volume (positive).
  EXPECT_NEAR(signedVolume(boxMesh({1, 2, 3})), 6.0, 1e-5);
  EXPECT_NEAR(signedVolume(sphereMesh(1.0f)), 4.0 / 3.0 * kPi, 0.05 * 4.0 / 3.0 * kPi);
  EXPECT_NEAR(signedVolume(cylinderMesh(0.5f, 2.0f)), kPi * 0.25 * 2.0, 0.02 * kPi * 0.5);
  EXPECT_NEAR(signedVolume(coneMesh(1.0f, 3.0f)), kPi, 0.02 * kPi);
  for (const Mesh& m : {boxMesh({1, 1, 1}), sphereMesh(1), cylinderMesh(1, 1), coneMesh(1, 1)}) {
    EXPECT_EQ(m.normals.size(), m.positions.size());
    EXPECT_EQ(m.colors.size(), m.positions.size());
  }
}

TEST(Props, ShapesAreTransformedAndColoured) {
  const auto props = propsOf(kHeader +
                             "DEF T Transform { translation 10 0 0 scale 2 2 2 children [ DEF Hat Shape {\n"
                             "  appearance Appearance { material Material { diffuseColor 1 0 0 } }\n"
                             "  geometry Box { size 1 1 1 } } ] }");
  ASSERT_EQ(props.size(), 1u);
  EXPECT_EQ(props[0].name, "Hat");
  EXPECT_EQ(props[0].geometry, "Box");
  const MeshBounds b = bounds(props[0].mesh);
  EXPECT_NEAR(b.min.x, 9.0f, 1e-5f);
  EXPECT_NEAR(b.max.x, 11.0f, 1e-5f);
  EXPECT_NEAR(signedVolume(props[0].mesh), 8.0, 1e-4);
  EXPECT_EQ(props[0].mesh.color(0), glm::vec3(1, 0, 0));
}

TEST(Props, FacesAreFanTriangulatedAndCcwFalseTurnsThemRound) {
  // A unit cube of quads, the last face without its -1, written clockwise (ccw FALSE).
  const std::string cube =
      "coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 1, 1 0 1, 1 1 1, 0 1 1 ] }\n"
      "coordIndex [ 0 1 2 3 -1, 4 7 6 5 -1, 0 4 5 1 -1, 1 5 6 2 -1, 2 6 7 3 -1, 3 7 4 0 ] }";
  const auto cw = propsOf(kHeader + "Shape { geometry IndexedFaceSet { ccw FALSE " + cube + " }");
  ASSERT_EQ(cw.size(), 1u);
  EXPECT_EQ(cw[0].mesh.triangleCount(), 12u);
  EXPECT_NEAR(signedVolume(cw[0].mesh), 1.0, 1e-5);
  const auto ccw = propsOf(kHeader + "Shape { geometry IndexedFaceSet { " + cube + " }");
  EXPECT_NEAR(signedVolume(ccw[0].mesh), -1.0, 1e-5);  // the same faces read counter-clockwise: inside out
}

TEST(Props, BadFacesAreLeftOutWithAWarning) {
  Diagnostics warnings;
  const auto props = propsOf(kHeader + "Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, "
                                       "0 1 0 ] }\n coordIndex [ 0 1 2 -1, 0 1 9 -1, 0 1 -1 ] } }",
                             &warnings);
  ASSERT_EQ(props.size(), 1u);
  EXPECT_EQ(props[0].mesh.triangleCount(), 1u);
  EXPECT_EQ(warnings.str(), "p.wrl:3:2: warning: coordIndex has a face with fewer than 3 points or an index beyond "
                            "the 3 points; such faces are left out\n");
  Diagnostics more;
  EXPECT_TRUE(propsOf(kHeader + "Shape { geometry Sphere { radius -1 } } Shape { geometry Text { } }", &more).empty());
  EXPECT_NE(more.str().find("Sphere has no triangles"), std::string::npos) << more.str();
  EXPECT_NE(more.str().find("Text geometry is not drawn as a prop"), std::string::npos) << more.str();
}

TEST(Props, QuirkFilesGiveTheirProps) {
  auto file = readVrmlFile(std::string(IMPS_SOURCE_DIR) + "/tests/data/worlds/blender_quirks.wrl");
  ASSERT_TRUE(file.has_value());
  const auto props = readProps(*file);
  ASSERT_EQ(props.size(), 3u);
  // Two instances of one cube mesh (USE), scaled by 0.5 and 1 m apart; a pyramid written with ccw FALSE.
  EXPECT_NEAR(signedVolume(props[0].mesh), 1.0, 1e-5);
  EXPECT_NEAR(signedVolume(props[1].mesh), 1.0, 1e-5);
  EXPECT_NEAR(bounds(props[0].mesh).min.x - bounds(props[1].mesh).min.x, 2.0f, 1e-5f);
}

TEST(Props, TransformedMovesPositionsAndTurnsNormals) {
  const Mesh box = boxMesh({1, 1, 1});
  const Rigid pose{glm::angleAxis(float(kPi / 2), glm::vec3(0, 0, 1)), {0, 5, 0}};
  const Mesh moved = transformed(box, pose);
  EXPECT_NEAR(signedVolume(moved), 1.0, 1e-5);
  EXPECT_NEAR(bounds(moved).min.y, 4.5f, 1e-5f);
  for (size_t v = 0; v < box.vertexCount(); ++v) {
    const glm::vec3 n = moved.normal(v) - pose.rotation * box.normal(v);
    EXPECT_NEAR(glm::length(n), 0.0f, 1e-6f);
  }
}

}  // namespace
}  // namespace imps

namespace imps {
namespace {

// A unit cube as an IndexedFaceSet (8 points, 6 quads, ccw seen from outside) with `extra` fields.
std::string cube(const std::string& extra) {
  return kHeader + "Shape { geometry IndexedFaceSet {\n"
                   "  coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0, 0 0 1, 1 0 1, 1 1 1, 0 1 1 ] }\n"
                   "  coordIndex [ 0 3 2 1 -1, 4 5 6 7 -1, 0 1 5 4 -1, 2 3 7 6 -1, 0 4 7 3 -1, 1 2 6 5 -1 ]\n" +
         extra + "\n} }\n";
}

TEST(Props, ColorNodesColourFacesOrCorners) {
  // Per face, by colorIndex: faces 0-5 take colours 1 0 1 0 1 0.
  const auto perFace = propsOf(cube("color Color { color [ 1 0 0, 0 0 1 ] } colorPerVertex FALSE "
                                    "colorIndex [ 1 0 1 0 1 0 ]"));
  ASSERT_EQ(perFace.size(), 1u);
  const Mesh& f = perFace[0].mesh;
  ASSERT_EQ(f.triangleCount(), 12u);
  for (size_t t = 0; t < 12; ++t) {
    const glm::vec3 expected = (t / 2) % 2 == 0 ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
    for (size_t c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(f.colors[3 * (3 * t + c) + size_t(k)], expected[k]) << t;
  }
  // Per vertex, through coordIndex: point i's colour is colour i, wherever the point is a corner.
  std::string eight = "color Color { color [ ";
  for (int i = 0; i < 8; ++i) eight += std::to_string(i / 8.0) + " 0 0, ";
  const auto perVertex = propsOf(cube(eight + "] }"));
  const Mesh& v = perVertex[0].mesh;
  for (size_t i = 0; i < v.vertexCount(); ++i) {
    const glm::vec3 p = v.position(i);
    const float expected = float(int(p.x) + 2 * int(p.y) + 4 * int(p.z));  // which of the 8 points, by layout
    const int which[8] = {0, 1, 3, 2, 4, 5, 7, 6};  // point index of (x, y, z) bits
    EXPECT_NEAR(v.colors[3 * i], float(which[int(expected)]) / 8.0f, 1e-6f) << i;
  }
  // Without a Color node the Material's colour stays.
  EXPECT_EQ(propsOf(cube(""))[0].mesh.colors[0], 0.8f);
}

TEST(Props, CreaseAngleSmoothsAndNormalNodesAreUsed) {
  // creaseAngle 0 (default): every corner has its face's normal, which faces outwards.
  const Mesh flat = propsOf(cube(""))[0].mesh;
  for (size_t i = 0; i < flat.vertexCount(); ++i) {
    const glm::vec3 n = flat.normal(i), p = flat.position(i);
    EXPECT_NEAR(std::abs(n.x) + std::abs(n.y) + std::abs(n.z), 1.0f, 1e-5f);
    EXPECT_GT(glm::dot(n, p - glm::vec3(0.5f)), 0.0f);
  }
  // Above 90 degrees the cube's faces are smoothed: each corner's normal is its point's diagonal.
  const Mesh smooth = propsOf(cube("creaseAngle 1.6"))[0].mesh;
  for (size_t i = 0; i < smooth.vertexCount(); ++i) {
    const glm::vec3 expected = glm::normalize(smooth.position(i) - glm::vec3(0.5f));
    EXPECT_NEAR(glm::dot(smooth.normal(i), expected), 1.0f, 1e-5f) << i;
  }
  // Just below 90 degrees nothing is smoothed.
  const Mesh crease = propsOf(cube("creaseAngle 1.5"))[0].mesh;
  for (size_t i = 0; i < crease.vertexCount(); ++i) EXPECT_EQ(crease.normal(i), flat.normal(i));
  // A Normal node per face wins over the faces' own.
  const Mesh given = propsOf(cube("normal Normal { vector [ 0 1 0 ] } normalPerVertex FALSE "
                                  "normalIndex [ 0 0 0 0 0 0 ]"))[0].mesh;
  for (size_t i = 0; i < given.vertexCount(); ++i) EXPECT_EQ(given.normal(i), glm::vec3(0, 1, 0));
}

}  // namespace
}  // namespace imps
