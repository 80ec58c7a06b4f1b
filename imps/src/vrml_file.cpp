// SPDX-License-Identifier: MIT
// The VRML 97 reader: ISO/IEC 14772-1 syntax into a generic node tree (see vrml_file.h). Based on: ISO/IEC
// 14772-1:1997 clause 5 (syntax) and Annex A (grammar); H-Anim 1.1 for the PROTO use it has to support.
#include "imps/vrml_file.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <set>
#include <utility>

#include "imps/file_read.h"
#include "imps/gzip.h"
#include "scene_parser.h"  // kMaxNesting
#include "vrml_lexer.h"

namespace imps {

namespace {

using vrml::DiagnosticSink;
using vrml::Token;
using vrml::TokenKind;

constexpr size_t kMaxFileBytes = size_t{256} << 20;
// The most values one field holds: 4,000,000 numbers is a Coordinate of 1.3 million points, far beyond a prop or
// a clip, and caps a field at 32 MB however its numbers are written ("0 0 0 …" costs 2 bytes a value on disk).
constexpr size_t kMaxFieldValues = 4'000'000;
constexpr std::string_view kHeader = "#VRML V2.0 utf8";

constexpr std::array<std::string_view, 54> kVrml97Nodes = {
    "Anchor", "Appearance", "AudioClip", "Background", "Billboard", "Box", "Collision", "Color",
    "ColorInterpolator", "Cone", "Coordinate", "CoordinateInterpolator", "Cylinder", "CylinderSensor",
    "DirectionalLight", "ElevationGrid", "Extrusion", "Fog", "FontStyle", "Group", "ImageTexture", "IndexedFaceSet",
    "IndexedLineSet", "Inline", "LOD", "Material", "MovieTexture", "NavigationInfo", "Normal", "NormalInterpolator",
    "OrientationInterpolator", "PixelTexture", "PlaneSensor", "PointLight", "PointSet", "PositionInterpolator",
    "ProximitySensor", "ScalarInterpolator", "Script", "Shape", "Sound", "Sphere", "SphereSensor", "SpotLight",
    "Switch", "Text", "TextureCoordinate", "TextureTransform", "TimeSensor", "TouchSensor", "Transform", "Viewpoint",
    "VisibilitySensor", "WorldInfo"};

bool isDeclarationKeyword(const std::string& s) {
  return s == "field" || s == "exposedField" || s == "eventIn" || s == "eventOut";
}
bool isReserved(const std::string& s) {
  return s == "DEF" || s == "USE" || s == "NULL" || s == "TRUE" || s == "FALSE" || s == "IS" || s == "ROUTE" ||
         s == "TO" || s == "PROTO" || s == "EXTERNPROTO";
}
bool isBool(const Token& t) { return t.kind == TokenKind::Identifier && (t.text == "TRUE" || t.text == "FALSE"); }
bool isScalar(const Token& t) {
  return t.kind == TokenKind::Number || t.kind == TokenKind::BadNumber || t.kind == TokenKind::String || isBool(t);
}
std::string position(const SourceLoc& loc) { return std::to_string(loc.line) + ":" + std::to_string(loc.column); }

// A mutable node while the file is read; frozen into VrmlNodeRef when it closes.
using NodePtr = std::shared_ptr<VrmlNode>;

// A field of a PROTO body still to be substituted: `bodyField IS interfaceField`.
struct IsMark {
  const VrmlNode* node;  // the template node holding it
  std::string bodyField;
  std::string interfaceField;
};

// A PROTO as declared: its interface (defaults by field name) and its body's nodes, still holding IS marks.
struct ProtoDecl {
  std::string name;
  SourceLoc loc;
  bool external = false;
  std::map<std::string, VrmlField, std::less<>> defaults;  // field/exposedField defaults; eventIn/eventOut empty
  std::vector<NodePtr> body;
  std::vector<IsMark> marks;
  std::vector<NodePtr> parsed;  // every node read in the body, kept so IsMark::node stays unique
};

// PROTO instances are expanded by copying their body: at most this many copied nodes per file, so a small file
// cannot ask for a huge expansion (a body of N nodes instantiated M times copies N*M).
#if defined(FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION)
constexpr size_t kMaxProtoCopies = 100'000;
#else
constexpr size_t kMaxProtoCopies = 5'000'000;
#endif

class Reader {
 public:
  Reader(std::string_view text, const std::string& fileName, DiagnosticSink& sink)
      : lexer_(text, fileName, sink, vrml::Dialect::Vrml97), sink_(sink) {
    file_.fileName = fileName;
  }

