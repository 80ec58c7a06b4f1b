// SPDX-License-Identifier: MIT
// Parser for the IMPS VRML 2 dialect: syntax only, reported to a ParserTarget (see scene_parser.h).
#include "scene_parser.h"

namespace imps::vrml {

namespace {

constexpr std::string_view kHeader = "#VRML V2.0 utf8";

bool isKeyword(const std::string& s) {
  return s == "DEF" || s == "USE" || s == "NULL" || s == "TRUE" || s == "FALSE";
}
bool isBool(const Token& t) { return t.kind == TokenKind::Identifier && (t.text == "TRUE" || t.text == "FALSE"); }
bool isScalar(const Token& t) {
  return t.kind == TokenKind::Number || t.kind == TokenKind::BadNumber || t.kind == TokenKind::String || isBool(t);
}

std::string position(const SourceLoc& loc) { return std::to_string(loc.line) + ":" + std::to_string(loc.column); }

class Parser {
 public:
  Parser(std::string_view text, const std::string& fileName, ParserTarget& target, DiagnosticSink& sink)
      : lexer_(text, fileName, sink), target_(target), sink_(sink) {}

  // file := header node*
  bool parseFile() {
    while (!stopped_) {
      const Token& t = lexer_.peek();
      if (t.kind == TokenKind::End) return true;
      if (startsNode(0)) {
        parseNode(0);
      } else if (t.kind == TokenKind::RightBrace || t.kind == TokenKind::RightBracket) {
        fail(t, "unexpected " + describe(t) + " at top level: nothing is open here");
      } else {
        fail(t, "expected a node at top level, found " + describe(t));
      }
    }
    return false;
  }

 private:
  // Stops the parse. Invalid and BadNumber tokens were reported by the lexer already.
  void fail(const Token& at, std::string message) {
    if (at.kind != TokenKind::Invalid && at.kind != TokenKind::BadNumber)
      sink_.error(lexer_.loc(at), std::move(message));
    stopped_ = true;
  }

  // Does the token `ahead` positions on start a node: DEF, USE, NULL, or `Type {`?
  bool startsNode(size_t ahead) {
    const Token& t = lexer_.peek(ahead);
    if (t.kind != TokenKind::Identifier || t.text == "TRUE" || t.text == "FALSE") return false;
    if (t.text == "DEF" || t.text == "USE" || t.text == "NULL") return true;
    return lexer_.peek(ahead + 1).kind == TokenKind::LeftBrace;
  }

  // Reads an identifier that names something (a DEF/USE name), not a keyword.
  bool expectName(const char* what, std::string& name, SourceLoc& loc) {
    Token t = lexer_.next();
    if (t.kind != TokenKind::Identifier || isKeyword(t.text)) {
      fail(t, std::string("expected a name after ") + what + ", found " + describe(t));
      return false;
    }
    name = t.text;
    loc = lexer_.loc(t);
    return true;
  }

  // node := 'USE' name | 'NULL' | ['DEF' name] Type '{' (fieldName value)* '}'
  // `depth` counts the nodes already open around this one.
  void parseNode(int depth) {
    Token first = lexer_.next();
    if (first.text == "USE") {
      std::string name;
      SourceLoc loc;
      if (expectName("USE", name, loc)) target_.use(name, lexer_.loc(first));
      return;
    }
    if (first.text == "NULL") {
      target_.null(lexer_.loc(first));
      return;
    }
    NodeHeader header;
    header.defLoc = lexer_.loc(first);
    Token type = first;
    if (first.text == "DEF") {
      SourceLoc nameLoc;
      if (!expectName("DEF", header.defName, nameLoc)) return;
      type = lexer_.next();
    }
    if (type.kind != TokenKind::Identifier || isKeyword(type.text)) {
      fail(type, "expected a node type, found " + describe(type));
      return;
    }
    header.type = type.text;
    header.typeLoc = lexer_.loc(type);
    const Token open = lexer_.next();
    if (open.kind != TokenKind::LeftBrace) {
      fail(open, "expected '{' after node type '" + type.text + "', found " + describe(open));
      return;
    }
    if (depth + 1 > kMaxNesting) {
      fail(type, "nodes nested deeper than " + std::to_string(kMaxNesting) + " levels");
      return;
    }
    target_.beginNode(header);
    while (!stopped_ && !sink_.full()) {
      const Token& t = lexer_.peek();
      if (t.kind == TokenKind::RightBrace) {
        const Token close = lexer_.next();
        target_.endNode(lexer_.loc(close));
        return;
      }
      if (t.kind == TokenKind::End) {
        fail(t, "unexpected end of file inside " + type.text + ": the '{' at " + position(lexer_.loc(open)) +
                    " is never closed");
        return;
      }
      if (t.kind != TokenKind::Identifier || isKeyword(t.text)) {
        fail(t, "expected a field name or '}' in " + type.text + ", found " + describe(t));
        return;
      }
      const Token name = lexer_.next();
      parseFieldValue(name, depth + 1);
    }
    stopped_ = true;
  }

