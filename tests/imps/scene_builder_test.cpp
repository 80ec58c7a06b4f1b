// SPDX-License-Identifier: MIT
// The SceneBuilder (imps/src/scene_builder.h): the ParserTarget that checks what the parser reports against the IMPS
// node types (docs/scene-format.md) and fills a Scene. Driven by hand (it needs no parser) and by the parser, with the
// exact text of every semantic error: unknown types and fields, value types, ranges, blend parameters against the
// blend in force, fields given twice, DEF/USE, where nodes may go, roots, BlendGroup members, the node limits and
// texturing. Syntax errors are the parser's (scene_parser_test.cpp); reading files is readScene's
// (scene_reader_test.cpp).
#include "scene_builder.h"

#include <gtest/gtest.h>

#include <expected>
#include <string>

namespace imps {
namespace {

using vrml::SceneBuilder;

const std::string kHeader = "#VRML V2.0 utf8\n";

// The parser driving a SceneBuilder, then finish(): the whole of a read without readScene. Warnings (not errors) are
// copied to `warnings`.
std::expected<Scene, Diagnostics> build(std::string_view text, const std::string& fileName,
                                        Diagnostics* warnings = nullptr) {
  Diagnostics diagnostics;
  vrml::DiagnosticSink sink(diagnostics);
  SceneBuilder builder(fileName, sink);
  Scene scene = builder.finish(vrml::parse(text, fileName, builder, sink));
  for (const Diagnostic& d : diagnostics.all())
    if (warnings != nullptr && d.severity == Severity::Warning) warnings->warning(d.loc, d.message);
  if (diagnostics.hasErrors()) return std::unexpected(std::move(diagnostics));
  return scene;
}

// Every diagnostic of a build that must fail, one per line.
std::string errorsOf(const std::string& text) {
  auto result = build(text, "t.wrl");
  EXPECT_FALSE(result.has_value()) << "expected errors for:\n" << text;
  return result.has_value() ? std::string() : result.error().str();
}

// The scene of a build that must succeed; its warnings go to `warnings`.
Scene sceneOf(const std::string& text, Diagnostics* warnings = nullptr) {
  auto result = build(text, "t.wrl", warnings);
  EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().str());
  return result.has_value() ? *result : Scene{};
}

vrml::FieldValue numbers(std::initializer_list<const char*> spellings) {
  vrml::FieldValue v;
  for (const char* s : spellings) v.items.push_back({vrml::TokenKind::Number, s, 1, 1});
  v.loc = {"t.wrl", 1, 1};
  return v;
}

vrml::NodeHeader header(const std::string& type, const std::string& def = "") {
  vrml::NodeHeader h;
  h.type = type;
  h.typeLoc = h.defLoc = {"t.wrl", 1, 1};
  h.defName = def;
  return h;
}

// ---- Driven by hand: the builder is a ParserTarget like any other. ----

TEST(SceneBuilder, BuildsFromTargetCallsAlone) {
  Diagnostics d;
  vrml::DiagnosticSink sink(d);
  SceneBuilder b("t.wrl", sink);
  const SourceLoc loc{"t.wrl", 1, 1};
  b.beginNode(header("RigidTransform", "J"));
  b.field("translation", loc, numbers({"1", "2", "3"}));
  b.beginNodeField("children", loc, true);
  b.beginNode(header("Metaball", "A"));
  b.field("radius", loc, numbers({"0.5"}));
  b.endNode(loc);
  b.use("A", loc);
  b.endNodeField();
  b.endNode(loc);
  const Scene scene = b.finish(true);
  EXPECT_FALSE(d.hasErrors()) << d.str();
  ASSERT_TRUE(scene.root.has_value());
  const auto& joint = std::get<TransformNode>(*scene.root);
  EXPECT_EQ(joint.name, "J");
  EXPECT_EQ(joint.translation, glm::vec3(1, 2, 3));
  ASSERT_EQ(joint.children.size(), 2u);
  const auto& ball = std::get<ShapeNode>(joint.children[0]);
  EXPECT_EQ(ball.name, "A");
  EXPECT_EQ(ball.radius, 0.5f);
  const auto& copy = std::get<ShapeNode>(joint.children[1]);
  EXPECT_EQ(copy.useOf, "A") << "a USE copies the DEF'd node and remembers the name";
  EXPECT_EQ(copy.radius, 0.5f);
}

TEST(SceneBuilder, WholeFileChecksRunOnlyWhenTheParseReachedTheEnd) {
  // A BlendGroup naming no DEF is found by finish(true); after a parse that stopped early the file is incomplete
  // (the DEF may have been further on), so finish(false) does not report it.
  for (bool parsedToEnd : {true, false}) {
    Diagnostics d;
    vrml::DiagnosticSink sink(d);
    SceneBuilder b("t.wrl", sink);
    const SourceLoc loc{"t.wrl", 1, 1};
    b.beginNode(header("BlendGroup"));
    vrml::FieldValue members;
    members.items.push_back({vrml::TokenKind::String, "Nobody", 1, 1});
    members.loc = loc;
    b.field("members", loc, members);
    b.endNode(loc);
    b.finish(parsedToEnd);
    EXPECT_EQ(d.hasErrors(), parsedToEnd) << d.str();
  }
}

// ---- Driven by the parser: every semantic error, exactly. ----

TEST(SceneBuilder, UnknownNodeTypeAndField) {
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ Metabal { radius 1 } ] }"),
            "t.wrl:2:29: error: unknown node type 'Metabal'; did you mean 'Metaball'?\n");
  EXPECT_EQ(errorsOf(kHeader + "Frobnicator { }"), "t.wrl:2:1: error: unknown node type 'Frobnicator'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball {\n  radus 1\n}"),
            "t.wrl:3:3: error: unknown field 'radus' in Metaball; did you mean 'radius'?\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { colour 1 }"),
            "t.wrl:2:12: error: unknown field 'colour' in Metaball (its fields are: center, radius, blendParam, "
            "material, texGen, texture)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { materal Material { } }"),
            "t.wrl:2:12: error: unknown field 'materal' in Metaball; did you mean 'material'?\n");
}