  // file := statement* ; statement := node | PROTO | EXTERNPROTO | ROUTE
  VrmlFile read() {
    Scope top;
    scope_ = &top;
    while (!stopped_ && !sink_.full()) {
      const Token& t = lexer_.peek();
      if (t.kind == TokenKind::End) break;
      if (t.kind == TokenKind::RightBrace || t.kind == TokenKind::RightBracket) {
        fail(t, "unexpected " + vrml::describe(t) + " at top level: nothing is open here");
        break;
      }
      if (parseStatement(0, &file_.roots)) continue;
      if (!stopped_)
        fail(lexer_.peek(), "expected a node, PROTO or ROUTE at top level, found " + vrml::describe(lexer_.peek()));
    }
    checkRoutes(top);
    file_.routes = std::move(top.routes);
    for (auto& [name, node] : top.defs) file_.defs.emplace(name, node);
    return std::move(file_);
  }

 private:
  // DEF names and ROUTEs of the file, or of one PROTO body (names there are local to it).
  struct Scope {
    std::map<std::string, NodePtr, std::less<>> defs;
    std::vector<VrmlRoute> routes;
    ProtoDecl* proto = nullptr;  // the PROTO whose body this is
  };

  void fail(const Token& at, std::string message) {
    if (at.kind != TokenKind::Invalid && at.kind != TokenKind::BadNumber)
      sink_.error(lexer_.loc(at), std::move(message));
    stopped_ = true;
  }

  bool startsNode(size_t ahead) {
    const Token& t = lexer_.peek(ahead);
    if (t.kind != TokenKind::Identifier) return false;
    if (t.text == "DEF" || t.text == "USE" || t.text == "NULL") return true;
    return !isReserved(t.text) && lexer_.peek(ahead + 1).kind == TokenKind::LeftBrace;
  }

  bool expectName(const char* what, std::string& name) {
    const Token t = lexer_.next();
    if (t.kind != TokenKind::Identifier || isReserved(t.text)) {
      fail(t, std::string("expected a name after ") + what + ", found " + vrml::describe(t));
      return false;
    }
    name = t.text;
    return true;
  }

  bool expect(TokenKind kind, const char* what, const std::string& context) {
    const Token t = lexer_.next();
    if (t.kind == kind) return true;
    fail(t, std::string("expected ") + what + " " + context + ", found " + vrml::describe(t));
    return false;
  }

  // A statement where nodes may appear (top level, a PROTO body, an MFNode list: exporters put ROUTEs there).
  // Appends a node to `nodes`; returns false when the next token starts no statement (nothing consumed).
  bool parseStatement(int depth, std::vector<VrmlNodeRef>* nodes, std::vector<NodePtr>* mutableNodes = nullptr) {
    const Token& t = lexer_.peek();
    if (t.kind != TokenKind::Identifier) return false;
    if (t.text == "ROUTE") return parseRoute(), true;
    if (t.text == "PROTO" || t.text == "EXTERNPROTO") return parseProto(depth), true;
    if (!startsNode(0)) return false;
    NodePtr node = parseNode(depth);
    if (node) {
      if (mutableNodes != nullptr) mutableNodes->push_back(node);
      if (nodes != nullptr) nodes->push_back(node);
    }
    return true;
  }

