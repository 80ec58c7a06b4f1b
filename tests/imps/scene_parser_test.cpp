// SPDX-License-Identifier: MIT
// The VRML parser (imps/src/scene_parser.h) against a recording ParserTarget: the events a file's structure
// produces and their order, node-valued fields, DEF/USE/NULL, value lists, the header, and what the target sees when
// a syntax error stops the parse (a properly nested prefix). Nothing here knows the IMPS node types.
#include "scene_parser.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace imps::vrml {
namespace {

std::string at(const SourceLoc& loc) { return std::to_string(loc.line) + ":" + std::to_string(loc.column); }

// Writes each call as one line, e.g. `begin Metaball@2:1 def=A@2:1`, `field radius@2:12 [Number 1]`.
class RecordingTarget final : public ParserTarget {
 public:
  std::vector<std::string> events;
  int depth = 0;  // open nodes plus open node fields; must never go negative
  int minDepth = 0;

  void beginNode(const NodeHeader& h) override {
    std::string e = "begin " + h.type + "@" + at(h.typeLoc);
    if (!h.defName.empty()) e += " def=" + h.defName + "@" + at(h.defLoc);
    EXPECT_TRUE(h.defName.empty() ? at(h.defLoc) == at(h.typeLoc) : true) << "without DEF, defLoc is typeLoc";
    events.push_back(e);
    open();
  }
  void endNode(const SourceLoc& closeLoc) override {
    events.push_back("end@" + at(closeLoc));
    close();
  }
  void use(const std::string& name, const SourceLoc& loc) override { events.push_back("use " + name + "@" + at(loc)); }
  void null(const SourceLoc& loc) override { events.push_back("null@" + at(loc)); }
  void field(const std::string& name, const SourceLoc& nameLoc, const FieldValue& value) override {
    std::string e = "field " + name + "@" + at(nameLoc) + (value.bracketed ? " [" : " (");
    for (size_t i = 0; i < value.items.size(); ++i) {
      const Token& t = value.items[i];
      e += (i ? " " : "") + kindName(t.kind) + ":" + t.text;
    }
    e += value.bracketed ? "]" : ")";
    e += "@" + at(value.loc);
    events.push_back(e);
  }
  void beginNodeField(const std::string& name, const SourceLoc& nameLoc, bool bracketed) override {
    events.push_back("nodes " + name + "@" + at(nameLoc) + (bracketed ? " [" : ""));
    open();
  }
  void endNodeField() override {
    events.push_back("/nodes");
    close();
  }