TEST(SceneBuilder, WrongValueType) {
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius \"big\" }"),
            "t.wrl:2:19: error: expected a number for field 'radius' of Metaball, found a string\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius TRUE }"),
            "t.wrl:2:19: error: expected a number for field 'radius' of Metaball, found 'TRUE'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius 1 2 }"),
            "t.wrl:2:19: error: expected a number for field 'radius' of Metaball, found 2 numbers\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius [ 1 ] }"),
            "t.wrl:2:21: error: expected a number for field 'radius' of Metaball, found a list\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius Material { } }"),
            "t.wrl:2:12: error: expected a number for field 'radius' of Metaball, found a node\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { center 1 2 }"),
            "t.wrl:2:19: error: expected 3 numbers for field 'center' of Metaball, found 2 numbers\n");
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { rotation 0 1 0 }"),
            "t.wrl:2:27: error: expected 4 numbers (axis x y z, angle in radians) for field 'rotation' of "
            "RigidTransform, found 3 numbers\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { material 3 }"),
            "t.wrl:2:21: error: expected a node for field 'material' of Metaball, found '3'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { material [ Material { } ] }"),
            "t.wrl:2:12: error: field 'material' of Metaball holds one node, not a list\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { numThreads 1.5 }"),
            "t.wrl:2:28: error: expected an integer for field 'numThreads' of Tesselator3MP, found '1.5'\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { seed 3000000000 }"),
            "t.wrl:2:22: error: integer '3000000000' for field 'seed' of Tesselator3MP is out of range\n");
  EXPECT_EQ(errorsOf(kHeader + "ExponentialBlend { fastExp 1 }"),
            "t.wrl:2:28: error: expected TRUE or FALSE for field 'fastExp' of ExponentialBlend, found '1'\n");
  EXPECT_EQ(errorsOf(kHeader + "BlendGroup { members [ 1 ] }"),
            "t.wrl:2:24: error: expected a string or a list of strings for field 'members' of BlendGroup, found "
            "'1'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius }"),
            "t.wrl:2:19: error: expected a value for field 'radius', found '}'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { radius center 1 2 3 }"),
            "t.wrl:2:19: error: expected a value for field 'radius', found 'center'\n");
}