  // ROUTE name.field TO name.field
  void parseRoute() {
    const Token keyword = lexer_.next();
    VrmlRoute route;
    route.loc = lexer_.loc(keyword);
    if (!parseRouteEnd(route.fromNode, route.fromField)) return;
    const Token to = lexer_.next();
    if (to.kind != TokenKind::Identifier || to.text != "TO") {
      fail(to, "expected 'TO' in ROUTE, found " + vrml::describe(to));
      return;
    }
    if (!parseRouteEnd(route.toNode, route.toField)) return;
    scope_->routes.push_back(std::move(route));
  }

  bool parseRouteEnd(std::string& node, std::string& field) {
    const Token t = lexer_.next();
    const size_t dot = t.kind == TokenKind::Identifier ? t.text.find('.') : std::string::npos;
    if (dot == std::string::npos || dot == 0 || dot + 1 == t.text.size() ||
        t.text.find('.', dot + 1) != std::string::npos) {
      fail(t, "expected 'NodeName.fieldName' in ROUTE, found " + vrml::describe(t));
      return false;
    }
    node = t.text.substr(0, dot);
    field = t.text.substr(dot + 1);
    return true;
  }

  // PROTO Name [ declarations ] { body } | EXTERNPROTO Name [ declarations ] urls
  void parseProto(int depth) {
    const Token keyword = lexer_.next();
    ProtoDecl decl;
    decl.external = keyword.text == "EXTERNPROTO";
    decl.loc = lexer_.loc(keyword);
    if (!expectName(keyword.text.c_str(), decl.name)) return;
    if (!expect(TokenKind::LeftBracket, "'['", "after " + keyword.text + " " + decl.name)) return;
    while (!stopped_ && lexer_.peek().kind != TokenKind::RightBracket) {
      const Token kind = lexer_.next();
      if (kind.kind != TokenKind::Identifier || !isDeclarationKeyword(kind.text)) {
        fail(kind, "expected 'field', 'exposedField', 'eventIn', 'eventOut' or ']' in " + decl.name + ", found " +
                       vrml::describe(kind));
        return;
      }
      std::string type, name;
      if (!expectName(kind.text.c_str(), type) || !expectName(type.c_str(), name)) return;
      VrmlField value;
      value.name = name;
      value.loc = lexer_.loc(kind);
      const bool hasValue = !decl.external && (kind.text == "field" || kind.text == "exposedField");
      if (hasValue && !parseValue(value, depth + 1, decl.name)) return;
      decl.defaults.insert_or_assign(name, std::move(value));
    }
    lexer_.next();  // ']'
    if (decl.external) {
      VrmlField urls;
      if (!parseValue(urls, depth + 1, decl.name)) return;
    } else {
      if (!expect(TokenKind::LeftBrace, "'{'", "to open the body of PROTO " + decl.name)) return;
      Scope body;
      body.proto = &decl;
      Scope* outer = std::exchange(scope_, &body);
      while (!stopped_ && !sink_.full() && lexer_.peek().kind != TokenKind::RightBrace) {
        if (lexer_.peek().kind == TokenKind::End) {
          fail(lexer_.peek(), "unexpected end of file inside PROTO " + decl.name);
          break;
        }
        if (!parseStatement(depth + 1, nullptr, &decl.body)) {
          fail(lexer_.peek(), "expected a node, PROTO or ROUTE in PROTO " + decl.name + ", found " +
                                  vrml::describe(lexer_.peek()));
        }
      }
      scope_ = outer;
      if (stopped_) return;
      lexer_.next();  // '}'
      checkRoutes(body);
      if (decl.body.empty()) sink_.warning(decl.loc, "PROTO " + decl.name + " has no nodes in its body");
    }
    if (depth == 0) file_.protos.push_back(decl.name);
    std::string name = decl.name;
    protos_.insert_or_assign(std::move(name), std::make_shared<ProtoDecl>(std::move(decl)));
  }

