// SPDX-License-Identifier: MIT
// The VRML lexer (imps/src/vrml_lexer.h) on its own: token kinds, number spellings, comments and separators,
// strings with escapes, the two identifier dialects, line and code-point column positions, lookahead, bad input
// reported once at the bad token, and the DiagnosticSink's cap.
#include "vrml_lexer.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace imps::vrml {
namespace {

// Every token of `text` up to and including End, with the diagnostics the lexer reported.
struct Lexed {
  std::vector<Token> tokens;
  Diagnostics diagnostics;
};

Lexed lex(std::string_view text, Dialect dialect = Dialect::Imps) {
  Lexed out;
  DiagnosticSink sink(out.diagnostics);
  Lexer lexer(text, "t.wrl", sink, dialect);
  while (true) {
    out.tokens.push_back(lexer.next());
    if (out.tokens.back().kind == TokenKind::End) break;
    if (out.tokens.size() > 1000) break;  // a lexer that never ends the input fails below, not hangs
  }
  return out;
}

std::vector<TokenKind> kindsOf(const Lexed& l) {
  std::vector<TokenKind> kinds;
  for (const Token& t : l.tokens) kinds.push_back(t.kind);
  return kinds;
}

// The single token of `text` (End is checked to follow it).
Token only(std::string_view text, Dialect dialect = Dialect::Imps, Diagnostics* diagnostics = nullptr) {
  Lexed l = lex(text, dialect);
  EXPECT_EQ(l.tokens.size(), 2u) << text;
  EXPECT_EQ(l.tokens.back().kind, TokenKind::End) << text;
  if (diagnostics != nullptr) *diagnostics = l.diagnostics;
  return l.tokens.front();
}

TEST(VrmlLexer, BracketsIdentifiersAndEnd) {
  const Lexed l = lex("Metaball { radius [ ] }");
  EXPECT_EQ(kindsOf(l), (std::vector<TokenKind>{TokenKind::Identifier, TokenKind::LeftBrace, TokenKind::Identifier,
                                                TokenKind::LeftBracket, TokenKind::RightBracket, TokenKind::RightBrace,
                                                TokenKind::End}));
  EXPECT_EQ(l.tokens[0].text, "Metaball");
  EXPECT_EQ(l.tokens[2].text, "radius");
  EXPECT_FALSE(l.diagnostics.hasErrors());
  // Keywords are identifiers too; the parser tells them apart.
  for (const char* keyword : {"DEF", "USE", "NULL", "TRUE", "FALSE"}) {
    const Token t = only(keyword);
    EXPECT_EQ(t.kind, TokenKind::Identifier) << keyword;
    EXPECT_EQ(t.text, keyword);
  }
  // End repeats once the input is used up.
  Diagnostics none;
  DiagnosticSink sink(none);
  Lexer lexer("", "t.wrl", sink);
  EXPECT_EQ(lexer.next().kind, TokenKind::End);
  EXPECT_EQ(lexer.next().kind, TokenKind::End);
}

TEST(VrmlLexer, WhitespaceCommasAndCommentsSeparateAndAreDropped) {
  const Lexed l = lex("a,b\tc\r\nd # e f { [ \"\n,,g#h");
  ASSERT_EQ(l.tokens.size(), 6u);
  std::vector<std::string> texts;
  for (size_t i = 0; i + 1 < l.tokens.size(); ++i) texts.push_back(l.tokens[i].text);
  EXPECT_EQ(texts, (std::vector<std::string>{"a", "b", "c", "d", "g"}));
  EXPECT_FALSE(l.diagnostics.hasErrors());
}

TEST(VrmlLexer, WellFormedNumbersKeepTheirSpelling) {
  // docs/scene-format.md: [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?, decimal only.
  for (const char* spelling : {"0", "1", "-2.", ".5", "+4E+2", "1e-3", "-0.5e+1", "007", "123456789012"}) {
    Diagnostics d;
    const Token t = only(spelling, Dialect::Imps, &d);
    EXPECT_EQ(t.kind, TokenKind::Number) << spelling;
    EXPECT_EQ(t.text, spelling) << "the spelling is kept: ints and floats differ";
    EXPECT_FALSE(d.hasErrors()) << spelling;
  }
}

TEST(VrmlLexer, MalformedNonFiniteAndOutOfRangeNumbersAreOneReportedBadToken) {
  struct Case {
    const char* text;
    const char* message;
  };
  for (const Case& c :
       {Case{"1.2.3", "malformed number '1.2.3'"}, Case{"1e", "malformed number '1e'"},
        Case{"-", "malformed number '-'"}, Case{".", "malformed number '.'"},
        Case{"0x1F", "malformed number '0x1F'"},  // hexadecimal is not in the dialect
        Case{"1..2", "malformed number '1..2'"}, Case{"nan", "'nan' is not a finite number"},
        Case{"-Infinity", "'-Infinity' is not a finite number"}, Case{"+inf", "'+inf' is not a finite number"},
        Case{"INF", "'INF' is not a finite number"}, Case{"1e999", "number '1e999' is out of range"}}) {
    Diagnostics d;
    const Token t = only(c.text, Dialect::Imps, &d);
    EXPECT_EQ(t.kind, TokenKind::BadNumber) << c.text;
    EXPECT_EQ(t.text, c.text);
    ASSERT_EQ(d.all().size(), 1u) << c.text;
    EXPECT_EQ(d.all()[0].message, c.message);
    EXPECT_EQ(d.all()[0].loc.line, 1);
    EXPECT_EQ(d.all()[0].loc.column, 1);
  }
  // A bad number does not swallow what follows it.
  const Lexed l = lex("1.2.3 4");
  EXPECT_EQ(kindsOf(l), (std::vector<TokenKind>{TokenKind::BadNumber, TokenKind::Number, TokenKind::End}));
  EXPECT_EQ(l.diagnostics.errorCount(), 1);
}

TEST(VrmlLexer, StringsDecodeBackslashEscapes) {
  EXPECT_EQ(only(R"("plain")").text, "plain");
  EXPECT_EQ(only(R"("")").kind, TokenKind::String);
  EXPECT_EQ(only(R"("")").text, "");
  // VRML: a backslash makes the next character literal, so \" and \\ give " and \, and \n gives n.
  EXPECT_EQ(only(R"("q\"uo\\te")").text, "q\"uo\\te");
  EXPECT_EQ(only(R"("a\nb")").text, "anb");
  // Separators, comment marks and brackets inside a string are text; tabs and newlines are kept.
  const Token t = only("\"a, b # { [\n\tc\"");
  EXPECT_EQ(t.kind, TokenKind::String);
  EXPECT_EQ(t.text, "a, b # { [\n\tc");
  EXPECT_EQ(describe(t), "a string");
}

TEST(VrmlLexer, UnterminatedStringAndControlCharactersAreReported) {
  Diagnostics d;
  const Token t = only("  \"never closed", Dialect::Imps, &d);
  EXPECT_EQ(t.kind, TokenKind::Invalid);
  ASSERT_EQ(d.all().size(), 1u);
  EXPECT_EQ(d.all()[0].str(), "t.wrl:1:3: error: unterminated string (it starts here)");
  // A backslash at the very end escapes nothing; the string is still unterminated.
  EXPECT_EQ(only("\"x\\").kind, TokenKind::Invalid);

  const Lexed bell = lex("\"a\x07");
  ASSERT_FALSE(bell.tokens.empty());
  EXPECT_EQ(bell.tokens[0].kind, TokenKind::Invalid);
  EXPECT_EQ(bell.tokens[0].text, "0x07");
  ASSERT_GE(bell.diagnostics.all().size(), 1u);
  EXPECT_EQ(bell.diagnostics.all()[0].str(),
            "t.wrl:1:3: error: control character 0x07 in a string; a scene file must be text");

  Diagnostics nul;
  const Token stray = only(std::string_view("\0", 1), Dialect::Imps, &nul);
  EXPECT_EQ(stray.kind, TokenKind::Invalid);
  EXPECT_EQ(stray.text, "0x00");
  ASSERT_EQ(nul.all().size(), 1u);
  EXPECT_EQ(nul.all()[0].message, "unexpected control character 0x00; a scene file must be text");
}

TEST(VrmlLexer, ImpsIdentifiersAreCLike) {
  EXPECT_EQ(only("_a1_B").text, "_a1_B");
  // '-' and '.' end an IMPS identifier: `Box01-POS` is a name and then a (bad) number.
  const Lexed l = lex("Box01-POS");
  EXPECT_EQ(kindsOf(l), (std::vector<TokenKind>{TokenKind::Identifier, TokenKind::BadNumber, TokenKind::End}));
  EXPECT_EQ(l.tokens[0].text, "Box01");
  // A non-ASCII letter is a stray character, named whole.
  const Lexed e = lex("\xc3\xa9");
  ASSERT_EQ(e.tokens.size(), 2u);
  EXPECT_EQ(e.tokens[0].kind, TokenKind::Invalid);
  EXPECT_EQ(e.tokens[0].text, "\xc3\xa9");
  ASSERT_EQ(e.diagnostics.all().size(), 1u);
  EXPECT_EQ(e.diagnostics.all()[0].message, "unexpected character '\xc3\xa9'");
}

TEST(VrmlLexer, Vrml97IdentifiersAsExportersWriteThem) {
  // ISO/IEC 14772 clause 5.3: any printable character but " # ' , [ \ ] { } and white space; UTF-8 letters.
  for (const char* name : {"Box01-POS-INTERP", "caf\xc3\xa9", "a+b", "x:y", "Node.field", "_1"}) {
    Diagnostics d;
    const Token t = only(name, Dialect::Vrml97, &d);
    EXPECT_EQ(t.kind, TokenKind::Identifier) << name;
    EXPECT_EQ(t.text, name);
    EXPECT_FALSE(d.hasErrors()) << name;
  }
  // The excluded characters end a name.
  const Lexed l = lex("a{b}c[d]e,f#g", Dialect::Vrml97);
  std::vector<std::string> names;
  for (const Token& t : l.tokens)
    if (t.kind == TokenKind::Identifier) names.push_back(t.text);
  EXPECT_EQ(names, (std::vector<std::string>{"a", "b", "c", "d", "e", "f"}));
  // A name may not start with a digit, '+', '-' or '.': those start numbers.
  EXPECT_EQ(only("-1", Dialect::Vrml97).kind, TokenKind::Number);
  EXPECT_EQ(only("1a", Dialect::Vrml97).kind, TokenKind::BadNumber);
  // Non-finite spellings are bad numbers in both dialects.
  EXPECT_EQ(only("NaN", Dialect::Vrml97).kind, TokenKind::BadNumber);
}

TEST(VrmlLexer, PositionsAreLinesAndCodePointColumnsFromOne) {
  const Lexed l = lex("a\n  \"\xc3\xa9\xc3\xa9\" b\n\n\t[");
  ASSERT_EQ(l.tokens.size(), 5u);
  EXPECT_EQ(l.tokens[0].line, 1);
  EXPECT_EQ(l.tokens[0].column, 1);
  EXPECT_EQ(l.tokens[1].line, 2);
  EXPECT_EQ(l.tokens[1].column, 3);
  EXPECT_EQ(l.tokens[2].line, 2);
  EXPECT_EQ(l.tokens[2].column, 8) << "\"éé\" is 4 characters (6 bytes) starting at column 3, then a space";
  EXPECT_EQ(l.tokens[3].line, 4);
  EXPECT_EQ(l.tokens[3].column, 2);
  Diagnostics none;
  DiagnosticSink sink(none);
  Lexer lexer("x", "f.wrl", sink);
  const SourceLoc loc = lexer.loc(lexer.next());
  EXPECT_EQ(loc.file, "f.wrl");
  EXPECT_EQ(loc.line, 1);
  EXPECT_EQ(loc.column, 1);
}

TEST(VrmlLexer, PeekLooksAheadWithoutConsuming) {
  Diagnostics d;
  DiagnosticSink sink(d);
  Lexer lexer("a b c", "t.wrl", sink);
  EXPECT_EQ(lexer.peek(2).text, "c");
  EXPECT_EQ(lexer.peek().text, "a");
  EXPECT_EQ(lexer.peek(1).text, "b");
  EXPECT_EQ(lexer.next().text, "a");
  EXPECT_EQ(lexer.peek().text, "b");
  EXPECT_EQ(lexer.next().text, "b");
  EXPECT_EQ(lexer.next().text, "c");
  EXPECT_EQ(lexer.peek(5).kind, TokenKind::End);
  // Peeking far ahead over a bad token reports it once, not once per peek.
  Diagnostics once;
  DiagnosticSink onceSink(once);
  Lexer bad("1.2.3", "t.wrl", onceSink);
  bad.peek(3);
  bad.peek(0);
  bad.next();
  EXPECT_EQ(once.errorCount(), 1);
}

TEST(VrmlLexer, InvalidUtf8IsReportedOnceAndEndsTheInput) {
  const Lexed l = lex("a b\xff c d \xfe");
  EXPECT_EQ(kindsOf(l),
            (std::vector<TokenKind>{TokenKind::Identifier, TokenKind::Identifier, TokenKind::Invalid, TokenKind::End}));
  EXPECT_EQ(l.tokens[2].text, "0xFF");
  ASSERT_EQ(l.diagnostics.all().size(), 1u);
  EXPECT_EQ(l.diagnostics.all()[0].str(),
            "t.wrl:1:4: error: invalid UTF-8 (byte 0xFF); a scene file must be UTF-8 text");
  // Inside a string the bad byte is reported at itself, and the string is not delivered.
  const Lexed s = lex("\"ab\xc0\xaf\"");
  ASSERT_EQ(s.diagnostics.all().size(), 1u);
  EXPECT_EQ(s.diagnostics.all()[0].loc.column, 4);
  EXPECT_EQ(s.tokens[0].kind, TokenKind::Invalid);
}

TEST(VrmlLexer, DescribeNamesTokensForMessages) {
  EXPECT_EQ(describe(only("radius")), "'radius'");
  EXPECT_EQ(describe(only("1.5")), "'1.5'");
  EXPECT_EQ(describe(only("{")), "'{'");
  EXPECT_EQ(describe(only("}")), "'}'");
  EXPECT_EQ(describe(only("[")), "'['");
  EXPECT_EQ(describe(only("]")), "']'");
  EXPECT_EQ(describe(Token{}), "end of file");
}

TEST(VrmlDiagnosticSink, StopsAtTheCapWithOneNote) {
  Diagnostics d;
  DiagnosticSink sink(d);
  for (int i = 0; i < DiagnosticSink::kMaxErrors - 1; ++i) sink.error({"t", 1, i + 1}, "e");
  EXPECT_FALSE(sink.full());
  sink.warning({"t", 1, 1}, "w");
  sink.error({"t", 2, 1}, "last");
  EXPECT_TRUE(sink.full());
  EXPECT_TRUE(sink.hasErrors());
  sink.error({"t", 3, 1}, "dropped");
  sink.warning({"t", 3, 1}, "dropped too");
  EXPECT_EQ(d.errorCount(), DiagnosticSink::kMaxErrors);
  int notes = 0;
  for (const Diagnostic& x : d.all()) {
    notes += x.severity == Severity::Note ? 1 : 0;
    EXPECT_NE(x.message.find("dropped"), 0u);
  }
  EXPECT_EQ(notes, 1);
  EXPECT_EQ(d.all().back().message, "too many errors; stopping here");
  EXPECT_EQ(d.all().size(), size_t(DiagnosticSink::kMaxErrors) + 2);  // the errors, one warning, one note
}

}  // namespace
}  // namespace imps::vrml