TEST(SceneBuilder, NonPositiveAndOutOfRangeValues) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"Metaball { radius 0 }", "field 'radius' of Metaball must be > 0, found 0"},
      {"Ellipsoid { radii 1 -1 1 }", "field 'radii' of Ellipsoid must be > 0 in every component, found 1 -1 1"},
      {"LineSeg { radius1 -0.5 }", "field 'radius1' of LineSeg must be > 0, found -0.5"},
      {"LineSeg { radius2 0 }", "field 'radius2' of LineSeg must be > 0, found 0"},
      {"MarchingCubes { cellSize 0 }", "field 'cellSize' of MarchingCubes must be > 0, found 0"},
      {"MarchingCubes { xResolution -1 }",
       "field 'xResolution' of MarchingCubes must be between 0 and 4096 cells (0: unset), found -1"},
      {"MarchingCubes { zResolution 2147483647 }",
       "field 'zResolution' of MarchingCubes must be between 0 and 4096 cells (0: unset), found 2147483647"},
      {"MarchingCubes { numThreads -2 }",
       "field 'numThreads' of MarchingCubes must be between 0 and 1024 (0: all cores), found -2"},
      {"MarchingCubes { numThreads 1025 }",
       "field 'numThreads' of MarchingCubes must be between 0 and 1024 (0: all cores), found 1025"},
      {"ExponentialBlend { variance -2 }", "field 'variance' of ExponentialBlend must be > 0, found -2"},
      {"BlancSchlickBlend { hardness 0 }", "field 'hardness' of BlancSchlickBlend must be > 0, found 0"},
      {"EllipticalBlend { blendRange -0 }", "field 'blendRange' of EllipticalBlend must be > 0, found -0"},
      {"Tesselator3MP { spatialSubdivision UniformHash { cubeSize 0 } }",
       "field 'cubeSize' of UniformHash must be > 0, found 0"},
      {"Tesselator3MP { spatialSubdivision UniformHash { bitsPerDim 0 } }",
       "field 'bitsPerDim' of UniformHash must be between 1 and 10, found 0"},
      {"Tesselator3MP { spatialSubdivision UniformHash { bitsPerDim 11 } }",
       "field 'bitsPerDim' of UniformHash must be between 1 and 10, found 11"},
      {"Tesselator3MP { desiredRadius 0 }", "field 'desiredRadius' of Tesselator3MP must be > 0, found 0"},
      {"Tesselator3MP { deltaT -0.01 }", "field 'deltaT' of Tesselator3MP must be > 0, found -0.01"},
      // F >= 0 everywhere: an iso-value of 0 or below would make all of space inside.
      {"Tesselator3MP { isoValue 0 }", "field 'isoValue' of Tesselator3MP must be > 0, found 0"},
      {"MarchingCubes { isoValue -1 }", "field 'isoValue' of MarchingCubes must be > 0, found -1"},
      {"Tesselator3MP { numThreads -1 }",
       "field 'numThreads' of Tesselator3MP must be between 0 and 1024 (0: all cores), found -1"},
      // Once a segfault inside oneTBB (an arena of two billion threads).
      {"Tesselator3MP { numThreads 2147483647 }",
       "field 'numThreads' of Tesselator3MP must be between 0 and 1024 (0: all cores), found 2147483647"},
      {"Tesselator3MP { updatesPerRender 0 }", "field 'updatesPerRender' of Tesselator3MP must be >= 1, found 0"},
      {"Metaball { material Material { diffuseColor 1.5 0 0 } }",
       "field 'diffuseColor' of Material must be between 0 and 1 in every component, found 1.5 0 0"},
      {"Metaball { material Material { transparency -1 } }",
       "field 'transparency' of Material must be between 0 and 1, found -1"},
      {"RigidTransform { rotation 0 0 0 1 }",
       "field 'rotation' of RigidTransform has a zero axis with a non-zero angle"},
  };
  for (const auto& [body, message] : cases) {
    const std::string errors = errorsOf(kHeader + body);
    EXPECT_NE(errors.find("t.wrl:2:"), std::string::npos) << errors;
    EXPECT_EQ(errors.substr(errors.find("error: ") + 7), message + "\n") << body;
  }
  // Exact positions for a few.
  EXPECT_EQ(errorsOf(kHeader + "Metaball {\n  radius -1\n}"),
            "t.wrl:3:10: error: field 'radius' of Metaball must be > 0, found -1\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { spatialSubdivision UniformHash { bitsPerDim 11 } }"),
            "t.wrl:2:61: error: field 'bitsPerDim' of UniformHash must be between 1 and 10, found 11\n");
}