  // node := USE name | NULL | [DEF name] Type { body }. Returns null for NULL, an unknown type or an error.
  NodePtr parseNode(int depth) {
    const Token first = lexer_.next();
    if (first.text == "NULL") return nullptr;
    if (first.text == "USE") {
      std::string name;
      if (!expectName("USE", name)) return nullptr;
      if (auto found = scope_->defs.find(name); found != scope_->defs.end()) return found->second;
      sink_.error(lexer_.loc(first),
                  "USE " + name + ": no node is DEF'd with that name before here" +
                      (openDefs_.contains(name) ? " (a node cannot USE itself or an ancestor)" : ""));
      return nullptr;
    }
    auto node = std::make_shared<VrmlNode>();
    if (scope_->proto != nullptr) scope_->proto->parsed.push_back(node);
    Token type = first;
    if (first.text == "DEF") {
      if (!expectName("DEF", node->defName)) return nullptr;
      type = lexer_.next();
    }
    if (type.kind != TokenKind::Identifier || isReserved(type.text)) {
      fail(type, "expected a node type, found " + vrml::describe(type));
      return nullptr;
    }
    node->type = type.text;
    node->loc = lexer_.loc(type);
    if (!expect(TokenKind::LeftBrace, "'{'", "after node type '" + type.text + "'")) return nullptr;
    if (depth + 1 > vrml::kMaxNesting) {
      fail(type, "nodes nested deeper than " + std::to_string(vrml::kMaxNesting) + " levels");
      return nullptr;
    }
    if (!node->defName.empty()) openDefs_.insert(node->defName);
    parseBody(*node, depth + 1);
    if (!node->defName.empty()) openDefs_.erase(node->defName);
    if (stopped_) return nullptr;

    const auto proto = protos_.find(node->type);
    if (proto == protos_.end() && !isVrml97NodeType(node->type)) {
      const std::string key = node->type + "@" + std::to_string(node->loc.line);
      if (warnedUnknown_.insert(key).second)
        sink_.warning(node->loc,
                      "unknown node type '" + node->type + "' skipped (not VRML 97 and no PROTO declares it)");
      return nullptr;
    }
    if (proto != protos_.end()) instantiate(*proto->second, *node);
    if (!node->defName.empty()) {
      if (scope_->defs.contains(node->defName))
        sink_.warning(node->loc, "DEF " + node->defName + " redefined; USE and ROUTE see this node from here on");
      scope_->defs.insert_or_assign(node->defName, node);
    }
    return node;
  }

  // body := (fieldName value | fieldName IS name | declaration | ROUTE | PROTO)* '}'
  void parseBody(VrmlNode& node, int depth) {
    while (!stopped_ && !sink_.full()) {
      const Token& t = lexer_.peek();
      if (t.kind == TokenKind::RightBrace) {
        lexer_.next();
        return;
      }
      if (t.kind == TokenKind::End) {
        fail(t,
             "unexpected end of file inside " + node.type + ": its '{' at " + position(node.loc) + " is never closed");
        return;
      }
      if (t.kind == TokenKind::Identifier && (t.text == "ROUTE" || t.text == "PROTO" || t.text == "EXTERNPROTO")) {
        parseStatement(depth, nullptr);
        continue;
      }
      if (t.kind != TokenKind::Identifier || isReserved(t.text)) {
        fail(t, "expected a field name or '}' in " + node.type + ", found " + vrml::describe(t));
        return;
      }
      const Token name = lexer_.next();
      if (isDeclarationKeyword(name.text)) {  // Script's interface: `field SFFloat x 1`, `eventIn SFTime y`
        parseDeclaration(node, name, depth);
        continue;
      }
      parseField(node, name.text, lexer_.loc(name), depth);
    }
    stopped_ = true;
  }

  void parseDeclaration(VrmlNode& node, const Token& kind, int depth) {
    std::string type, name;
    if (!expectName(kind.text.c_str(), type) || !expectName(type.c_str(), name)) return;
    if (kind.text == "field" || kind.text == "exposedField") parseField(node, name, lexer_.loc(kind), depth);
    else if (lexer_.peek().kind == TokenKind::Identifier && lexer_.peek().text == "IS")
      parseField(node, name, lexer_.loc(kind), depth);
  }

