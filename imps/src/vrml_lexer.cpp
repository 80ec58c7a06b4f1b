// SPDX-License-Identifier: MIT
// Lexer for the IMPS VRML 2 dialect: UTF-8 text to tokens with line and column.
#include "vrml_lexer.h"

#include <cctype>
#include <charconv>
#include <cstdio>
#include <system_error>

namespace imps::vrml {

void DiagnosticSink::error(const SourceLoc& loc, std::string message) {
  if (full()) return;
  diagnostics_.error(loc, std::move(message));
  if (full() && !truncated_) {
    truncated_ = true;
    diagnostics_.note(loc, "too many errors; stopping here");
  }
}

void DiagnosticSink::warning(const SourceLoc& loc, std::string message) {
  if (full()) return;
  diagnostics_.warning(loc, std::move(message));
}

std::string describe(const Token& token) {
  switch (token.kind) {
    case TokenKind::Identifier:
    case TokenKind::Number:
    case TokenKind::BadNumber:
    case TokenKind::Invalid: return "'" + token.text + "'";
    case TokenKind::String: return "a string";
    case TokenKind::LeftBrace: return "'{'";
    case TokenKind::RightBrace: return "'}'";
    case TokenKind::LeftBracket: return "'['";
    case TokenKind::RightBracket: return "']'";
    case TokenKind::End: return "end of file";
  }
  return "?";
}

namespace {

bool isIdentifierStart(char c) { return std::isalpha(static_cast<unsigned char>(c)) != 0 || c == '_'; }
bool isIdentifierChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }
// ISO/IEC 14772-1 clause 5.3: IdRestChars exclude control characters, space and `" # ' , . [ \ ] { }`; we keep
// '.' (see Dialect::Vrml97). IdFirstChar further excludes digits, '+' and '-' (and '.').
bool isVrml97IdentifierChar(char c) {
  const auto b = static_cast<unsigned char>(c);
  if (b <= 0x20 || b == 0x7F) return false;
  return c != '"' && c != '#' && c != '\'' && c != ',' && c != '[' && c != '\\' && c != ']' && c != '{' && c != '}';
}
bool isVrml97IdentifierStart(char c) {
  return isVrml97IdentifierChar(c) && std::isdigit(static_cast<unsigned char>(c)) == 0 && c != '+' && c != '-' &&
         c != '.';
}

// A number is scanned as the longest run of these, so `1.2.3` and `1e` are one bad token rather than several.
bool isNumberRunChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '+' || c == '-' || c == '_';
}

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

bool isNonFiniteSpelling(std::string_view s) {
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) s.remove_prefix(1);
  return equalsIgnoreCase(s, "nan") || equalsIgnoreCase(s, "inf") || equalsIgnoreCase(s, "infinity");
}

// [+-]? (digits ('.' digits?)? | '.' digits) ([eE] [+-]? digits)?
bool isWellFormedNumber(std::string_view s) {
  size_t i = 0;
  auto digits = [&] {
    const size_t start = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) != 0) ++i;
    return i - start;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  size_t mantissaDigits = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissaDigits += digits();
  }
  if (mantissaDigits == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == s.size();
}

std::string byteHex(unsigned char b) {
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "0x%02X", b);
  return buffer;
}

}  // namespace

Lexer::Lexer(std::string_view text, std::string fileName, DiagnosticSink& sink, Dialect dialect)
    : text_(text), fileName_(std::move(fileName)), sink_(sink), dialect_(dialect), end_(firstInvalidUtf8(text)) {}

const Token& Lexer::peek(size_t ahead) {
  while (lookahead_.size() <= ahead) lookahead_.push_back(scan());
  return lookahead_[ahead];
}

Token Lexer::next() {
  peek();
  Token token = std::move(lookahead_.front());
  lookahead_.pop_front();
  return token;
}

void Lexer::advance() {
  const char c = text_[pos_++];
  if (c == '\n') {
    ++line_;
    column_ = 1;
  } else if ((static_cast<unsigned char>(c) & 0xC0) != 0x80) {
    ++column_;  // count code points, not bytes
  }
}

void Lexer::skipSpaceAndComments() {
  while (pos_ < end_) {
    const char c = current();
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == ',') {
      advance();
    } else if (c == '#') {
      while (pos_ < end_ && current() != '\n') advance();
    } else {
      return;
    }
  }
}