TEST(SceneBuilder, BlendParameterAgainstTheBlendInForce) {
  // No polygonizer and no blend node: ExponentialBlend is in force, blobbiness must be negative.
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children Metaball { blendParam 0 } }"),
            "t.wrl:2:27: error: blendParam 0 of Metaball must be negative under ExponentialBlend (it is the "
            "blobbiness B)\n");
  // The polygonizer's blendingFunction, even when it comes after the scene graph.
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP {\n"
                               "  sceneGraph RigidTransform { children LineSeg { blendParam -2 } }\n"
                               "  blendingFunction BlancSchlickBlend { }\n"
                               "}"),
            "t.wrl:3:40: error: blendParam -2 of LineSeg must be > 0 under BlancSchlickBlend (it is the hardness)\n");
  EXPECT_EQ(errorsOf(kHeader + "MarchingCubes { blendingFunction EllipticalBlend { }\n"
                               "  sceneGraph Ellipsoid { blendParam -0.5 } }"),
            "t.wrl:3:14: error: blendParam -0.5 of Ellipsoid must be > 0 under EllipticalBlend (it is the blend "
            "range)\n");
  // A flat root blend (or any enclosing blend) is the one in force.
  EXPECT_EQ(errorsOf(kHeader + "ExponentialBlend { children [ Metaball { blendParam 2 } ] }"),
            "t.wrl:2:31: error: blendParam 2 of Metaball must be negative under ExponentialBlend (it is the "
            "blobbiness B)\n");
  sceneOf(kHeader +
          "Tesselator3MP { blendingFunction ExponentialBlend { }\n"
          "  sceneGraph BlancSchlickBlend { children [ Metaball { blendParam 2 } ] } }");
}

TEST(SceneBuilder, FieldGivenTwice) {
  EXPECT_EQ(errorsOf(kHeader + "Metaball {\n  radius 1\n  radius 2\n}"),
            "t.wrl:4:3: error: field 'radius' is given twice in Metaball (first at 3:3)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { material Material { } material Material { } }"),
            "t.wrl:2:34: error: field 'material' is given twice in Metaball (first at 2:12)\n");
}

TEST(SceneBuilder, DefAndUse) {
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ DEF Left Metaball { } USE Lefty ] }"),
            "t.wrl:2:51: error: USE of undefined name 'Lefty'; did you mean 'Left'?\n");
  EXPECT_EQ(errorsOf(kHeader + "DEF Loop RigidTransform { children [ USE Loop ] }"),
            "t.wrl:2:38: error: USE of 'Loop' inside its own definition\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { spatialSubdivision DEF H UniformHash { } }"),
            "t.wrl:2:36: error: DEF is not allowed on a UniformHash node: only shapes, RigidTransforms, blend nodes "
            "and Materials can be named\n");
  EXPECT_EQ(errorsOf(kHeader + "DEF TRUE Metaball { }"), "t.wrl:2:5: error: expected a name after DEF, found 'TRUE'\n");
  // USE of a node whose definition had an error is not reported a second time.
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ DEF A Metabll { } USE A ] }"),
            "t.wrl:2:35: error: unknown node type 'Metabll'; did you mean 'Metaball'?\n");
  // A USE'd node must also fit the field it lands in.
  EXPECT_EQ(errorsOf(kHeader + "Metaball { material DEF M Material { } }\nBlendGroup { }\nRigidTransform { }"),
            "t.wrl:4:1: error: a second scene root 'RigidTransform': the file already has one (the Metaball at 2:1); "
            "a file holds at most one polygonizer or scene graph root\n");
}