  void parseField(VrmlNode& node, const std::string& name, const SourceLoc& loc, int depth) {
    const Token& t = lexer_.peek();
    if (t.kind == TokenKind::Identifier && t.text == "IS") {
      lexer_.next();
      std::string interfaceName;
      if (!expectName("IS", interfaceName)) return;
      if (scope_->proto == nullptr) {
        sink_.error(loc, "'" + name + " IS " + interfaceName + "' outside a PROTO body");
        return;
      }
      if (!scope_->proto->defaults.contains(interfaceName)) {
        sink_.error(loc, "'" + name + " IS " + interfaceName + "': PROTO " + scope_->proto->name +
                             " declares no field or event '" + interfaceName + "'");
        return;
      }
      scope_->proto->marks.push_back({&node, name, interfaceName});
      return;
    }
    VrmlField field;
    field.name = name;
    field.loc = loc;
    if (!parseValue(field, depth, node.type)) return;
    const auto same =
        std::find_if(node.fields.begin(), node.fields.end(), [&](const VrmlField& f) { return f.name == name; });
    if (same != node.fields.end()) {
      sink_.warning(loc, "field '" + name + "' of " + node.type + " given twice (also at " + position(same->loc) +
                             "); the last value counts");
      *same = std::move(field);
    } else {
      node.fields.push_back(std::move(field));
    }
  }

  // value := scalar+ | '[' scalar* ']' | node | '[' (node | ROUTE)* ']'
  bool parseValue(VrmlField& field, int depth, const std::string& context) {
    const Token& t = lexer_.peek();
    field.valueLoc = lexer_.loc(t);
    if (t.kind == TokenKind::LeftBracket) {
      const Token open = lexer_.next();
      const Token& inside = lexer_.peek();
      if (startsNode(0) || (inside.kind == TokenKind::Identifier && inside.text == "ROUTE")) {
        field.nodeValued = true;
        while (!stopped_ && !sink_.full() && parseStatement(depth, &field.nodes)) {}
      } else {
        readScalars(field);
      }
      if (stopped_) return false;
      const Token& close = lexer_.peek();
      if (close.kind == TokenKind::RightBracket) {
        lexer_.next();
        return true;
      }
      if (close.kind == TokenKind::End)
        fail(close, "unexpected end of file: the '[' at " + position(lexer_.loc(open)) + " is never closed");
      else
        fail(close,
             "expected ']' to close the '[' at " + position(lexer_.loc(open)) + ", found " + vrml::describe(close));
      return false;
    }
    if (startsNode(0)) {
      field.nodeValued = true;
      if (NodePtr node = parseNode(depth)) field.nodes.push_back(node);
      return !stopped_;
    }
    if (isScalar(t)) {
      readScalars(field);
      return true;
    }
    fail(t, "expected a value for field '" + field.name + "' of " + context + ", found " + vrml::describe(t));
    return false;
  }

  // Reads a run of scalars into the field, at most kMaxFieldValues of them: past that one error is reported and the
  // rest of the run is read and dropped, so one huge list costs bounded memory.
  void readScalars(VrmlField& field) {
    size_t count = 0;
    while (isScalar(lexer_.peek())) {
      const Token t = lexer_.next();
      if (++count <= kMaxFieldValues) {
        addScalar(field, t);
      } else if (count == kMaxFieldValues + 1) {
        sink_.error(lexer_.loc(t), "field '" + field.name + "' has more than " + std::to_string(kMaxFieldValues) +
                                       " values; the reader's limit per field (docs/world-format.md)");
      }
    }
  }

  static void addScalar(VrmlField& field, const Token& t) {
    if (t.kind == TokenKind::String) {
      field.strings.push_back(t.text);
    } else if (t.kind == TokenKind::Number) {
      std::string_view digits = t.text;
      if (digits[0] == '+') digits.remove_prefix(1);
      double value = 0.0;
      std::from_chars(digits.data(), digits.data() + digits.size(), value);  // checked by the lexer
      field.numbers.push_back(value);
    } else if (t.kind == TokenKind::Identifier) {
      field.numbers.push_back(t.text == "TRUE" ? 1.0 : 0.0);
      ++field.booleans;
    }
    // BadNumber: already an error
  }

