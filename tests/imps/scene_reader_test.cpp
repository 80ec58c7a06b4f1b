// SPDX-License-Identifier: MIT
// Tests for readScene / readSceneFile (imps/src/scene_reader.cpp): figure A-1, every node and field, syntax and file
// errors end to end with their exact text. The semantic checks are the SceneBuilder's (scene_builder_test.cpp).
#include "imps/scene_reader.h"
#include "scene_parser.h"  // kMaxFieldItems

#include <gtest/gtest.h>

#include <string>

namespace imps {
namespace {

std::string scenePath(const std::string& name) { return std::string(IMPS_SOURCE_DIR) + "/tests/data/scenes/" + name; }

const std::string kHeader = "#VRML V2.0 utf8\n";

// Every diagnostic of a read that must fail, one per line.
std::string errorsOf(const std::string& text) {
  auto result = readScene(text, "t.wrl");
  EXPECT_FALSE(result.has_value()) << "expected errors for:\n" << text;
  return result.has_value() ? std::string() : result.error().str();
}

// The scene of a read that must succeed; its warnings go to `warnings`.
Scene sceneOf(const std::string& text, Diagnostics* warnings = nullptr) {
  auto result = readScene(text, "t.wrl", warnings);
  EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().str());
  return result.has_value() ? *result : Scene{};
}

TEST(SceneReader, FigureA1LoadsWithTheFiguresValues) {
  Diagnostics warnings;
  auto result = readSceneFile(scenePath("figure_a1.wrl"), &warnings);
  ASSERT_TRUE(result.has_value()) << result.error().str();
  EXPECT_TRUE(warnings.all().empty()) << warnings.str();
  const Scene& scene = *result;
  ASSERT_TRUE(std::holds_alternative<Tesselator3MPNode>(scene.polygonizer));
  const auto& t = std::get<Tesselator3MPNode>(scene.polygonizer);
  EXPECT_EQ(t.deltaT, 0.045f);
  EXPECT_EQ(t.desiredRadius, 0.3f);
  EXPECT_EQ(t.queryRadius, 0.8f);
  EXPECT_EQ(t.energyCoeff, 10.0f);
  EXPECT_EQ(t.surfaceCoeff, 30.0f);
  EXPECT_EQ(t.fissioningFrac, 0.5f);
  EXPECT_EQ(t.isoValue, 1.0f);
  EXPECT_TRUE(t.useSimpleRadii);
  EXPECT_EQ(t.numThreads, 3);
  EXPECT_EQ(t.updatesPerRender, 3);
  EXPECT_EQ(t.colorWidth, 3.0f);
  EXPECT_TRUE(t.doDifferentialTransforms);
  EXPECT_EQ(t.seed, 1);  // not in the figure: the default
  ASSERT_TRUE(t.blendingFunction.has_value());
  EXPECT_EQ(t.blendingFunction->kind, BlendKind::Exponential);
  EXPECT_EQ(t.blendingFunction->variance, 2.0f);
  EXPECT_TRUE(t.blendingFunction->children.empty());
  EXPECT_EQ(t.spatialSubdivision.cubeSize, 0.6f);
  EXPECT_EQ(t.spatialSubdivision.bitsPerDim, 3);

  ASSERT_TRUE(t.sceneGraph.has_value());
  const auto& root = std::get<TransformNode>(*t.sceneGraph);
  EXPECT_EQ(root.translation, glm::vec3(0.0f));
  EXPECT_EQ(root.loc.line, 23);
  EXPECT_EQ(root.loc.column, 16);
  ASSERT_EQ(root.children.size(), 2u);
  const auto& ball1 = std::get<ShapeNode>(root.children[0]);
  EXPECT_EQ(ball1.kind, ShapeKind::Metaball);
  EXPECT_EQ(ball1.radius, 1.0f);
  EXPECT_EQ(ball1.center, glm::vec3(0.0f));
  EXPECT_FALSE(ball1.blendParam.has_value());
  ASSERT_TRUE(ball1.material.has_value());
  EXPECT_EQ(ball1.material->diffuseColor, glm::vec3(0.29f, 0.41f, 0.44f));
  const auto& child = std::get<TransformNode>(root.children[1]);
  EXPECT_EQ(child.translation, glm::vec3(2.0f, 2.0f, 0.0f));
  ASSERT_EQ(child.children.size(), 1u);
  const auto& ball2 = std::get<ShapeNode>(child.children[0]);
  ASSERT_TRUE(ball2.material.has_value());
  EXPECT_EQ(ball2.material->diffuseColor, glm::vec3(0.8f, 0.2f, 0.2f));
  EXPECT_EQ(scene.sceneGraph(), &*t.sceneGraph);
  EXPECT_EQ(scene.fileName, scenePath("figure_a1.wrl"));
}

TEST(SceneReader, EveryNodeAndFieldType) {
  auto result = readSceneFile(scenePath("hierarchical_blanc_schlick.wrl"));
  ASSERT_TRUE(result.has_value()) << result.error().str();
  const auto& t = std::get<Tesselator3MPNode>(result->polygonizer);
  EXPECT_EQ(t.deltaT, 0.03f);
  EXPECT_EQ(t.desiredRadius, 0.25f);
  EXPECT_EQ(t.queryRadius, 0.7f);
  EXPECT_EQ(t.energyCoeff, 12.0f);
  EXPECT_EQ(t.surfaceCoeff, 25.5f);
  EXPECT_EQ(t.fissioningFrac, 0.4f);
  EXPECT_EQ(t.isoValue, 0.9f);
  EXPECT_FALSE(t.useSimpleRadii);
  EXPECT_EQ(t.numThreads, 0);
  EXPECT_EQ(t.updatesPerRender, 2);
  EXPECT_EQ(t.colorWidth, 2.5f);
  EXPECT_FALSE(t.doDifferentialTransforms);
  EXPECT_EQ(t.seed, 42);
  EXPECT_EQ(t.blendingFunction->kind, BlendKind::BlancSchlick);
  EXPECT_EQ(t.blendingFunction->hardness, 2.0f);
  EXPECT_EQ(t.spatialSubdivision, (UniformHash{0.5f, 4}));

  const auto& pelvis = std::get<TransformNode>(*t.sceneGraph);
  EXPECT_EQ(pelvis.name, "Pelvis");
  EXPECT_EQ(pelvis.translation, glm::vec3(0, 1, 0));
  EXPECT_EQ(pelvis.rotation, (Rotation{{1, 0, 0}, 0.25f}));
  ASSERT_EQ(pelvis.children.size(), 4u);
  const auto& hips = std::get<ShapeNode>(pelvis.children[0]);
  EXPECT_EQ(hips.kind, ShapeKind::Ellipsoid);
  EXPECT_EQ(hips.name, "Hips");
  EXPECT_EQ(hips.orientation, (Rotation{{0, 0, 1}, 1.5707964f}));
  EXPECT_EQ(hips.radii, glm::vec3(0.3f, 0.2f, 0.25f));
  EXPECT_EQ(hips.blendParam, 1.5f);
  const Material& m = *hips.material;
  EXPECT_EQ(m.diffuseColor, glm::vec3(0.2f, 0.3f, 0.9f));
  EXPECT_EQ(m.emissiveColor, glm::vec3(0.1f, 0, 0));
  EXPECT_EQ(m.specularColor, glm::vec3(1, 1, 1));
  EXPECT_EQ(m.ambientIntensity, 0.4f);
  EXPECT_EQ(m.shininess, 0.9f);
  EXPECT_EQ(m.transparency, 0.25f);

  const auto& leftHip = std::get<TransformNode>(pelvis.children[1]);
  const auto& thigh = std::get<ShapeNode>(leftHip.children[0]);
  EXPECT_EQ(thigh.kind, ShapeKind::LineSeg);
  EXPECT_EQ(thigh.point1, glm::vec3(0));
  EXPECT_EQ(thigh.point2, glm::vec3(0, -0.45f, 0));
  EXPECT_EQ(thigh.radius1, 0.12f);
  EXPECT_EQ(thigh.radius2, 0.09f);
  EXPECT_EQ(thigh.blendParam, 3.0f);

  // USE copies the DEF'd node: same fields, no name of its own, useOf = the name, located at the USE.
  const auto& rightHip = std::get<TransformNode>(pelvis.children[2]);
  const auto& thighCopy = std::get<ShapeNode>(rightHip.children[0]);
  EXPECT_EQ(thighCopy.useOf, "Thigh");
  EXPECT_EQ(thighCopy.name, "");
  EXPECT_EQ(thighCopy.point2, thigh.point2);
  EXPECT_EQ(thighCopy.loc.line, 55);
  EXPECT_EQ(thighCopy.loc.column, 11);
  const auto& leftHipCopy = std::get<TransformNode>(pelvis.children[3]);
  EXPECT_EQ(leftHipCopy.useOf, "LeftHip");
  EXPECT_EQ(leftHipCopy.children, leftHip.children);

  ASSERT_EQ(result->blendGroups.size(), 2u);
  EXPECT_EQ(result->blendGroups[0].members, (std::vector<std::string>{"LeftHip", "RightHip"}));
  EXPECT_FALSE(result->blendGroups[0].blend);
  EXPECT_EQ(result->blendGroups[1].members, (std::vector<std::string>{"Hips"}));
  EXPECT_TRUE(result->blendGroups[1].blend);
}

TEST(SceneReader, MarchingCubesAndNestedBlends) {
  auto result = readSceneFile(scenePath("marching_cubes_elliptical.wrl"));
  ASSERT_TRUE(result.has_value()) << result.error().str();
  const auto& mc = std::get<MarchingCubesNode>(result->polygonizer);
  EXPECT_EQ(mc.cellSize, 0.05f);
  EXPECT_EQ(mc.xResolution, 20);
  EXPECT_EQ(mc.yResolution, 40);
  EXPECT_EQ(mc.zResolution, 20);
  EXPECT_EQ(mc.isoValue, 1.0f);
  EXPECT_EQ(mc.numThreads, 2);
  EXPECT_EQ(mc.blendingFunction->kind, BlendKind::Elliptical);
  EXPECT_EQ(mc.blendingFunction->blendRange, 0.25f);
  const auto& root = std::get<TransformNode>(*mc.sceneGraph);
  ASSERT_EQ(root.children.size(), 3u);
  const auto& nested = std::get<BlendNode>(root.children[2]);
  EXPECT_EQ(nested.kind, BlendKind::Exponential);
  EXPECT_EQ(nested.variance, 0.5f);
  EXPECT_EQ(std::get<ShapeNode>(nested.children[0]).blendParam, -1e-3f);
}

TEST(SceneReader, FlatBlendRootAndSingleShapeRoot) {
  auto flat = readSceneFile(scenePath("flat_exponential.wrl"));
  ASSERT_TRUE(flat.has_value()) << flat.error().str();
  EXPECT_TRUE(std::holds_alternative<std::monostate>(flat->polygonizer));
  const auto& body = std::get<BlendNode>(*flat->root);
  EXPECT_EQ(body.name, "Body");
  EXPECT_TRUE(body.fastExp);
  EXPECT_EQ(body.variance, 1.5f);
  ASSERT_EQ(body.children.size(), 3u);
  const auto& torso = std::get<ShapeNode>(body.children[1]);
  EXPECT_EQ(torso.center, glm::vec3(0, 0.9f, 0));  // commas are whitespace
  EXPECT_EQ(torso.material->useOf, "Skin");
  EXPECT_EQ(torso.material->shininess, 0.5f);

  auto single = readSceneFile(scenePath("single_metaball.wrl"));
  ASSERT_TRUE(single.has_value()) << single.error().str();
  const auto& ball = std::get<ShapeNode>(*single->root);
  EXPECT_EQ(ball.center, glm::vec3(0.125f, 0.0f, 3.0f));
  EXPECT_EQ(ball.radius, 2.0f);
}

TEST(SceneReader, SyntaxDetails) {
  // Comments, commas, strings with escapes, a trailing comment on the header, an empty file body.
  EXPECT_TRUE(readScene("#VRML V2.0 utf8 written by hand\n", "t.wrl").has_value());
  EXPECT_TRUE(readScene("\xEF\xBB\xBF#VRML V2.0 utf8\r\nMetaball { radius 2 }\r\n", "t.wrl").has_value());
  const Scene s = sceneOf(kHeader +
                          "DEF A Metaball { radius 1 } # a comment { [ \"\n"
                          "BlendGroup { members [ \"A\", \"A\" ] }\n"
                          "BlendGroup { members [] blend FALSE }\n");
  ASSERT_EQ(s.blendGroups.size(), 2u);
  EXPECT_EQ(s.blendGroups[0].members, (std::vector<std::string>{"A", "A"}));
  EXPECT_TRUE(s.blendGroups[1].members.empty());
  // String escapes \" and \\ (seen through the message about the member).
  EXPECT_EQ(errorsOf(kHeader + "BlendGroup { members [ \"q\\\"uo\\\\te\" ] }"),
            "t.wrl:2:24: error: BlendGroup member 'q\"uo\\te' names no DEF'd shape or RigidTransform\n");
  // Numbers in every spelling:
  const Scene n = sceneOf(kHeader + "LineSeg { point1 +1 -2. .5 point2 1e2 1E-2 -0.5e+1 radius1 3 radius2 1 }");
  const auto& seg = std::get<ShapeNode>(*n.root);
  EXPECT_EQ(seg.point1, glm::vec3(1, -2, 0.5f));
  EXPECT_EQ(seg.point2, glm::vec3(100, 0.01f, -5));
  // NULL leaves a node field at its default.
  const Scene z = sceneOf(kHeader + "Metaball { material NULL }");
  EXPECT_FALSE(std::get<ShapeNode>(*z.root).material.has_value());
  // A field value may be a single node for an MFNode field.
  const Scene c = sceneOf(kHeader + "RigidTransform { children Metaball { } }");
  EXPECT_EQ(std::get<TransformNode>(*c.root).children.size(), 1u);
}

// ---- Errors: each yields exactly this message at this line:column. ----

TEST(SceneReaderErrors, Header) {
  EXPECT_EQ(errorsOf("Metaball { }\n"), "t.wrl:1:1: error: missing header: the first line must be '#VRML V2.0 utf8'\n");
  EXPECT_EQ(errorsOf(""), "t.wrl:1:1: error: missing header: the first line must be '#VRML V2.0 utf8'\n");
  EXPECT_EQ(errorsOf("#VRML V1.0 ascii\n"),
            "t.wrl:1:1: error: unsupported header '#VRML V1.0 ascii'; the first line must be '#VRML V2.0 utf8'\n");
  EXPECT_EQ(errorsOf("#VRML V2.0 utf8x\n"),
            "t.wrl:1:1: error: unsupported header '#VRML V2.0 utf8x'; the first line must be '#VRML V2.0 utf8'\n");
  EXPECT_EQ(errorsOf("\n#VRML V2.0 utf8\n"),
            "t.wrl:1:1: error: missing header: the first line must be '#VRML V2.0 utf8' (it is on line 2; nothing "
            "may come before it)\n");
}

TEST(SceneReaderErrors, Brackets) {
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform {\n  children [\n    Metaball { radius 1 }\n"),
            "t.wrl:5:1: error: unexpected end of file: the '[' at 3:12 is never closed\n");
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform {\n  children [\n    Metaball { radius 1 }\n}\n"),
            "t.wrl:5:1: error: expected ']' to close the '[' at 3:12, found '}'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1 }\n}\n"),
            "t.wrl:3:1: error: unexpected '}' at top level: nothing is open here\n");
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ Metaball { } ] ] }"),
            "t.wrl:2:44: error: expected a field name or '}' in RigidTransform, found ']'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball radius 1 }"),
            "t.wrl:2:1: error: expected a node at top level, found 'Metaball'\n");
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ 1 Metaball { } ] }"),
            "t.wrl:2:31: error: a list holds either values or nodes, not both\n");
}

