// SPDX-License-Identifier: MIT
// The IMPS VRML 2 parser: checks the syntax and reports what it reads to a ParserTarget, without knowing what the
// nodes mean (pbrt-v4's ParserTarget). Private to imps/src; the grammar is in docs/scene-format.md.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "vrml_lexer.h"

namespace imps::vrml {

// Files may nest nodes at most this deep (a Tesselator3MP holding a RigidTransform holding a Metaball is 3).
constexpr int kMaxNesting = 200;

// A field's value holds at most this many numbers, strings or booleans (each is kept with its spelling and
// position until the target has checked it, ~50 bytes apiece); longer lists are an error, read past and dropped.
constexpr size_t kMaxFieldItems = 1'000'000;

// A field's value when it is not nodes: the run of numbers, strings and TRUE/FALSE after the field name, or the
// contents of `[ ... ]`. The parser does not know field types; the target checks count and kinds.
struct FieldValue {
  std::vector<Token> items;  // Number, BadNumber, String, or Identifier TRUE/FALSE
  bool bracketed = false;
  SourceLoc loc;  // where the value starts
};

// `[DEF name] Type {`: what the parser knows about a node when it opens.
struct NodeHeader {
  std::string type;
  SourceLoc typeLoc;
  std::string defName;  // empty without DEF
  SourceLoc defLoc;     // where DEF is; equals typeLoc without DEF
};

// Receives a file's structure in order. Node-valued fields arrive as beginNodeField, then one beginNode..endNode,
// use or null per node, then endNodeField. Calls nest properly even when the parser stops early at a syntax
// error (open nodes are then never ended). Errors the target finds go to its own DiagnosticSink.
class ParserTarget {
 public:
  virtual ~ParserTarget() = default;
  virtual void beginNode(const NodeHeader& header) = 0;
  virtual void endNode(const SourceLoc& closeLoc) = 0;
  virtual void use(const std::string& name, const SourceLoc& loc) = 0;
  virtual void null(const SourceLoc& loc) = 0;
  virtual void field(const std::string& name, const SourceLoc& nameLoc, const FieldValue& value) = 0;
  virtual void beginNodeField(const std::string& name, const SourceLoc& nameLoc, bool bracketed) = 0;
  virtual void endNodeField() = 0;
};

// Parses a whole file, header line included, reporting syntax errors to `sink`. Returns true when the file was
// read to its end; false when a syntax error (a missing or extra bracket, a premature end of file, nesting deeper
// than kMaxNesting, a stray character) or a full sink stopped it, in which case the target saw only a prefix.
// Bad numbers are reported but do not stop the parse: they reach the target as BadNumber items.
bool parse(std::string_view text, const std::string& fileName, ParserTarget& target, DiagnosticSink& sink);

}  // namespace imps::vrml