  // Every ROUTE of a scope names nodes DEF'd in it.
  void checkRoutes(const Scope& scope) {
    for (const VrmlRoute& r : scope.routes) {
      for (const std::string* name : {&r.fromNode, &r.toNode}) {
        if (!scope.defs.contains(*name)) {
          std::vector<std::string> known;
          for (const auto& [def, node] : scope.defs) known.push_back(def);
          const std::string guess = closestMatch(*name, known);
          sink_.error(r.loc, "ROUTE names '" + *name + "', which no node is DEF'd as" +
                                 (guess.empty() ? std::string() : " (did you mean '" + guess + "'?)"));
        }
      }
    }
  }

  // The instance's PROTO body: the body's first node, cloned with every IS replaced (H-Anim's Joint, Segment,
  // Humanoid). Clones share nothing with the template except nodes given as field values.
  void instantiate(const ProtoDecl& decl, VrmlNode& instance) {
    for (const VrmlField& f : instance.fields) {
      if (!decl.defaults.contains(f.name))
        sink_.warning(f.loc, "PROTO " + decl.name + " declares no field '" + f.name + "'; it is ignored");
    }
    if (decl.external || decl.body.empty()) return;
    std::map<const VrmlNode*, NodePtr> copies;
    instance.protoBody = cloneTemplate(decl, *decl.body.front(), instance, copies);
  }

  // Copies `from` and its descendants once each (a USE in the body stays one shared node).
  NodePtr cloneTemplate(const ProtoDecl& decl, const VrmlNode& from, VrmlNode& instance,
                        std::map<const VrmlNode*, NodePtr>& copies) {
    if (auto done = copies.find(&from); done != copies.end()) return done->second;
    if (++protoCopies_ > kMaxProtoCopies) {
      if (protoCopies_ == kMaxProtoCopies + 1)
        sink_.error(instance.loc, "PROTO instances expand to more than " + std::to_string(kMaxProtoCopies) + " nodes");
      return std::make_shared<VrmlNode>(VrmlNode{from.type, from.defName, from.loc, {}, nullptr, {}});
    }
    auto copy = std::make_shared<VrmlNode>();
    copies.emplace(&from, copy);
    copy->type = from.type;
    copy->defName = from.defName;
    copy->loc = from.loc;
    copy->protoBody = from.protoBody;
    copy->isLinks = from.isLinks;
    for (const VrmlField& f : from.fields) {
      VrmlField field = f;
      if (f.nodeValued) {
        for (VrmlNodeRef& child : field.nodes) child = cloneTemplate(decl, *child, instance, copies);
      }
      copy->fields.push_back(std::move(field));
    }
    for (const IsMark& mark : decl.marks) {
      if (mark.node != &from) continue;
      instance.isLinks.push_back({mark.interfaceField, copy, mark.bodyField});
      const VrmlField* given = instance.field(mark.interfaceField);
      const auto fallback = decl.defaults.find(mark.interfaceField);
      const VrmlField* value = given != nullptr ? given : &fallback->second;
      if (!value->nodeValued && value->numbers.empty() && value->strings.empty()) continue;  // an event, or []
      VrmlField substituted = *value;
      substituted.name = mark.bodyField;
      copy->fields.push_back(std::move(substituted));
    }
    return copy;
  }