// A 40 MB scene of one long list took 1.7 GB in `check`: a field keeps at most vrml::kMaxFieldItems values. The
// list is read past (one error at the first value too many), so the rest of the file is still checked.
TEST(SceneReaderErrors, OverlongListIsBoundedAndReadPast) {
  std::string list;
  list.reserve(2 * (vrml::kMaxFieldItems + 2));
  for (size_t i = 0; i < vrml::kMaxFieldItems + 2; ++i) list += "1 ";
  const std::string text = kHeader + "Metaball { center [ " + list + "] radius -1 }\n";
  const std::string column = std::to_string(std::string("Metaball { center [ ").size() + 2 * vrml::kMaxFieldItems + 1);
  const std::string errors = errorsOf(text);
  EXPECT_EQ(errors.substr(0, errors.find('\n') + 1),
            "t.wrl:2:" + column + ": error: a value of more than " + std::to_string(vrml::kMaxFieldItems) +
                " items; the format's limit per field (docs/scene-format.md)\n");
  EXPECT_NE(errors.find("radius"), std::string::npos) << "the field after the list was not checked: " << errors;
}

TEST(SceneReaderErrors, FileEndsMidNode) {
  auto result = readSceneFile(scenePath("bad_unclosed.wrl"));
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().str(), scenePath("bad_unclosed.wrl") +
                                      ":6:1: error: unexpected end of file inside Metaball: the '{' at 4:14 is "
                                      "never closed\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball {"),
            "t.wrl:2:11: error: unexpected end of file inside Metaball: the '{' at 2:10 is never closed\n");
  EXPECT_EQ(errorsOf(kHeader + "DEF"), "t.wrl:2:4: error: expected a name after DEF, found end of file\n");
  EXPECT_EQ(errorsOf(kHeader + "BlendGroup { members \"A"),
            "t.wrl:2:22: error: unterminated string (it starts here)\n");
}

