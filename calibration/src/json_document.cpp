// SPDX-License-Identifier: MIT
// A location-tracking JSON reader for the calibration files (see json_document.h).
#include "json_document.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <unordered_map>

#include "imps/file_read.h"
#include "imps/utf8.h"

namespace imps::calibration::detail {

const JsonValue* JsonValue::find(std::string_view key) const {
  for (const Member& m : members)
    if (m.key == key) return &m.value;
  return nullptr;
}

const char* describe(JsonValue::Kind kind) {
  switch (kind) {
    case JsonValue::Kind::Null: return "null";
    case JsonValue::Kind::Bool: return "a boolean";
    case JsonValue::Kind::Number: return "a number";
    case JsonValue::Kind::String: return "a string";
    case JsonValue::Kind::Array: return "an array";
    case JsonValue::Kind::Object: return "an object";
  }
  return "?";
}

namespace {

// Deep nesting is never meaningful in a calibration file; the limit keeps the recursion bounded.
constexpr int kMaxDepth = 64;

class Parser {
 public:
  Parser(std::string_view text, std::string_view file, Diagnostics& diags) : text_(text), file_(file), diags_(diags) {}

  bool document(JsonValue& out) {
    skipSpace();
    if (!value(out, 0)) return false;
    skipSpace();
    if (pos_ < text_.size()) return fail("expected the end of the document after the top-level value");
    return true;
  }

 private:
  SourceLoc here() const { return {std::string(file_), line_, column_}; }
  bool fail(std::string message) {
    diags_.error(here(), std::move(message));
    return false;
  }
  bool atEnd() const { return pos_ >= text_.size(); }
  char peek() const { return text_[pos_]; }
  void advance() {
    if (text_[pos_] == '\n') {
      ++line_;
      column_ = 1;
    } else {
      ++column_;
    }
    ++pos_;
  }
  void skipSpace() {
    while (!atEnd() && (peek() == ' ' || peek() == '\t' || peek() == '\n' || peek() == '\r')) advance();
  }

  bool value(JsonValue& out, int depth) {
    if (atEnd()) return fail("unexpected end of file: expected a value");
    if (depth > kMaxDepth) return fail("values nested too deeply");
    out.loc = here();
    const char c = peek();
    if (c == '{') return object(out, depth);
    if (c == '[') return array(out, depth);
    if (c == '"') {
      out.kind = JsonValue::Kind::String;
      return string(out.string);
    }
    if ((c == '-' && text_.substr(pos_, 2) != "-I") || (c >= '0' && c <= '9')) return number(out);
    if (literal("true")) {
      out.kind = JsonValue::Kind::Bool;
      out.boolean = true;
      return true;
    }
    if (literal("false")) {
      out.kind = JsonValue::Kind::Bool;
      return true;
    }
    if (literal("null")) {
      out.kind = JsonValue::Kind::Null;
      return true;
    }
    if (c == '\'') return fail("strings take double quotes in JSON");
    if (c == 'N' || c == 'I' || (c == '-' && text_.substr(pos_, 2) == "-I"))
      return fail("NaN and infinities are not JSON numbers: write a finite number");
    return fail(std::string("expected a value, found '") + c + "'");
  }

  bool literal(std::string_view word) {
    if (text_.substr(pos_, word.size()) != word) return false;
    for (size_t i = 0; i < word.size(); ++i) advance();
    return true;
  }