 private:
  static std::string kindName(TokenKind k) {
    switch (k) {
      case TokenKind::Number:
        return "N";
      case TokenKind::BadNumber:
        return "Bad";
      case TokenKind::String:
        return "S";
      case TokenKind::Identifier:
        return "Id";
      default:
        return "?";
    }
  }
  void open() { ++depth; }
  void close() {
    --depth;
    minDepth = std::min(minDepth, depth);
  }
};

struct Parsed {
  bool toEnd = false;
  RecordingTarget target;
  Diagnostics diagnostics;
};

Parsed parseText(const std::string& text) {
  Parsed p;
  DiagnosticSink sink(p.diagnostics);
  p.toEnd = parse(text, "t.wrl", p.target, sink);
  EXPECT_GE(p.target.minDepth, 0) << "more closing calls than opening ones";
  return p;
}

const std::string kHeader = "#VRML V2.0 utf8\n";

TEST(SceneParser, NodesAndScalarFieldsInOrder) {
  const Parsed p = parseText(kHeader + "Metaball { radius 1.5 center 0 -1 2e1 name \"x\" on TRUE }\nOther { }");
  EXPECT_TRUE(p.toEnd);
  EXPECT_FALSE(p.diagnostics.hasErrors());
  EXPECT_EQ(p.target.events, (std::vector<std::string>{
                                 "begin Metaball@2:1",
                                 "field radius@2:12 (N:1.5)@2:19",
                                 "field center@2:23 (N:0 N:-1 N:2e1)@2:30",
                                 "field name@2:39 (S:x)@2:44",
                                 "field on@2:48 (Id:TRUE)@2:51",
                                 "end@2:56",
                                 "begin Other@3:1",
                                 "end@3:9",
                             }));
  EXPECT_EQ(p.target.depth, 0);
}

TEST(SceneParser, BracketedValuesAndEmptyLists) {
  const Parsed p = parseText(kHeader + "N { members [ \"a\", \"b\" ] empty [ ] flags [ TRUE FALSE ] }");
  EXPECT_TRUE(p.toEnd);
  EXPECT_EQ(p.target.events, (std::vector<std::string>{
                                 "begin N@2:1",
                                 "field members@2:5 [S:a S:b]@2:15",
                                 "field empty@2:26 []@2:34",
                                 "field flags@2:36 [Id:TRUE Id:FALSE]@2:44",
                                 "end@2:57",
                             }));
}

TEST(SceneParser, NodeFieldsDefUseAndNull) {
  const Parsed p = parseText(kHeader +
                             "DEF T Group {\n"
                             "  children [ DEF A Ball { } USE A NULL ]\n"
                             "  material M { }\n"
                             "  other NULL\n"
                             "}\n"
                             "USE T\n");
  EXPECT_TRUE(p.toEnd) << p.diagnostics.str();
  EXPECT_EQ(p.target.events, (std::vector<std::string>{
                                 "begin Group@2:7 def=T@2:1",
                                 "nodes children@3:3 [",
                                 "begin Ball@3:20 def=A@3:14",
                                 "end@3:27",
                                 "use A@3:29",
                                 "null@3:35",
                                 "/nodes",
                                 "nodes material@4:3",
                                 "begin M@4:12",
                                 "end@4:16",
                                 "/nodes",
                                 "nodes other@5:3",
                                 "null@5:9",
                                 "/nodes",
                                 "end@6:1",
                                 "use T@7:1",
                             }));
  EXPECT_EQ(p.target.depth, 0);
}

TEST(SceneParser, BadNumbersReachTheTargetAndDoNotStopTheParse) {
  const Parsed p = parseText(kHeader + "N { a 1..2 b 3 }");
  EXPECT_TRUE(p.toEnd);
  EXPECT_EQ(p.diagnostics.errorCount(), 1);
  EXPECT_EQ(p.target.events, (std::vector<std::string>{"begin N@2:1", "field a@2:5 (Bad:1..2)@2:7",
                                                       "field b@2:12 (N:3)@2:14", "end@2:16"}));
}

TEST(SceneParser, HeaderByteOrderMarkAndLineEndings) {
  EXPECT_TRUE(parseText("#VRML V2.0 utf8").toEnd);
  EXPECT_TRUE(parseText("#VRML V2.0 utf8\tanything\r\nN { }").toEnd);
  const Parsed bom = parseText("\xEF\xBB\xBF#VRML V2.0 utf8\nN { }");
  EXPECT_TRUE(bom.toEnd);
  EXPECT_EQ(bom.target.events, (std::vector<std::string>{"begin N@2:1", "end@2:5"}));
  for (const char* bad : {"", "N { }", "#VRML V1.0 ascii\n", "#VRML V2.0 utf8x\n", "\n#VRML V2.0 utf8\n"}) {
    const Parsed p = parseText(bad);
    EXPECT_FALSE(p.toEnd) << bad;
    EXPECT_TRUE(p.target.events.empty()) << "nothing reaches the target without a header: " << bad;
    ASSERT_EQ(p.diagnostics.errorCount(), 1) << bad;
    EXPECT_EQ(at(p.diagnostics.all()[0].loc), "1:1");
  }
}

// A syntax error stops the parse: false, one error, and the target saw a prefix whose calls nest properly.
TEST(SceneParser, SyntaxErrorsStopWithANestedPrefix) {
  struct Case {
    std::string body;
    std::string message;
    std::vector<std::string> events;
  };
  const std::vector<Case> cases = {
      {"N { a 1 ",
       "t.wrl:2:9: error: unexpected end of file inside N: the '{' at 2:3 is never closed",
       {"begin N@2:1", "field a@2:5 (N:1)@2:7"}},
      {"N { } }", "t.wrl:2:7: error: unexpected '}' at top level: nothing is open here", {"begin N@2:1", "end@2:5"}},
      {"N { a [ 1 2 }", "t.wrl:2:13: error: expected ']' to close the '[' at 2:7, found '}'", {"begin N@2:1"}},
      {"N { a [ 1 M { } ] }", "t.wrl:2:11: error: a list holds either values or nodes, not both", {"begin N@2:1"}},
      {"N { c [ M { } 1 ] }",
       "t.wrl:2:15: error: expected ']' to close the '[' at 2:7, found '1'",
       {"begin N@2:1", "nodes c@2:5 [", "begin M@2:9", "end@2:13", "/nodes"}},
      {"N { 1 }", "t.wrl:2:5: error: expected a field name or '}' in N, found '1'", {"begin N@2:1"}},
      {"N { a }", "t.wrl:2:7: error: expected a value for field 'a', found '}'", {"begin N@2:1"}},
      {"N [ ]", "t.wrl:2:1: error: expected a node at top level, found 'N'", {}},
      {"DEF 1 N { }", "t.wrl:2:5: error: expected a name after DEF, found '1'", {}},
      {"DEF A TRUE { }", "t.wrl:2:7: error: expected a node type, found 'TRUE'", {}},
      {"USE NULL", "t.wrl:2:5: error: expected a name after USE, found 'NULL'", {}},
      {"N { c M { a [ } }",
       "t.wrl:2:15: error: expected ']' to close the '[' at 2:13, found '}'",
       {"begin N@2:1", "nodes c@2:5", "begin M@2:7", "/nodes"}},
  };
  for (const Case& c : cases) {
    const Parsed p = parseText(kHeader + c.body);
    EXPECT_FALSE(p.toEnd) << c.body;
    EXPECT_EQ(p.diagnostics.str(), c.message + "\n") << c.body;
    EXPECT_EQ(p.target.events, c.events) << c.body;
  }
}

TEST(SceneParser, NestingIsBoundedAtKMaxNesting) {
  auto nested = [](int levels) {
    std::string s = kHeader;
    for (int i = 0; i < levels; ++i) s += "N { c ";
    for (int i = 0; i < levels; ++i) s += "} ";
    return s;
  };
  // "N { c N { c ... } }": the innermost `c` has no value, so the deepest legal file ends with a scalar.
  std::string ok = kHeader;
  for (int i = 0; i < kMaxNesting - 1; ++i) ok += "N { c ";
  ok += "N { } ";
  for (int i = 0; i < kMaxNesting - 1; ++i) ok += "} ";
  const Parsed deepest = parseText(ok);
  EXPECT_TRUE(deepest.toEnd) << deepest.diagnostics.str();
  EXPECT_EQ(deepest.target.depth, 0);

  const Parsed tooDeep = parseText(nested(kMaxNesting + 1));
  EXPECT_FALSE(tooDeep.toEnd);
  ASSERT_EQ(tooDeep.diagnostics.errorCount(), 1);
  EXPECT_NE(tooDeep.diagnostics.all()[0].message.find("nested deeper than 200 levels"), std::string::npos);
  int begins = 0;
  for (const std::string& e : tooDeep.target.events) begins += e.starts_with("begin ") ? 1 : 0;
  EXPECT_EQ(begins, kMaxNesting) << "the node past the limit never reaches the target";
}

TEST(SceneParser, OverlongValueIsReportedOnceReadPastAndDropped) {
  std::string text = kHeader + "N { a [";
  text.reserve(text.size() + 2 * (kMaxFieldItems + 3));
  for (size_t i = 0; i < kMaxFieldItems + 2; ++i) text += " 1";
  text += " ] b 2 }";
  const Parsed p = parseText(text);
  EXPECT_TRUE(p.toEnd) << "the rest of the run is read past";
  EXPECT_EQ(p.diagnostics.errorCount(), 1);
  // "N { a [" is 7 columns, each item 2 more, then " ]", " b", " 2" and " }".
  const size_t afterItems = 7 + 2 * (kMaxFieldItems + 2);
  const auto column = [&](size_t extra) { return "@2:" + std::to_string(afterItems + extra); };
  EXPECT_EQ(p.target.events,
            (std::vector<std::string>{"begin N@2:1", "field b" + column(4) + " (N:2)" + column(6), "end" + column(8)}));
}

TEST(SceneParser, AFullSinkStopsTheParse) {
  std::string text = kHeader + "N {";
  for (int i = 0; i < DiagnosticSink::kMaxErrors + 10; ++i) text += " a 1..2";
  text += " }";
  const Parsed p = parseText(text);
  EXPECT_FALSE(p.toEnd);
  EXPECT_EQ(p.diagnostics.errorCount(), DiagnosticSink::kMaxErrors);
  EXPECT_LT(p.target.events.size(), size_t(DiagnosticSink::kMaxErrors + 10));
}

}  // namespace
}  // namespace imps::vrml