  vrml::Lexer lexer_;
  DiagnosticSink& sink_;
  VrmlFile file_;
  Scope* scope_ = nullptr;
  std::map<std::string, std::shared_ptr<ProtoDecl>, std::less<>> protos_;
  std::set<std::string> warnedUnknown_;
  std::set<std::string> openDefs_;
  size_t protoCopies_ = 0;
  bool stopped_ = false;
};

bool checkHeader(std::string_view text, const std::string& fileName, DiagnosticSink& sink) {
  const SourceLoc start{fileName, 1, 1};
  std::string_view line = text.substr(0, text.find('\n'));
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.starts_with(kHeader) &&
      (line.size() == kHeader.size() || line[kHeader.size()] == ' ' || line[kHeader.size()] == '\t'))
    return true;
  if (line.starts_with("#VRML V1.0"))
    sink.error(start, "VRML 1.0 is not supported; the first line must be '" + std::string(kHeader) + "' (VRML 97)");
  else
    sink.error(start, "missing header: the first line of a VRML 97 file must be '" + std::string(kHeader) + "'");
  return false;
}

std::string hexByte(char c) {
  const auto b = static_cast<unsigned char>(c);
  return {"0123456789ABCDEF"[b >> 4], "0123456789ABCDEF"[b & 15]};
}

// ISO-8859-1 to UTF-8: every byte is the code point of the same value.
std::string latin1ToUtf8(std::string_view text) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (const char c : text) {
    const auto b = static_cast<unsigned char>(c);
    if (b < 0x80) {
      out += c;
    } else {
      out += static_cast<char>(0xC0 | (b >> 6));
      out += static_cast<char>(0x80 | (b & 0x3F));
    }
  }
  return out;
}

SourceLoc locOfOffset(std::string_view text, size_t offset, const std::string& fileName) {
  SourceLoc loc{fileName, 1, 1};
  for (size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++loc.line;
      loc.column = 1;
    } else if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) {
      ++loc.column;
    }
  }
  return loc;
}

}  // namespace

bool isVrml97NodeType(std::string_view name) {
  return std::find(kVrml97Nodes.begin(), kVrml97Nodes.end(), name) != kVrml97Nodes.end();
}

const VrmlField* VrmlNode::field(std::string_view name) const {
  for (const VrmlField& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}

const VrmlNode& VrmlNode::resolved() const {
  const VrmlNode* node = this;
  while (node->protoBody) node = node->protoBody.get();
  return *node;
}

std::expected<VrmlFile, Diagnostics> readVrml(std::string_view bytes, const std::string& fileName,
                                              Diagnostics* warnings) {
  Diagnostics diagnostics;
  DiagnosticSink sink(diagnostics);
  std::string inflated;
  if (isGzip(bytes)) {
    auto limit = inputLimitBytes(kMaxFileBytes);
    if (!limit) {
      diagnostics.error({fileName, 0, 0}, "cannot decompress: " + limit.error().all().front().message);
      return std::unexpected(std::move(diagnostics));
    }
    auto text = gunzip(bytes, *limit);
    if (!text) {
      diagnostics.error({fileName, 0, 0}, "cannot decompress: " + text.error().all().front().message);
      return std::unexpected(std::move(diagnostics));
    }
    inflated = std::move(*text);
    bytes = inflated;
  }
  if (bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);
  std::string recoded;
  if (const size_t bad = firstInvalidUtf8(bytes); bad < bytes.size()) {
    sink.warning(locOfOffset(bytes, bad, fileName),
                 "not UTF-8 (byte 0x" + hexByte(bytes[bad]) +
                     "); the file is read as ISO-8859-1, as 3D Studio MAX wrote it");
    recoded = latin1ToUtf8(bytes);
    bytes = recoded;
  }
  VrmlFile file;
  if (checkHeader(bytes, fileName, sink)) file = Reader(bytes, fileName, sink).read();
  if (warnings != nullptr) {
    for (const Diagnostic& d : diagnostics.all()) {
      if (d.severity == Severity::Warning) warnings->warning(d.loc, d.message);
      else if (d.severity == Severity::Note) warnings->note(d.loc, d.message);
    }
  }
  if (diagnostics.hasErrors()) return std::unexpected(std::move(diagnostics));
  return file;
}

std::expected<VrmlFile, Diagnostics> readVrmlFile(const std::string& path, Diagnostics* warnings) {
  auto bytes = readFileText(path, kMaxFileBytes);
  if (!bytes) {
    Diagnostics diagnostics;
    diagnostics.error({path, 0, 0}, "cannot read VRML file: " + bytes.error().message);
    return std::unexpected(std::move(diagnostics));
  }
  return readVrml(*bytes, path, warnings);
}

}  // namespace imps
