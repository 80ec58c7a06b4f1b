// SPDX-License-Identifier: MIT
// Tests for readVrml / readVrmlFile: VRML 97 syntax, DEF/USE, ROUTE, PROTO, gzip, the exporters' quirks and errors.
#include "imps/vrml_file.h"

#include <gtest/gtest.h>

#include <string>

#include "imps/file_read.h"
#include "imps/scene_reader.h"

namespace imps {
namespace {

std::string worldPath(const std::string& name) { return std::string(IMPS_SOURCE_DIR) + "/tests/data/worlds/" + name; }

const std::string kHeader = "#VRML V2.0 utf8\n";

std::string errorsOf(const std::string& text) {
  auto result = readVrml(text, "w.wrl");
  EXPECT_FALSE(result.has_value()) << "expected errors for:\n" << text;
  return result.has_value() ? std::string() : result.error().str();
}

VrmlFile fileOf(const std::string& text, Diagnostics* warnings = nullptr) {
  auto result = readVrml(text, "w.wrl", warnings);
  EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().str());
  return result.has_value() ? *result : VrmlFile{};
}

VrmlFile fileAt(const std::string& name, Diagnostics* warnings = nullptr) {
  auto result = readVrmlFile(worldPath(name), warnings);
  EXPECT_TRUE(result.has_value()) << (result.has_value() ? "" : result.error().str());
  return result.has_value() ? *result : VrmlFile{};
}

TEST(VrmlFile, ReadsNodesFieldsAndValues) {
  const VrmlFile file = fileOf(kHeader + "DEF T Transform { translation 1 2.5 -3 children [ Shape { geometry Box { "
                                         "size 1 2 3 } } ] }\nWorldInfo { title \"a \\\"b\\\"\" info [\"x\" \"y\"] }");
  ASSERT_EQ(file.roots.size(), 2u);
  const VrmlNode& t = *file.roots[0];
  EXPECT_EQ(t.type, "Transform");
  EXPECT_EQ(t.defName, "T");
  EXPECT_EQ(t.loc.line, 2);
  EXPECT_EQ(t.loc.column, 7);
  ASSERT_NE(t.field("translation"), nullptr);
  EXPECT_EQ(t.field("translation")->numbers, (std::vector<double>{1, 2.5, -3}));
  ASSERT_NE(t.field("children"), nullptr);
  EXPECT_TRUE(t.field("children")->nodeValued);
  ASSERT_EQ(t.field("children")->nodes.size(), 1u);
  const VrmlNode& box = *t.field("children")->nodes[0]->field("geometry")->nodes.at(0);
  EXPECT_EQ(box.type, "Box");
  EXPECT_EQ(box.field("size")->numbers, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(file.roots[1]->field("title")->strings, std::vector<std::string>{"a \"b\""});
  EXPECT_EQ(file.roots[1]->field("info")->strings, (std::vector<std::string>{"x", "y"}));
  EXPECT_EQ(file.defs.at("T"), file.roots[0]);
}

TEST(VrmlFile, UseIsTheDefdNodeItself) {
  const VrmlFile file = fileOf(kHeader + "DEF G Group { } Transform { children [ USE G USE G ] }");
  const auto& children = file.roots[1]->field("children")->nodes;
  ASSERT_EQ(children.size(), 2u);
  EXPECT_EQ(children[0], file.roots[0]);
  EXPECT_EQ(children[1], file.roots[0]);
}

TEST(VrmlFile, BooleansAreCountedAndReadAsOneAndZero) {
  const VrmlFile file = fileOf(kHeader + "TimeSensor { loop TRUE enabled FALSE }");
  EXPECT_EQ(file.roots[0]->field("loop")->numbers, std::vector<double>{1.0});
  EXPECT_EQ(file.roots[0]->field("loop")->booleans, 1u);
  EXPECT_EQ(file.roots[0]->field("enabled")->numbers, std::vector<double>{0.0});
}

TEST(VrmlFile, RoutesAreSplitAtTheDot) {
  const VrmlFile file = fileOf(kHeader +
                               "DEF T-1 TimeSensor { } DEF I PositionInterpolator { }\n"
                               "ROUTE T-1.fraction_changed TO I.set_fraction");
  ASSERT_EQ(file.routes.size(), 1u);
  EXPECT_EQ(file.routes[0].fromNode, "T-1");
  EXPECT_EQ(file.routes[0].fromField, "fraction_changed");
  EXPECT_EQ(file.routes[0].toNode, "I");
  EXPECT_EQ(file.routes[0].toField, "set_fraction");
  EXPECT_EQ(file.routes[0].loc.line, 3);
}

TEST(VrmlFile, UnknownNodesAreSkippedWithOneWarningPerTypeAndLine) {
  Diagnostics warnings;
  const VrmlFile file = fileOf(kHeader +
                                   "Group { children [ Frob { a 1 } Frob { b [ Frob { } ] } Transform { } ] }\n"
                                   "Frob { }",
                               &warnings);
  ASSERT_EQ(file.roots.size(), 1u);  // the top-level Frob is gone
  ASSERT_EQ(file.roots[0]->field("children")->nodes.size(), 1u);
  EXPECT_EQ(file.roots[0]->field("children")->nodes[0]->type, "Transform");
  EXPECT_EQ(warnings.str(),
            "w.wrl:2:20: warning: unknown node type 'Frob' skipped (not VRML 97 and no PROTO declares it)\n"
            "w.wrl:3:1: warning: unknown node type 'Frob' skipped (not VRML 97 and no PROTO declares it)\n");
}

TEST(VrmlFile, AnUnknownNodeInACharacterStaysAnError) {
  const auto scene = readScene(kHeader + "Transform { }", "c.wrl");
  ASSERT_FALSE(scene.has_value());
  EXPECT_NE(scene.error().str().find("c.wrl:2:1: error: unknown node type 'Transform'"), std::string::npos)
      << scene.error().str();
}

TEST(VrmlFile, ScriptInterfaceDeclarationsRead) {
  const VrmlFile file = fileOf(kHeader +
                               "DEF S Script { eventIn SFTime tick field SFFloat speed 2 field SFNode n NULL "
                               "url \"javascript: function tick(v) {}\" }");
  EXPECT_EQ(file.roots[0]->field("speed")->numbers, std::vector<double>{2});
  EXPECT_TRUE(file.roots[0]->field("n")->nodeValued);
  EXPECT_EQ(file.roots[0]->field("tick"), nullptr);
}

TEST(VrmlFile, ProtoInstanceExpandsItsBodyWithIsSubstituted) {
  const VrmlFile file = fileOf(kHeader +
                               "PROTO J [ exposedField SFVec3f translation 0 0 0 exposedField MFNode children [] "
                               "exposedField SFVec3f center 1 2 3 ]\n"
                               "{ Transform { translation IS translation center IS center children IS children } }\n"
                               "DEF a J { translation 4 5 6 children [ Shape { } ] }");
  ASSERT_EQ(file.protos, std::vector<std::string>{"J"});
  const VrmlNode& instance = *file.roots.at(0);
  EXPECT_EQ(instance.type, "J");
  ASSERT_TRUE(instance.protoBody);
  const VrmlNode& body = instance.resolved();
  EXPECT_EQ(body.type, "Transform");
  EXPECT_EQ(body.field("translation")->numbers, (std::vector<double>{4, 5, 6}));
  EXPECT_EQ(body.field("center")->numbers, (std::vector<double>{1, 2, 3}));  // the PROTO's default
  ASSERT_EQ(body.field("children")->nodes.size(), 1u);
  EXPECT_EQ(body.field("children")->nodes[0]->type, "Shape");
  // A ROUTE to the instance's `translation` reaches the body's Transform.
  bool linked = false;
  for (const VrmlIsLink& link : instance.isLinks)
    linked = linked ||
             (link.interfaceField == "translation" && link.bodyNode.get() == &body && link.bodyField == "translation");
  EXPECT_TRUE(linked);
}

TEST(VrmlFile, TwoInstancesOfAProtoShareNoBody) {
  const VrmlFile file = fileOf(kHeader + "PROTO P [ field SFVec3f t 0 0 0 ] { Transform { translation IS t } }\n"
                                         "P { t 1 0 0 } P { }");
  ASSERT_EQ(file.roots.size(), 2u);
  EXPECT_NE(file.roots[0]->protoBody, file.roots[1]->protoBody);
  EXPECT_EQ(file.roots[0]->resolved().field("translation")->numbers, (std::vector<double>{1, 0, 0}));
  EXPECT_EQ(file.roots[1]->resolved().field("translation")->numbers, (std::vector<double>{0, 0, 0}));
}

TEST(VrmlFile, HAnimHumanoidReadsThroughItsProtos) {
  Diagnostics warnings;
  const VrmlFile file = fileAt("hanim_humanoid.wrl", &warnings);
  EXPECT_TRUE(warnings.all().empty()) << warnings.str();
  EXPECT_EQ(file.protos, (std::vector<std::string>{"Joint", "Segment", "Site", "Humanoid", "Displacer"}));
  const VrmlNode& knee = *file.defs.at("hanim_l_knee");
  EXPECT_EQ(knee.type, "Joint");
  EXPECT_EQ(knee.field("name")->strings, std::vector<std::string>{"l_knee"});
  EXPECT_EQ(knee.resolved().type, "Transform");
  EXPECT_EQ(knee.resolved().field("center")->numbers, (std::vector<double>{0.1, 0.5, 0}));
  // The humanoid's body: Humanoid -> Transform -> second Group -> HumanoidRoot Joint.
  const VrmlNode& humanoid = file.defs.at("Walker")->resolved();
  const VrmlNode& bodyGroup = *humanoid.field("children")->nodes.at(1);
  EXPECT_EQ(bodyGroup.field("children")->nodes.at(0), file.defs.at("hanim_HumanoidRoot"));
  EXPECT_EQ(file.defs.at("Walker")->field("joints")->nodes.size(), 5u);
  EXPECT_EQ(file.routes.size(), 4u);
}

TEST(VrmlFile, MaxQuirksRead) {
  Diagnostics warnings;
  const VrmlFile file = fileAt("max_quirks.wrl", &warnings);
  // The Latin-1 bone name is read (one warning) and kept as UTF-8.
  ASSERT_EQ(warnings.all().size(), 1u) << warnings.str();
  EXPECT_NE(warnings.str().find("max_quirks.wrl:31:19: warning: not UTF-8 (byte 0xFC)"), std::string::npos)
      << warnings.str();
  EXPECT_TRUE(file.defs.contains("Bip01_Schl\xC3\xBCsselbein"));
  // The TimeSensor and interpolators are children of Bip01, between commas.
  const auto& children = file.defs.at("Bip01")->field("children")->nodes;
  ASSERT_EQ(children.size(), 5u);
  EXPECT_EQ(children[0]->type, "TimeSensor");
  EXPECT_EQ(children[0]->defName, "Bip01-TIMER");
  EXPECT_EQ(file.defs.at("Bip01-POS-INTERP")->field("key")->numbers, (std::vector<double>{0, 0.5, 1}));
  ASSERT_EQ(file.routes.size(), 8u);
  EXPECT_EQ(file.routes[3].toField, "set_scale");
  EXPECT_EQ(file.routes[5].toField, "set_scaleOrientation");
  EXPECT_EQ(file.defs.at("Box01-COORD")->field("point")->numbers.size(), 24u);
}

TEST(VrmlFile, GzippedFileReadsLikeThePlainOne) {
  const VrmlFile plain = fileAt("max_quirks.wrl");
  const VrmlFile zipped = fileAt("max_quirks.wrl.gz");
  ASSERT_EQ(zipped.roots.size(), plain.roots.size());
  EXPECT_EQ(zipped.routes.size(), plain.routes.size());
  EXPECT_EQ(zipped.defs.size(), plain.defs.size());
  EXPECT_EQ(zipped.defs.at("Box01-COORD")->field("point")->numbers,
            plain.defs.at("Box01-COORD")->field("point")->numbers);
}

TEST(VrmlFile, TruncatedOrCorruptGzipIsAnError) {
  const std::string zipped = *readFileText(worldPath("max_quirks.wrl.gz"), 1 << 20);
  EXPECT_EQ(errorsOf(zipped.substr(0, zipped.size() / 2)), "w.wrl: error: cannot decompress: truncated gzip data\n");
  std::string corrupt = zipped;
  for (size_t i = 20; i < 60; ++i) corrupt[i] = static_cast<char>(~corrupt[i]);
  EXPECT_NE(errorsOf(corrupt).find("w.wrl: error: cannot decompress: corrupt gzip data"), std::string::npos);
}

TEST(VrmlFile, BlenderQuirksRead) {
  Diagnostics warnings;
  const VrmlFile file = fileAt("blender_quirks.wrl", &warnings);
  EXPECT_TRUE(warnings.all().empty()) << warnings.str();
  // The linked duplicate USEs the same mesh group.
  EXPECT_EQ(file.defs.at("OB_Cube_001")->field("children")->nodes.at(0), file.defs.at("ME_Cube"));
  EXPECT_EQ(file.defs.at("coord_Cube")->field("point")->numbers.size(), 24u);
}

TEST(VrmlFile, ErrorsSayWhereAndWhat) {
  EXPECT_EQ(errorsOf("#VRML V1.0 ascii\n"),
            "w.wrl:1:1: error: VRML 1.0 is not supported; the first line must be '#VRML V2.0 utf8' (VRML 97)\n");
  EXPECT_EQ(errorsOf("Group { }"),
            "w.wrl:1:1: error: missing header: the first line of a VRML 97 file must be '#VRML V2.0 utf8'\n");
  EXPECT_EQ(errorsOf(kHeader + "Group { children [ USE Nope ] }"),
            "w.wrl:2:20: error: USE Nope: no node is DEF'd with that name before here\n");
  EXPECT_EQ(errorsOf(kHeader + "DEF A Group { children [ USE A ] }"),
            "w.wrl:2:26: error: USE A: no node is DEF'd with that name before here (a node cannot USE itself or an "
            "ancestor)\n");
  EXPECT_EQ(errorsOf(kHeader + "DEF Timer TimeSensor { }\nROUTE Timr.fraction_changed TO Timer.x"),
            "w.wrl:3:1: error: ROUTE names 'Timr', which no node is DEF'd as (did you mean 'Timer'?)\n");
  EXPECT_EQ(errorsOf(kHeader + "ROUTE A TO B.c"),
            "w.wrl:2:7: error: expected 'NodeName.fieldName' in ROUTE, found 'A'\n");
  EXPECT_EQ(errorsOf(kHeader + "Transform { translation IS t }"),
            "w.wrl:2:13: error: 'translation IS t' outside a PROTO body\n");
  EXPECT_EQ(errorsOf(kHeader + "PROTO P [ field SFFloat a 1 ] { Transform { translation IS b } }"),
            "w.wrl:2:45: error: 'translation IS b': PROTO P declares no field or event 'b'\n");
  EXPECT_EQ(errorsOf(kHeader + "Group { children [ Shape { }"),
            "w.wrl:2:29: error: unexpected end of file: the '[' at 2:18 is never closed\n");
  EXPECT_EQ(errorsOf(kHeader + "Transform { translation 1 2 3x }"), "w.wrl:2:29: error: malformed number '3x'\n");
  EXPECT_EQ(errorsOf(kHeader + "Transform { translation }"),
            "w.wrl:2:25: error: expected a value for field 'translation' of Transform, found '}'\n");
}

TEST(VrmlFile, DeepNestingIsAnErrorNotACrash) {
  std::string text = kHeader;
  for (int i = 0; i < 300; ++i) text += "Group { children [ ";
  EXPECT_NE(errorsOf(text).find("nodes nested deeper than 200 levels"), std::string::npos);
}

TEST(VrmlFile, AFieldHoldsAtMostFourMillionValues) {
  // Two bytes a value on disk, eight in memory: the cap keeps one field at 32 MB however it is written.
  std::string many = kHeader + "Coordinate { point [";
  many.reserve(many.size() + 2 * 4'000'003 + 8);
  for (int i = 0; i < 4'000'003; ++i) many += " 0";
  EXPECT_EQ(errorsOf(many + " ] }"),
            "w.wrl:2:8000022: error: field 'point' has more than 4000000 values; the reader's limit per field "
            "(docs/world-format.md)\n");
  std::string fits = kHeader + "Coordinate { point [";
  for (int i = 0; i < 1'000'000; ++i) fits += " 0 0 0 0";
  const VrmlFile file = fileOf(fits + " ] }");
  ASSERT_EQ(file.roots.size(), 1u);
  EXPECT_EQ(file.roots[0]->field("point")->numbers.size(), 4'000'000u);
}

TEST(VrmlFile, MissingFileIsOneDiagnostic) {
  auto result = readVrmlFile("/nonexistent/x.wrl");
  ASSERT_FALSE(result.has_value());
  EXPECT_EQ(result.error().str(), "/nonexistent/x.wrl: error: cannot read VRML file: No such file or directory\n");
}

}  // namespace
}  // namespace imps
