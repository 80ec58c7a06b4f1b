// SPDX-License-Identifier: MIT
// Tokens of the IMPS VRML 2 dialect (docs/scene-format.md): identifiers, numbers, strings and brackets, each with
// its line and column. Private to imps/src.
#pragma once

#include <deque>
#include <string>
#include <string_view>

#include "imps/diagnostic.h"
#include "imps/utf8.h"

namespace imps::vrml {

// Collects the diagnostics of one read and stops accepting errors after kMaxErrors (a "too many errors" note
// is added once), so a hopeless file gives a readable report. Not thread-safe; one per read.
class DiagnosticSink {
 public:
  static constexpr int kMaxErrors = 50;

  explicit DiagnosticSink(Diagnostics& diagnostics) : diagnostics_(diagnostics) {}
  void error(const SourceLoc& loc, std::string message);
  void warning(const SourceLoc& loc, std::string message);
  // True once kMaxErrors errors were reported: callers stop reading.
  bool full() const { return diagnostics_.errorCount() >= kMaxErrors; }
  bool hasErrors() const { return diagnostics_.hasErrors(); }

 private:
  Diagnostics& diagnostics_;
  bool truncated_ = false;
};

enum class TokenKind {
  Identifier,  // node types, field names, DEF names and the keywords DEF USE NULL TRUE FALSE
  Number,      // a well-formed decimal number (its spelling is kept: ints and floats differ)
  BadNumber,   // a malformed, non-finite or out-of-range number; already reported
  String,      // text: the contents with escapes decoded
  LeftBrace,
  RightBrace,
  LeftBracket,
  RightBracket,
  End,      // end of input
  Invalid,  // a stray character or an unterminated string; already reported
};

struct Token {
  TokenKind kind = TokenKind::End;
  std::string text;
  int line = 0;
  int column = 0;  // in UTF-8 code points, from 1
};

// How a token is named in messages: 'radius', '1.5', a string, '{', end of file.
std::string describe(const Token& token);

// Which identifiers a lexer accepts. Imps: the scene dialect's C-like names ([A-Za-z_][A-Za-z0-9_]*). Vrml97: the
// names of ISO/IEC 14772 clause 5 as DCC exporters write them (3D Studio MAX's `Box01-POS-INTERP`, UTF-8 letters):
// any printable character except `" # ' , [ \ ] { }` and white space, not starting with a digit, '+', '-' or '.';
// a '.' inside a name is kept so `Node.field` (ROUTE) is one token, split by the reader.
enum class Dialect { Imps, Vrml97 };

// Splits a whole file into tokens. Commas, whitespace and `#` comments separate tokens and are dropped. Lexical
// errors are reported to the sink when the bad token is produced and come back as BadNumber or Invalid tokens.
// Invalid UTF-8 is reported once, at the first bad byte, and ends the input there. `text` must outlive the lexer.
class Lexer {
 public:
  Lexer(std::string_view text, std::string fileName, DiagnosticSink& sink, Dialect dialect = Dialect::Imps);

  // The token `ahead` positions after the next one (0: the next one), without consuming anything.
  const Token& peek(size_t ahead = 0);
  Token next();
  SourceLoc loc(const Token& token) const { return {fileName_, token.line, token.column}; }

 private:
  Token scan();
  void skipSpaceAndComments();
  Token scanNumberLike(Token token);
  Token scanString(Token token);
  char current() const { return pos_ < end_ ? text_[pos_] : '\0'; }
  void advance();

  std::string_view text_;
  std::string fileName_;
  DiagnosticSink& sink_;
  Dialect dialect_ = Dialect::Imps;
  std::deque<Token> lookahead_;
  size_t pos_ = 0;
  size_t end_ = 0;  // the first invalid UTF-8 byte, or the text's size
  int line_ = 1;
  int column_ = 1;
};

using imps::firstInvalidUtf8;  // imps/utf8.h

}  // namespace imps::vrml