TEST(SceneBuilder, DuplicateDefIsAWarningAndTheLaterOneWins) {
  Diagnostics warnings;
  const Scene s = sceneOf(kHeader +
                              "RigidTransform { children [\n"
                              "  DEF A Metaball { radius 1 }\n"
                              "  DEF A Metaball { radius 2 }\n"
                              "  USE A\n"
                              "] }",
                          &warnings);
  EXPECT_EQ(warnings.str(),
            "t.wrl:4:9: warning: 'A' is defined again (first at 3:9); USE refers to the latest "
            "definition\n");
  const auto& children = std::get<TransformNode>(*s.root).children;
  ASSERT_EQ(children.size(), 3u);
  EXPECT_EQ(std::get<ShapeNode>(children[2]).radius, 2.0f);
  // Without the out-parameter the read still succeeds.
  EXPECT_TRUE(build(kHeader + "RigidTransform { children [ DEF A Metaball { } DEF A Metaball { } ] }", "t.wrl"));
}

TEST(SceneBuilder, NodeNotAllowedInField) {
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children [ Material { } ] }"),
            "t.wrl:2:29: error: a Material node is not allowed in field 'children' of RigidTransform (it takes a "
            "shape, RigidTransform or blend node)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { material RigidTransform { } }"),
            "t.wrl:2:21: error: a RigidTransform node is not allowed in field 'material' of Metaball (it takes a "
            "Material)\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { sceneGraph DEF B Metaball { }\n  blendingFunction USE B }"),
            "t.wrl:3:20: error: a Metaball node is not allowed in field 'blendingFunction' of Tesselator3MP (it "
            "takes a blend node (ExponentialBlend, BlancSchlickBlend or EllipticalBlend))\n");
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { blendingFunction ExponentialBlend { children Metaball { } } }"),
            "t.wrl:2:34: error: the blendingFunction of Tesselator3MP must have no children; put the shapes in "
            "sceneGraph\n");
  EXPECT_EQ(errorsOf(kHeader + "Material { }"),
            "t.wrl:2:1: error: a Material node cannot be at top level (a file holds one polygonizer or scene graph "
            "root, plus BlendGroups)\n");
  EXPECT_EQ(errorsOf(kHeader + "RigidTransform { children BlendGroup { } }"),
            "t.wrl:2:27: error: a BlendGroup node is not allowed in field 'children' of RigidTransform (it takes a "
            "shape, RigidTransform or blend node)\n");
  EXPECT_EQ(errorsOf(kHeader + "NULL"), "t.wrl:2:1: error: NULL is only allowed as the value of a node field\n");
}

TEST(SceneBuilder, MoreThanOneRoot) {
  EXPECT_EQ(errorsOf(kHeader + "Tesselator3MP { }\nMetaball { }\n"),
            "t.wrl:3:1: error: a second scene root 'Metaball': the file already has one (the Tesselator3MP at 2:1); "
            "a file holds at most one polygonizer or scene graph root\n");
}

TEST(SceneBuilder, BlendGroupMembers) {
  EXPECT_EQ(errorsOf(kHeader +
                     "RigidTransform { children [ DEF LeftArm LineSeg { } DEF M Metaball { material DEF Red Material "
                     "{ } } ] }\n"
                     "BlendGroup { members [ \"LeftArn\" \"Red\" \"Nobody\" ] }"),
            "t.wrl:3:24: error: BlendGroup member 'LeftArn' names no DEF'd shape or RigidTransform; did you mean "
            "'LeftArm'?\n"
            "t.wrl:3:34: error: BlendGroup member 'Red' is not a shape or RigidTransform\n"
            "t.wrl:3:40: error: BlendGroup member 'Nobody' names no DEF'd shape or RigidTransform\n");
  // Members may be DEF'd after the group.
  sceneOf(kHeader + "BlendGroup { members \"J\" }\nDEF J RigidTransform { }");
}

TEST(SceneBuilder, LineSegWithOneSphereInsideTheOtherWarns) {
  Diagnostics warnings;
  sceneOf(kHeader + "LineSeg { point1 0 0 0 point2 0 1 0 radius1 2 radius2 0.5 }", &warnings);
  EXPECT_EQ(warnings.str(),
            "t.wrl:2:1: warning: one end sphere of this LineSeg contains the other (|radius1 - "
            "radius2| >= |point2 - point1|), so it is just a sphere\n");
  Diagnostics none;
  sceneOf(kHeader + "LineSeg { point1 0 0 0 point2 0 2 0 radius1 2 radius2 0.5 }", &none);
  EXPECT_TRUE(none.all().empty());
  // Warnings come with the errors when the read fails.
  EXPECT_EQ(errorsOf(kHeader + "LineSeg { radius2 5 }\nMetaball { }"),
            "t.wrl:2:1: warning: one end sphere of this LineSeg contains the other (|radius1 - radius2| >= |point2 "
            "- point1|), so it is just a sphere\n"
            "t.wrl:3:1: error: a second scene root 'Metaball': the file already has one (the LineSeg at 2:1); a "
            "file holds at most one polygonizer or scene graph root\n");
}