TEST(SceneReaderErrors, BadNumbers) {
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1.2.3 }"), "t.wrl:2:19: error: malformed number '1.2.3'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1e }"), "t.wrl:2:19: error: malformed number '1e'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius - }"), "t.wrl:2:19: error: malformed number '-'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius nan }"), "t.wrl:2:19: error: 'nan' is not a finite number\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { center 0 -inf 0 }"), "t.wrl:2:21: error: '-inf' is not a finite number\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { center 0 INF 0 }"), "t.wrl:2:21: error: 'INF' is not a finite number\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1e999 }"), "t.wrl:2:19: error: number '1e999' is out of range\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1e39 }"),
            "t.wrl:2:19: error: number '1e39' for field 'radius' of Metaball is out of range for a 32-bit float\n");
  // A bad number does not stop the read: later errors are still found.
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1..2 center 0 0 }"),
            "t.wrl:2:19: error: malformed number '1..2'\n"
            "t.wrl:2:31: error: expected 3 numbers for field 'center' of Metaball, found 2 numbers\n");
}

TEST(SceneReaderErrors, BinaryGarbageAndBadUtf8) {
  auto result = readSceneFile(scenePath("bad_binary.wrl"));
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().str(), scenePath("bad_binary.wrl") +
                                      ":3:1: error: unexpected control character 0x00; a scene file must be text\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1 }\xff"),
            "t.wrl:2:22: error: invalid UTF-8 (byte 0xFF); a scene file must be UTF-8 text\n");
  EXPECT_EQ(errorsOf(kHeader + "# caf\xc3\xa9 \xc0\xaf\n"),
            "t.wrl:2:8: error: invalid UTF-8 (byte 0xC0); a scene file must be UTF-8 text\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { r\xc3\xa9sum\xc3\xa9 1 }"),
            "t.wrl:2:13: error: unexpected character '\xc3\xa9'\n");
  // Valid UTF-8 in strings and comments is fine; columns count characters.
  EXPECT_EQ(errorsOf(kHeader + "BlendGroup { members \"\xc3\xa9\xc3\xa9\" blend 2 }"),
            "t.wrl:2:33: error: expected TRUE or FALSE for field 'blend' of BlendGroup, found '2'\n"
            "t.wrl:2:22: error: BlendGroup member '\xc3\xa9\xc3\xa9' names no DEF'd shape or RigidTransform\n");
}