  bool object(JsonValue& out, int depth) {
    out.kind = JsonValue::Kind::Object;
    advance();  // {
    skipSpace();
    if (!atEnd() && peek() == '}') {
      advance();
      return true;
    }
    std::unordered_map<std::string, size_t> keys;  // key -> index in out.members
    for (;;) {
      skipSpace();
      if (atEnd()) return fail("unexpected end of file inside an object");
      if (peek() == '}') return fail("expected a key after ',' (JSON has no trailing commas)");
      if (peek() != '"') return fail("expected a key in double quotes");
      JsonValue::Member m;
      m.keyLoc = here();
      if (!string(m.key)) return false;
      // A hash of the keys so far: an object of 100,000 keys is checked in linear time.
      if (const auto [it, fresh] = keys.try_emplace(m.key, out.members.size()); !fresh) {
        diags_.error(m.keyLoc, "duplicate key '" + m.key + "' (first at line " +
                                   std::to_string(out.members[it->second].keyLoc.line) + ")");
        return false;
      }
      skipSpace();
      if (atEnd() || peek() != ':') return fail("expected ':' after key '" + m.key + "'");
      advance();
      skipSpace();
      if (!value(m.value, depth + 1)) return false;
      out.members.push_back(std::move(m));
      skipSpace();
      if (atEnd()) return fail("unexpected end of file inside an object: expected ',' or '}'");
      if (peek() == ',') {
        advance();
        continue;
      }
      if (peek() == '}') {
        advance();
        return true;
      }
      return fail("expected ',' or '}' after a member");
    }
  }

  bool array(JsonValue& out, int depth) {
    out.kind = JsonValue::Kind::Array;
    advance();  // [
    skipSpace();
    if (!atEnd() && peek() == ']') {
      advance();
      return true;
    }
    for (;;) {
      skipSpace();
      if (!atEnd() && peek() == ']') return fail("expected a value after ',' (JSON has no trailing commas)");
      JsonValue item;
      if (!value(item, depth + 1)) return false;
      out.items.push_back(std::move(item));
      skipSpace();
      if (atEnd()) return fail("unexpected end of file inside an array: expected ',' or ']'");
      if (peek() == ',') {
        advance();
        continue;
      }
      if (peek() == ']') {
        advance();
        return true;
      }
      return fail("expected ',' or ']' after an array element");
    }
  }

  static void appendUtf8(std::string& s, uint32_t cp) {
    if (cp < 0x80) {
      s += static_cast<char>(cp);
    } else if (cp < 0x800) {
      s += static_cast<char>(0xC0 | (cp >> 6));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
      s += static_cast<char>(0xE0 | (cp >> 12));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
      s += static_cast<char>(0xF0 | (cp >> 18));
      s += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
      s += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
      s += static_cast<char>(0x80 | (cp & 0x3F));
    }
  }

  bool hex4(uint32_t& out) {
    out = 0;
    for (int i = 0; i < 4; ++i) {
      if (atEnd()) return fail("unexpected end of file in a \\u escape");
      const char c = peek();
      uint32_t d;
      if (c >= '0' && c <= '9') d = static_cast<uint32_t>(c - '0');
      else if (c >= 'a' && c <= 'f') d = static_cast<uint32_t>(c - 'a' + 10);
      else if (c >= 'A' && c <= 'F') d = static_cast<uint32_t>(c - 'A' + 10);
      else return fail("expected four hex digits after \\u");
      out = out * 16 + d;
      advance();
    }
    return true;
  }

  bool string(std::string& out) {
    advance();  // opening quote
    for (;;) {
      if (atEnd()) return fail("unexpected end of file inside a string");
      const char c = peek();
      if (c == '"') {
        advance();
        return true;
      }
      if (c == '\n') return fail("unterminated string (missing '\"' before the end of the line)");
      if (static_cast<unsigned char>(c) < 0x20) return fail("control character inside a string");
      if (c != '\\') {
        out += c;
        advance();
        continue;
      }
      advance();
      if (atEnd()) return fail("unexpected end of file in an escape");
      const char e = peek();
      advance();
      switch (e) {
        case '"': out += '"'; break;
        case '\\': out += '\\'; break;
        case '/': out += '/'; break;
        case 'b': out += '\b'; break;
        case 'f': out += '\f'; break;
        case 'n': out += '\n'; break;
        case 'r': out += '\r'; break;
        case 't': out += '\t'; break;
        case 'u': {
          uint32_t cp;
          if (!hex4(cp)) return false;
          if (cp >= 0xD800 && cp < 0xDC00) {  // a surrogate pair
            uint32_t low;
            if (!literal("\\u") || !hex4(low) || low < 0xDC00 || low >= 0xE000)
              return fail("unpaired UTF-16 surrogate in a \\u escape");
            cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
          } else if (cp >= 0xDC00 && cp < 0xE000) {
            return fail("unpaired UTF-16 surrogate in a \\u escape");
          }
          appendUtf8(out, cp);
          break;
        }
        default: return fail(std::string("unknown escape '\\") + e + "'");
      }
    }
  }