  // value := scalar+ | '[' scalar* ']' | node | '[' node* ']'
  void parseFieldValue(const Token& name, int depth) {
    const SourceLoc nameLoc = lexer_.loc(name);
    const Token& t = lexer_.peek();
    if (t.kind == TokenKind::LeftBracket) {
      const Token open = lexer_.next();
      const Token& inside = lexer_.peek();
      if (startsNode(0)) {
        target_.beginNodeField(name.text, nameLoc, true);
        while (!stopped_ && startsNode(0)) parseNode(depth);
        if (!stopped_) expectClose(open, false);
        target_.endNodeField();
        return;
      }
      FieldValue value;
      value.bracketed = true;
      value.loc = lexer_.loc(inside);
      const bool kept = readScalars(value);
      if (!expectClose(open, !value.items.empty())) return;
      if (kept) target_.field(name.text, nameLoc, value);
      return;
    }
    if (startsNode(0)) {
      target_.beginNodeField(name.text, nameLoc, false);
      parseNode(depth);
      target_.endNodeField();
      return;
    }
    if (isScalar(t)) {
      FieldValue value;
      value.loc = lexer_.loc(t);
      if (readScalars(value)) target_.field(name.text, nameLoc, value);
      return;
    }
    fail(t, "expected a value for field '" + name.text + "', found " + describe(t));
  }

  // Reads the run of scalars into value.items, at most kMaxFieldItems of them: past that one error is reported and
  // the rest of the run is read and dropped, so one huge list costs bounded memory. False when the list was cut.
  bool readScalars(FieldValue& value) {
    bool cut = false;
    while (isScalar(lexer_.peek())) {
      if (value.items.size() < kMaxFieldItems) {
        value.items.push_back(lexer_.next());
        continue;
      }
      const Token extra = lexer_.next();
      if (!cut)
        sink_.error(lexer_.loc(extra), "a value of more than " + std::to_string(kMaxFieldItems) +
                                           " items; the format's limit per field (docs/scene-format.md)");
      cut = true;
    }
    return !cut;
  }

  // Consumes the ']' closing the list opened at `open`, or says why it is missing.
  bool expectClose(const Token& open, bool afterValues) {
    const Token& t = lexer_.peek();
    if (t.kind == TokenKind::RightBracket) {
      lexer_.next();
      return true;
    }
    if (afterValues && startsNode(0)) {
      fail(t, "a list holds either values or nodes, not both");
    } else if (t.kind == TokenKind::End) {
      fail(t, "unexpected end of file: the '[' at " + position(lexer_.loc(open)) + " is never closed");
    } else {
      fail(t, "expected ']' to close the '[' at " + position(lexer_.loc(open)) + ", found " + describe(t));
    }
    return false;
  }

  Lexer lexer_;
  ParserTarget& target_;
  DiagnosticSink& sink_;
  bool stopped_ = false;
};

// The header line: `#VRML V2.0 utf8`, then optionally whitespace and anything (a comment).
bool checkHeader(std::string_view text, const std::string& fileName, DiagnosticSink& sink) {
  const SourceLoc start{fileName, 1, 1};
  std::string_view line = text.substr(0, text.find('\n'));
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.starts_with(kHeader) &&
      (line.size() == kHeader.size() || line[kHeader.size()] == ' ' || line[kHeader.size()] == '\t'))
    return true;
  if (line.starts_with("#VRML")) {
    std::string_view shown = line.substr(0, 40);
    bool printable = firstInvalidUtf8(shown) == shown.size();
    for (char c : shown) printable = printable && (static_cast<unsigned char>(c) >= 0x20 && c != 0x7F);
    sink.error(start,
               (printable ? "unsupported header '" + std::string(shown) + "'" : std::string("unsupported header")) +
                   "; the first line must be '" + std::string(kHeader) + "'");
    return false;
  }
  std::string message = "missing header: the first line must be '" + std::string(kHeader) + "'";
  const size_t later = text.find(kHeader);
  if (later != std::string_view::npos && later < 4096) {
    int lineNumber = 1;
    for (size_t i = 0; i < later; ++i) lineNumber += text[i] == '\n' ? 1 : 0;
    if (lineNumber > 1) message += " (it is on line " + std::to_string(lineNumber) + "; nothing may come before it)";
  }
  sink.error(start, std::move(message));
  return false;
}

}  // namespace

bool parse(std::string_view text, const std::string& fileName, ParserTarget& target, DiagnosticSink& sink) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // a UTF-8 byte order mark is not a character
  if (!checkHeader(text, fileName, sink)) return false;
  Parser parser(text, fileName, target, sink);
  return parser.parseFile();
}

}  // namespace imps::vrml