TEST(SceneReaderErrors, NestingDeeperThan200) {
  std::string ok = kHeader, tooDeep = kHeader;
  for (int i = 0; i < 199; ++i) ok += "RigidTransform { children ";
  ok += "Metaball { }";
  for (int i = 0; i < 199; ++i) ok += "}";
  EXPECT_TRUE(readScene(ok, "t.wrl").has_value());
  EXPECT_EQ(errorsOf("#VRML V2.0 utf8\nRigidTransform { children " + ok.substr(kHeader.size()) + "}"),
            "t.wrl:2:5201: error: nodes nested deeper than 200 levels\n");
  for (int i = 0; i < 100000; ++i) tooDeep += "RigidTransform { children ";
  EXPECT_EQ(errorsOf(tooDeep), "t.wrl:2:5201: error: nodes nested deeper than 200 levels\n");
  // USE cannot be used to get deeper either.
  std::string viaUse = kHeader + "DEF Deep RigidTransform { children ";
  for (int i = 0; i < 150; ++i) viaUse += "RigidTransform { children ";
  for (int i = 0; i < 151; ++i) viaUse += "}";
  viaUse += "\nBlendGroup { }\n";
  std::string wrapped = kHeader + "DEF Deep RigidTransform { children ";
  for (int i = 0; i < 150; ++i) wrapped += "RigidTransform { children ";
  wrapped += "RigidTransform { } ";
  for (int i = 0; i < 151; ++i) wrapped += "}";
  wrapped = kHeader + "Tesselator3MP { sceneGraph RigidTransform { children [ " + wrapped.substr(kHeader.size());
  for (int i = 0; i < 60; ++i) wrapped += " RigidTransform { children";
  wrapped += " USE Deep";
  for (int i = 0; i < 60; ++i) wrapped += " }";
  wrapped += " ] } }";
  const std::string errors = errorsOf(wrapped);
  EXPECT_NE(errors.find("error: USE of 'Deep' here nests nodes deeper than 200 levels"), std::string::npos) << errors;
}

