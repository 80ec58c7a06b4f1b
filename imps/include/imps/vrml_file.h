// SPDX-License-Identifier: MIT
// Reading VRML 97 files as DCC tools export them (3D Studio MAX, Blender, H-Anim humanoids) into a generic node tree:
// the syntax of ISO/IEC 14772-1 with DEF/USE, ROUTE, PROTO/EXTERNPROTO and gzip compression. What the nodes mean
// (transforms, shapes, animation clips) is read from this tree by imps/world.h. docs/world-format.md.
//
// This is a separate reader from the IMPS character parser (imps/scene_reader.h): a world file may hold any node,
// so node types it does not know are skipped with a warning, where in a character they are errors.
#pragma once

#include <expected>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "imps/diagnostic.h"

namespace imps {

struct VrmlNode;
// Nodes are shared: a USE is the DEF'd node itself, as in VRML. Never cyclic (a node cannot USE itself or an
// ancestor: a DEF name is defined when its node closes).
using VrmlNodeRef = std::shared_ptr<const VrmlNode>;

// One field of a node as written: either values (numbers, strings, TRUE/FALSE) or nodes. The reader does not know
// field types; imps/world.h checks counts and kinds for the fields it uses.
struct VrmlField {
  std::string name;
  SourceLoc loc;                      // where the field name is
  SourceLoc valueLoc;                 // where its value starts
  bool nodeValued = false;            // an SFNode/MFNode value (possibly an empty list or NULL)
  std::vector<double> numbers;        // every number in order; TRUE/FALSE are 1/0 here too
  std::vector<std::string> strings;   // every string in order
  size_t booleans = 0;                // how many of `numbers` were TRUE/FALSE
  std::vector<VrmlNodeRef> nodes;     // the nodes in order; NULL gives no entry
};

// An event link of a PROTO instance: the instance's interface field `interfaceField` is the body node's field
// `bodyField` (an `IS`), so a ROUTE to the instance's field reaches that body node.
struct VrmlIsLink {
  std::string interfaceField;
  VrmlNodeRef bodyNode;
  std::string bodyField;
};

struct VrmlNode {
  std::string type;     // "Transform", or a PROTO's name for an instance of it ("Joint")
  std::string defName;  // empty without DEF
  SourceLoc loc;        // where the node type is
  std::vector<VrmlField> fields;
  // For an instance of a PROTO declared in the file: the PROTO body's first node with every `IS` replaced by the
  // instance's field value (or the PROTO's default), and where the instance's fields went. Null for a built-in
  // node and for an EXTERNPROTO instance (its body is in another file, which is not fetched).
  VrmlNodeRef protoBody;
  std::vector<VrmlIsLink> isLinks;

  // The field called `name`, or null. A field written twice is reported by the reader; the last one counts.
  const VrmlField* field(std::string_view name) const;
  // The node a renderer would see: the PROTO body for an instance (repeatedly, through nested PROTOs), else itself.
  const VrmlNode& resolved() const;
};

// `ROUTE fromNode.fromField TO toNode.toField`, names as written (set_/_changed prefixes and suffixes kept).
struct VrmlRoute {
  std::string fromNode, fromField, toNode, toField;
  SourceLoc loc;
};

// A whole file: its top-level nodes, its top-level ROUTEs (each checked to name DEF'd nodes) and its DEF names
// (the last node DEF'd with a name, as USE and ROUTE see it at the end of the file).
struct VrmlFile {
  std::string fileName;
  std::vector<VrmlNodeRef> roots;
  std::vector<VrmlRoute> routes;
  std::map<std::string, VrmlNodeRef, std::less<>> defs;
  std::vector<std::string> protos;  // PROTO and EXTERNPROTO names declared at top level, in order
};

// Is `name` one of the 54 node types of VRML 97 (ISO/IEC 14772-1 clause 6)?
bool isVrml97NodeType(std::string_view name);

// Reads a VRML 97 file from `bytes`, which may be gzip-compressed (as .wrl files were often served; decompressed
// up to 256 MiB). The first line must be `#VRML V2.0 utf8`. Text that is not UTF-8 is read as ISO-8859-1 with one
// warning (3D Studio MAX wrote names in the system code page under a utf8 header).
//
// Unknown node types (neither VRML 97 nor a PROTO/EXTERNPROTO declared before) are skipped with one warning per
// type and line; their fields are still checked for syntax. Errors (syntax, USE or ROUTE of an undefined name,
// `IS` outside a PROTO body, nesting deeper than 200 nodes, a bad number) make the result an error carrying every
// diagnostic as `file:line:column: error: ...`, at most 50 errors. Warnings go to `warnings` when it is not null,
// on success and on failure alike. Never throws for bad input (only std::bad_alloc), never crashes or hangs.
// Thread-safe: calls share no state.
std::expected<VrmlFile, Diagnostics> readVrml(std::string_view bytes, const std::string& fileName,
                                              Diagnostics* warnings = nullptr);

// readVrml on the file at `path`. A file that cannot be read (missing, a directory, larger than 256 MiB) gives one
// diagnostic `path: error: cannot read VRML file: reason`.
std::expected<VrmlFile, Diagnostics> readVrmlFile(const std::string& path, Diagnostics* warnings = nullptr);

}  // namespace imps
