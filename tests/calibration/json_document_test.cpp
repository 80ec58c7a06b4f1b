// SPDX-License-Identifier: MIT
// The calibration files' JSON reader (calibration/src/json_document.h): every value and key with its file:line:column
// (columns count bytes), RFC 8259's grammar without extensions (no comments, trailing commas, NaN, single quotes,
// leading zeros), escapes decoded to UTF-8, duplicate keys refused, input that is not UTF-8 refused at its first bad
// byte, and readJsonFileText's bounded, described reads.
#include "json_document.h"

#include <gtest/gtest.h>

#include <string>

#include "scratch_dir.h"

namespace imps::calibration::detail {
namespace {

std::string at(const SourceLoc& loc) { return std::to_string(loc.line) + ":" + std::to_string(loc.column); }

JsonValue parsed(std::string_view text) {
  JsonValue v;
  Diagnostics d;
  EXPECT_TRUE(parseJson(text, "f.json", v, d)) << text << "\n" << d.str();
  EXPECT_TRUE(d.all().empty());
  return v;
}

// The one diagnostic a document that must fail gives, as `file:line:col: error: message`.
std::string errorOf(std::string_view text) {
  JsonValue v;
  Diagnostics d;
  EXPECT_FALSE(parseJson(text, "f.json", v, d)) << text;
  EXPECT_EQ(d.all().size(), 1u) << text;
  return d.all().empty() ? std::string() : d.all()[0].str();
}

TEST(JsonDocument, ValuesKindsAndTheirLocations) {
  const JsonValue v = parsed("{\n  \"a\": [1, -2.5e1, true],\n\t\"b\" : null, \"c\": {\"d\": false}, \"e\": \"s\"\n}");
  ASSERT_EQ(v.kind, JsonValue::Kind::Object);
  EXPECT_EQ(at(v.loc), "1:1");
  ASSERT_EQ(v.members.size(), 4u);
  EXPECT_EQ(v.members[0].key, "a");
  EXPECT_EQ(at(v.members[0].keyLoc), "2:3");
  const JsonValue& a = v.members[0].value;
  ASSERT_EQ(a.kind, JsonValue::Kind::Array);
  EXPECT_EQ(at(a.loc), "2:8");
  ASSERT_EQ(a.items.size(), 3u);
  EXPECT_EQ(a.items[0].number, 1.0);
  EXPECT_TRUE(a.items[0].integral);
  EXPECT_EQ(at(a.items[1].loc), "2:12");
  EXPECT_EQ(a.items[1].number, -25.0);
  EXPECT_FALSE(a.items[1].integral) << "written with an exponent";
  EXPECT_EQ(a.items[2].kind, JsonValue::Kind::Bool);
  EXPECT_TRUE(a.items[2].boolean);
  EXPECT_EQ(at(v.members[1].keyLoc), "3:2") << "a tab is one byte";
  EXPECT_EQ(v.members[1].value.kind, JsonValue::Kind::Null);
  EXPECT_EQ(at(v.members[1].value.loc), "3:8");
  ASSERT_NE(v.find("c"), nullptr);
  ASSERT_NE(v.find("c")->find("d"), nullptr);
  EXPECT_FALSE(v.find("c")->find("d")->boolean);
  EXPECT_EQ(v.find("c")->find("d")->kind, JsonValue::Kind::Bool);
  EXPECT_EQ(v.find("e")->string, "s");
  EXPECT_EQ(v.find("missing"), nullptr);
  EXPECT_EQ(v.find("d"), nullptr) << "find looks at this object's members only";
  // Members stay in file order.
  std::string order;
  for (const auto& m : v.members) order += m.key;
  EXPECT_EQ(order, "abce");
  // Any value may be the document; white space around it is fine.
  EXPECT_EQ(parsed(" \r\n 42 \n").number, 42.0);
  EXPECT_EQ(parsed("[]").items.size(), 0u);
  EXPECT_EQ(parsed("{}").members.size(), 0u);
}

TEST(JsonDocument, ColumnsCountBytes) {
  // "é" is two bytes: the value after it starts two columns later than after an ASCII letter.
  const JsonValue ascii = parsed("{\"e\": 1}"), accented = parsed("{\"\xc3\xa9\": 1}");
  EXPECT_EQ(at(ascii.members[0].value.loc), "1:7");
  EXPECT_EQ(at(accented.members[0].value.loc), "1:8");
  EXPECT_EQ(accented.members[0].key, "\xc3\xa9");
}

TEST(JsonDocument, NumbersFollowTheJsonGrammar) {
  struct Good {
    const char* text;
    double value;
    bool integral;
  };
  for (const Good& g :
       {Good{"0", 0, true}, Good{"-0", 0, true}, Good{"17", 17, true}, Good{"-3", -3, true}, Good{"0.5", 0.5, false},
        Good{"1e3", 1000, false}, Good{"1E+2", 100, false}, Good{"-2.5e-1", -0.25, false}, Good{"1.0", 1, false}}) {
    const JsonValue v = parsed(g.text);
    EXPECT_EQ(v.kind, JsonValue::Kind::Number) << g.text;
    EXPECT_EQ(v.number, g.value) << g.text;
    EXPECT_EQ(v.integral, g.integral) << g.text;
  }
  EXPECT_EQ(errorOf("012"), "f.json:1:2: error: numbers may not have leading zeros");
  EXPECT_EQ(errorOf("1."), "f.json:1:3: error: expected a digit after '.'");
  EXPECT_EQ(errorOf("1e"), "f.json:1:3: error: expected a digit in the exponent");
  EXPECT_EQ(errorOf("-"), "f.json:1:2: error: expected a digit");
  EXPECT_EQ(errorOf(".5"), "f.json:1:1: error: expected a value, found '.'");
  EXPECT_EQ(errorOf("+1"), "f.json:1:1: error: expected a value, found '+'");
  EXPECT_EQ(errorOf("[1, 1e999]"), "f.json:1:5: error: number '1e999' is out of range");
  for (const char* nonFinite : {"NaN", "Infinity", "-Infinity"})
    EXPECT_EQ(errorOf(nonFinite), "f.json:1:1: error: NaN and infinities are not JSON numbers: write a finite number");
}

TEST(JsonDocument, StringEscapesDecodeToUtf8) {
  EXPECT_EQ(parsed(R"("\"\\\/\b\f\n\r\t")").string, "\"\\/\b\f\n\r\t");
  EXPECT_EQ(parsed(R"("\u0041\u00e9\u20AC")").string, "A\xc3\xa9\xe2\x82\xac") << "1, 2 and 3 UTF-8 bytes";
  EXPECT_EQ(parsed(R"("\ud83d\ude00")").string, "\xf0\x9f\x98\x80") << "a surrogate pair is one code point";
  EXPECT_EQ(parsed(R"("\u0000")").string, std::string(1, '\0'));
  EXPECT_EQ(parsed("\"caf\xc3\xa9\"").string, "caf\xc3\xa9") << "UTF-8 passes through";
  EXPECT_EQ(errorOf(R"("\x")"), "f.json:1:4: error: unknown escape '\\x'");
  EXPECT_EQ(errorOf(R"("\u12G4")"), "f.json:1:6: error: expected four hex digits after \\u");
  EXPECT_EQ(errorOf(R"("\ud83d")"), "f.json:1:8: error: unpaired UTF-16 surrogate in a \\u escape");
  EXPECT_EQ(errorOf(R"("\ud83d\u0041")"), "f.json:1:14: error: unpaired UTF-16 surrogate in a \\u escape");
  EXPECT_EQ(errorOf(R"("\ude00")"), "f.json:1:8: error: unpaired UTF-16 surrogate in a \\u escape");
  EXPECT_EQ(errorOf("\"a\tb\""), "f.json:1:3: error: control character inside a string");
  EXPECT_EQ(errorOf("\"ab\ncd\""), "f.json:1:4: error: unterminated string (missing '\"' before the end of the line)");
  EXPECT_EQ(errorOf("\"ab"), "f.json:1:4: error: unexpected end of file inside a string");
  EXPECT_EQ(errorOf("'ab'"), "f.json:1:1: error: strings take double quotes in JSON");
}

TEST(JsonDocument, DuplicateKeysAreRefusedWithBothPlaces) {
  EXPECT_EQ(errorOf("{\n\"k\": 1,\n\"j\": 2,\n  \"k\": 3}"), "f.json:4:3: error: duplicate key 'k' (first at line 2)");
  // The same key in different objects is fine; so are keys differing only in case.
  const JsonValue v = parsed(R"({"k": {"k": 1}, "K": 2})");
  EXPECT_EQ(v.members.size(), 2u);
  // An escape spelling the same key is the same key.
  EXPECT_EQ(errorOf(R"({"k": 1, "\u006b": 2})"), "f.json:1:10: error: duplicate key 'k' (first at line 1)");
}

TEST(JsonDocument, SyntaxErrorsSayWhereAndWhat) {
  EXPECT_EQ(errorOf(""), "f.json:1:1: error: unexpected end of file: expected a value");
  EXPECT_EQ(errorOf("[1, 2,]"), "f.json:1:7: error: expected a value after ',' (JSON has no trailing commas)");
  EXPECT_EQ(errorOf("{\"a\": 1,}"), "f.json:1:9: error: expected a key after ',' (JSON has no trailing commas)");
  EXPECT_EQ(errorOf("{a: 1}"), "f.json:1:2: error: expected a key in double quotes");
  EXPECT_EQ(errorOf("{\"a\" 1}"), "f.json:1:6: error: expected ':' after key 'a'");
  EXPECT_EQ(errorOf("{\"a\": 1 \"b\": 2}"), "f.json:1:9: error: expected ',' or '}' after a member");
  EXPECT_EQ(errorOf("[1 2]"), "f.json:1:4: error: expected ',' or ']' after an array element");
  EXPECT_EQ(errorOf("[1,"), "f.json:1:4: error: unexpected end of file: expected a value");
  EXPECT_EQ(errorOf("[1"), "f.json:1:3: error: unexpected end of file inside an array: expected ',' or ']'");
  EXPECT_EQ(errorOf("{\"a\": 1"), "f.json:1:8: error: unexpected end of file inside an object: expected ',' or '}'");
  EXPECT_EQ(errorOf("{"), "f.json:1:2: error: unexpected end of file inside an object");
  EXPECT_EQ(errorOf("1 2"), "f.json:1:3: error: expected the end of the document after the top-level value");
  EXPECT_EQ(errorOf("// c\n1"), "f.json:1:1: error: expected a value, found '/'") << "no comments";
  EXPECT_EQ(errorOf("tru"), "f.json:1:1: error: expected a value, found 't'");
}

TEST(JsonDocument, NestingIsBounded) {
  std::string ok(60, '[');
  ok += std::string(60, ']');
  EXPECT_EQ(parsed(ok).kind, JsonValue::Kind::Array);
  std::string deep(100000, '[');  // would exhaust the stack if the recursion were unbounded
  const std::string e = errorOf(deep);
  EXPECT_NE(e.find("values nested too deeply"), std::string::npos) << e;
}

TEST(JsonDocument, InputThatIsNotUtf8IsRefusedAtItsFirstBadByte) {
  EXPECT_EQ(errorOf("{\"a\":\n  \"x\xff\"}"),
            "f.json:2:5: error: invalid UTF-8 (byte 0xFF); a JSON file must be UTF-8 text");
  EXPECT_EQ(errorOf("\xc0\xaf"), "f.json:1:1: error: invalid UTF-8 (byte 0xC0); a JSON file must be UTF-8 text")
      << "an overlong encoding";
  EXPECT_EQ(errorOf("\"\xed\xa0\x80\""), "f.json:1:2: error: invalid UTF-8 (byte 0xED); a JSON file must be UTF-8 text")
      << "an encoded surrogate";
  // Even a bad byte the grammar would reject anyway is reported as what it is, and nothing is returned.
  JsonValue v;
  v.kind = JsonValue::Kind::Array;
  Diagnostics d;
  EXPECT_FALSE(parseJson("[1] \x80", "f.json", v, d));
  EXPECT_EQ(v.kind, JsonValue::Kind::Null) << "the output is reset";
}

TEST(JsonDocument, DescribeNamesKinds) {
  EXPECT_STREQ(describe(JsonValue::Kind::Null), "null");
  EXPECT_STREQ(describe(JsonValue::Kind::Bool), "a boolean");
  EXPECT_STREQ(describe(JsonValue::Kind::Number), "a number");
  EXPECT_STREQ(describe(JsonValue::Kind::String), "a string");
  EXPECT_STREQ(describe(JsonValue::Kind::Array), "an array");
  EXPECT_STREQ(describe(JsonValue::Kind::Object), "an object");
}

TEST(JsonDocument, ReadJsonFileTextIsBoundedAndSaysWhy) {
  ScratchDir dir("json_document");
  const auto path = dir.path() / "map.json";
  writeBytes(path, "{\"a\": 1}\n");
  auto text = readJsonFileText(path, "rig map");
  ASSERT_TRUE(text.has_value());
  EXPECT_EQ(*text, "{\"a\": 1}\n");

  auto missing = readJsonFileText(dir.path() / "none.json", "rig map");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().str(),
            (dir.path() / "none.json").string() + ": error: cannot read rig map: no such file\n");

  auto directory = readJsonFileText(dir.path(), "joint map");
  ASSERT_FALSE(directory.has_value());
  EXPECT_NE(directory.error().str().find("cannot read joint map: not a readable file"), std::string::npos);

  auto endless = readJsonFileText("/dev/zero", "check pose");
  ASSERT_FALSE(endless.has_value()) << "an endless input is refused before it fills memory";
  const std::string why = endless.error().str();
  EXPECT_NE(why.find("cannot read check pose: larger than"), std::string::npos) << why;
  EXPECT_NE(why.find("a check pose is a few kilobytes"), std::string::npos) << why;
}

}  // namespace
}  // namespace imps::calibration::detail