TEST(SceneReaderErrors, SeveralErrorsInOneRunAndTheCap) {
  auto result = readSceneFile(scenePath("bad_errors.wrl"));
  ASSERT_FALSE(result.has_value());
  const std::string f = scenePath("bad_errors.wrl");
  EXPECT_EQ(result.error().str(),
            f + ":3:10: error: field 'deltaT' of Tesselator3MP must be > 0, found -1\n" +
            f + ":4:14: error: expected an integer for field 'numThreads' of Tesselator3MP, found '1.5'\n" +
            f + ":5:48: error: field 'variance' of ExponentialBlend must be > 0, found 0\n" +
            f + ":6:47: error: field 'bitsPerDim' of UniformHash must be between 1 and 10, found 11\n" +
            f + ":9:7: error: unknown node type 'Metabal'; did you mean 'Metaball'?\n" +
            f + ":10:18: error: unknown field 'radus' in Metaball; did you mean 'radius'?\n" +
            f + ":10:33: error: malformed number '1.2.3'\n" +
            f + ":11:7: error: a Material node is not allowed in field 'children' of RigidTransform (it takes a "
                "shape, RigidTransform or blend node)\n" +
            f + ":12:7: error: USE of undefined name 'Nobody'\n");
  std::string many = kHeader + "RigidTransform { children [\n";
  for (int i = 0; i < 80; ++i) many += "Metaball { radius -1 }\n";
  many += "] }";
  auto capped = readScene(many, "t.wrl");
  ASSERT_FALSE(capped.has_value());
  EXPECT_EQ(capped.error().errorCount(), 50);
  EXPECT_EQ(capped.error().all().back().str(), "t.wrl:52:19: note: too many errors; stopping here");
}