Token Lexer::scan() {
  skipSpaceAndComments();
  Token token;
  token.line = line_;
  token.column = column_;
  if (pos_ >= end_) {
    if (end_ < text_.size()) {
      token.kind = TokenKind::Invalid;
      token.text = byteHex(static_cast<unsigned char>(text_[end_]));
      sink_.error(loc(token), "invalid UTF-8 (byte " + token.text + "); a scene file must be UTF-8 text");
      end_ = pos_ = text_.size();  // report once; nothing after a bad byte is read
    }
    return token;
  }
  const char c = current();
  switch (c) {
    case '{': token.kind = TokenKind::LeftBrace; break;
    case '}': token.kind = TokenKind::RightBrace; break;
    case '[': token.kind = TokenKind::LeftBracket; break;
    case ']': token.kind = TokenKind::RightBracket; break;
    default: break;
  }
  if (token.kind != TokenKind::End) {
    token.text = std::string(1, c);
    advance();
    return token;
  }
  if (c == '"') return scanString(std::move(token));
  if (std::isdigit(static_cast<unsigned char>(c)) != 0 || c == '+' || c == '-' || c == '.')
    return scanNumberLike(std::move(token));
  const bool vrml97 = dialect_ == Dialect::Vrml97;
  if (vrml97 ? isVrml97IdentifierStart(c) : isIdentifierStart(c)) {
    const size_t start = pos_;
    while (pos_ < end_ && (vrml97 ? isVrml97IdentifierChar(current()) : isIdentifierChar(current()))) advance();
    token.text = std::string(text_.substr(start, pos_ - start));
    token.kind = TokenKind::Identifier;
    if (isNonFiniteSpelling(token.text)) {
      token.kind = TokenKind::BadNumber;
      sink_.error(loc(token), "'" + token.text + "' is not a finite number");
    }
    return token;
  }
  // A stray character: name it readably (one whole UTF-8 character, or a control byte in hex).
  const size_t start = pos_;
  advance();
  while (pos_ < end_ && (static_cast<unsigned char>(current()) & 0xC0) == 0x80) advance();
  token.kind = TokenKind::Invalid;
  const auto b = static_cast<unsigned char>(c);
  if (b < 0x20 || b == 0x7F) {
    token.text = byteHex(b);
    sink_.error(loc(token), "unexpected control character " + token.text + "; a scene file must be text");
  } else {
    token.text = std::string(text_.substr(start, pos_ - start));
    sink_.error(loc(token), "unexpected character '" + token.text + "'");
  }
  return token;
}

Token Lexer::scanNumberLike(Token token) {
  const size_t start = pos_;
  while (pos_ < end_ && isNumberRunChar(current())) advance();
  token.text = std::string(text_.substr(start, pos_ - start));
  token.kind = TokenKind::BadNumber;
  if (isNonFiniteSpelling(token.text)) {
    sink_.error(loc(token), "'" + token.text + "' is not a finite number");
    return token;
  }
  if (!isWellFormedNumber(token.text)) {
    sink_.error(loc(token), "malformed number '" + token.text + "'");
    return token;
  }
  std::string_view digits = token.text;
  if (digits[0] == '+') digits.remove_prefix(1);  // from_chars takes no '+'
  double value = 0.0;
  const auto result = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (result.ec != std::errc() || result.ptr != digits.data() + digits.size()) {
    sink_.error(loc(token), "number '" + token.text + "' is out of range");
    return token;
  }
  token.kind = TokenKind::Number;
  return token;
}

Token Lexer::scanString(Token token) {
  advance();  // the opening quote
  token.kind = TokenKind::String;
  while (true) {
    if (pos_ >= end_) {
      if (end_ < text_.size()) return scan();  // reports the bad UTF-8 byte
      token.kind = TokenKind::Invalid;
      token.text = "\"";
      sink_.error(loc(token), "unterminated string (it starts here)");
      return token;
    }
    const char c = current();
    if (c == '"') {
      advance();
      return token;
    }
    if (c == '\\') {
      advance();
      if (pos_ >= end_) continue;  // reported above as unterminated
      token.text += current();     // VRML: a backslash makes the next character literal (\" and \\)
      advance();
      continue;
    }
    const auto b = static_cast<unsigned char>(c);
    if ((b < 0x20 && c != '\t' && c != '\n' && c != '\r') || b == 0x7F) {
      Token bad;
      bad.kind = TokenKind::Invalid;
      bad.line = line_;
      bad.column = column_;
      bad.text = byteHex(b);
      sink_.error(loc(bad), "control character " + bad.text + " in a string; a scene file must be text");
      advance();
      return bad;
    }
    token.text += c;
    advance();
  }
}

}  // namespace imps::vrml