TEST(SceneBuilder, UseExpansionIsBounded) {
  // Each level doubles the scene: 2^30 nodes if expanded blindly.
  std::string text = kHeader + "RigidTransform { children [ DEF L0 Metaball { }\n";
  for (int i = 1; i <= 30; ++i)
    text += "DEF L" + std::to_string(i) + " RigidTransform { children [ USE L" + std::to_string(i - 1) + " USE L" +
            std::to_string(i - 1) + " ] }\n";
  text += "] }";
  const std::string errors = errorsOf(text);
  const std::string limit = std::to_string(vrml::kMaxExpandedNodes);  // 100000 (a tenth in fuzzing builds)
  EXPECT_NE(errors.find("makes the scene larger than " + limit + " nodes"), std::string::npos) << errors;
}

TEST(SceneBuilder, WrittenNodesAreBoundedToo) {
  // One literal metaball more than the limit with the root: one error at the first one past it, and the rest read
  // past, not stored.
  std::string text = kHeader + "RigidTransform { children [\n";
  for (size_t i = 0; i < vrml::kMaxExpandedNodes; ++i) text += "Metaball { }\n";
  text += "] }";
  const std::string errors = errorsOf(text);
  EXPECT_EQ(errors, "t.wrl:" + std::to_string(vrml::kMaxExpandedNodes + 2) + ":1: error: the scene has more than " +
                        std::to_string(vrml::kMaxExpandedNodes) +
                        " nodes (written or copied by USE); the format's limit\n");
  std::string fits = kHeader + "RigidTransform { children [\n";
  for (size_t i = 0; i + 1 < vrml::kMaxExpandedNodes; ++i) fits += "Metaball { }\n";
  EXPECT_TRUE(build(fits + "] }", "t.wrl").has_value());
}

TEST(SceneBuilder, TexGenAndImageTexture) {
  const std::string f = "t.wrl";
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texGen TexGenPlane { width 0 height -1 } }"),
            f + ":2:39: error: field 'width' of TexGenPlane must be > 0, found 0\n" + f +
                ":2:48: error: field 'height' of TexGenPlane must be > 0, found -1\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texGen TexGenSphere { width 1 } }"),
            f + ":2:34: error: unknown field 'width' in TexGenSphere (its fields are: translation, rotation)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texture ImageTexture { url [ \"a.png\" \"b.png\" ] } }"),
            f + ":2:41: error: field 'url' of ImageTexture must be one non-empty string, found 2 strings\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texture ImageTexture { url \"\" } }"),
            f + ":2:39: error: field 'url' of ImageTexture must be one non-empty string, found an empty string\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texture ImageTexture { url 3 } }"),
            f + ":2:39: error: expected a string or a list of strings for field 'url' of ImageTexture, found '3'\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texture TexGenSphere { } }"),
            f + ":2:20: error: a TexGenSphere node is not allowed in field 'texture' of Metaball (it takes an "
                "ImageTexture)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texGen Material { } }"),
            f + ":2:19: error: a Material node is not allowed in field 'texGen' of Metaball (it takes a "
                "TexGenSphere or TexGenPlane)\n");
  EXPECT_EQ(errorsOf(kHeader + "Metaball { texGen TexGenSphre { } }"),
            f + ":2:19: error: unknown node type 'TexGenSphre'; did you mean 'TexGenSphere'?\n");
  EXPECT_EQ(errorsOf(kHeader + "ImageTexture { url \"a.png\" }"),
            f + ":2:1: error: a ImageTexture node cannot be at top level (a file holds one polygonizer or scene "
                "graph root, plus BlendGroups)\n");
}

}  // namespace
}  // namespace imps