TEST(SceneReader, TexGenAndImageTextureOnEveryShape) {
  const Scene scene = sceneOf(kHeader + R"(EllipticalBlend { children [
  Metaball { texGen TexGenSphere { translation 0 1 0 rotation 0 1 0 1.5 } texture ImageTexture { url "skin.png" } }
  Ellipsoid { texGen TexGenPlane { width 0.5 height 0.25 } }
  LineSeg { texture ImageTexture { url [ "dir/tie.jpg" ] } }
] }
)");
  const auto& children = std::get<BlendNode>(*scene.root).children;
  const auto& ball = std::get<ShapeNode>(children[0]);
  ASSERT_TRUE(ball.texGen && ball.texture);
  EXPECT_EQ(ball.texGen->kind, TexGenKind::Sphere);
  EXPECT_EQ(ball.texGen->translation, glm::vec3(0, 1, 0));
  EXPECT_EQ(ball.texGen->rotation, (Rotation{{0, 1, 0}, 1.5f}));
  EXPECT_EQ(ball.texture->url, "skin.png");
  EXPECT_EQ(ball.texture->loc.line, 3);  // the url string
  EXPECT_EQ(ball.texture->loc.column, 102);
  const auto& ellipsoid = std::get<ShapeNode>(children[1]);
  ASSERT_TRUE(ellipsoid.texGen);
  EXPECT_FALSE(ellipsoid.texture);
  EXPECT_EQ(ellipsoid.texGen->kind, TexGenKind::Plane);
  EXPECT_EQ(ellipsoid.texGen->width, 0.5f);
  EXPECT_EQ(ellipsoid.texGen->height, 0.25f);
  const auto& line = std::get<ShapeNode>(children[2]);
  EXPECT_FALSE(line.texGen);
  ASSERT_TRUE(line.texture);
  EXPECT_EQ(line.texture->url, "dir/tie.jpg");
  // Defaults.
  const TexGenNode plane = std::get<ShapeNode>(std::get<BlendNode>(*sceneOf(kHeader +
      "ExponentialBlend { children [ Metaball { texGen TexGenPlane { } } ] }").root).children[0]).texGen.value();
  EXPECT_EQ(plane.translation, glm::vec3(0));
  EXPECT_EQ(plane.rotation, Rotation{});
  EXPECT_EQ(plane.width, 2.0f);
  EXPECT_EQ(plane.height, 2.0f);
}

TEST(SceneReaderErrors, UnreadableFile) {
  auto missing = readSceneFile("/nonexistent/scene.wrl");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().str(),
            "/nonexistent/scene.wrl: error: cannot read scene file: No such file or directory\n");
  auto directory = readSceneFile(std::string(IMPS_SOURCE_DIR) + "/tests/data/scenes");
  ASSERT_FALSE(directory.has_value());
  EXPECT_EQ(directory.error().str(), std::string(IMPS_SOURCE_DIR) +
                                         "/tests/data/scenes: error: cannot read scene file: Is a directory\n");
}

}  // namespace
}  // namespace imps