  bool number(JsonValue& out) {
    out.kind = JsonValue::Kind::Number;
    const size_t start = pos_;
    auto digits = [&] {
      size_t n = 0;
      while (!atEnd() && peek() >= '0' && peek() <= '9') {
        advance();
        ++n;
      }
      return n;
    };
    if (peek() == '-') advance();
    if (atEnd() || !(peek() >= '0' && peek() <= '9')) return fail("expected a digit");
    if (peek() == '0') {
      advance();
      if (!atEnd() && peek() >= '0' && peek() <= '9') return fail("numbers may not have leading zeros");
    } else {
      digits();
    }
    bool integral = true;
    if (!atEnd() && peek() == '.') {
      advance();
      integral = false;
      if (digits() == 0) return fail("expected a digit after '.'");
    }
    if (!atEnd() && (peek() == 'e' || peek() == 'E')) {
      advance();
      integral = false;
      if (!atEnd() && (peek() == '+' || peek() == '-')) advance();
      if (digits() == 0) return fail("expected a digit in the exponent");
    }
    const std::string literalText(text_.substr(start, pos_ - start));
    out.number = std::strtod(literalText.c_str(), nullptr);
    out.integral = integral;
    if (!std::isfinite(out.number)) {
      diags_.error(out.loc, "number '" + literalText + "' is out of range");
      return false;
    }
    return true;
  }

  std::string_view text_;
  std::string_view file_;
  Diagnostics& diags_;
  size_t pos_ = 0;
  int line_ = 1;
  int column_ = 1;
};

}  // namespace

bool parseJson(std::string_view text, std::string_view fileName, JsonValue& out, Diagnostics& diags) {
  out = JsonValue{};
  // JSON text is UTF-8 (RFC 8259 section 8.1): a file that is not is refused at its first bad byte, so every string
  // read from it can be written back as JSON.
  if (const size_t bad = firstInvalidUtf8(text); bad < text.size()) {
    const std::string_view before = text.substr(0, bad);
    const size_t lineStart = before.rfind('\n');
    const int line = 1 + static_cast<int>(std::count(before.begin(), before.end(), '\n'));
    const int column = 1 + static_cast<int>(lineStart == std::string_view::npos ? bad : bad - lineStart - 1);
    char byte[8];
    std::snprintf(byte, sizeof byte, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(text[bad])));
    diags.error({std::string(fileName), line, column},
                std::string("invalid UTF-8 (byte ") + byte + "); a JSON file must be UTF-8 text");
    return false;
  }
  return Parser(text, fileName, diags).document(out);
}

std::expected<std::string, Diagnostics> readJsonFileText(const std::filesystem::path& path, std::string_view what) {
  auto text = readFileText(path, kMaxFileBytes);
  if (text) return std::move(*text);
  const std::string& message = text.error().message;
  const std::string reason = !std::filesystem::exists(path) ? std::string("no such file")
                             : message.starts_with("larger")
                                 ? message + "; a " + std::string(what) + " is a few kilobytes"
                                 : std::string("not a readable file");
  Diagnostics d;
  d.error({path.string(), 0, 0}, "cannot read " + std::string(what) + ": " + reason);
  return std::unexpected(d);
}

}  // namespace imps::calibration::detail
