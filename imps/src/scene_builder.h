// SPDX-License-Identifier: MIT
// SceneBuilder: the ParserTarget that checks what the parser reports against the IMPS node types and fills an
// imps::Scene. Private to imps/src; the rules it enforces are listed in docs/scene-format.md.
#pragma once

#include <map>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "imps/scene.h"
#include "scene_parser.h"

namespace imps::vrml {

// A scene is refused when it has more nodes than this, written or copied by USE (the "billion laughs" of DEF/USE).
#ifndef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr size_t kMaxExpandedNodes = 100000;
#else
// Fuzz builds (libFuzzer's convention): every input that reaches the limit pays for the whole expansion, and the
// corpus fills with USE bombs that do (use_bomb.wrl is a seed), so a tenth of the limit keeps the fuzzer fast; the
// code path is the same.
constexpr size_t kMaxExpandedNodes = 10000;
#endif

class SceneBuilder final : public ParserTarget {
 public:
  SceneBuilder(std::string fileName, DiagnosticSink& sink);
  ~SceneBuilder() override;

  void beginNode(const NodeHeader& header) override;
  void endNode(const SourceLoc& closeLoc) override;
  void use(const std::string& name, const SourceLoc& loc) override;
  void null(const SourceLoc& loc) override;
  void field(const std::string& name, const SourceLoc& nameLoc, const FieldValue& value) override;
  void beginNodeField(const std::string& name, const SourceLoc& nameLoc, bool bracketed) override;
  void endNodeField() override;

  // Runs the checks that need the whole file (BlendGroup members, blendParam against the blend in force) when
  // `parsedToEnd`, and hands over the scene. Call once, after parse().
  Scene finish(bool parsedToEnd);

  // The node under construction; monostate for a node that is being skipped after an error.
  using NodeData = std::variant<std::monostate, Tesselator3MPNode, MarchingCubesNode, BlendNode, UniformHash,
                                TransformNode, ShapeNode, Material, BlendGroupNode, TexGenNode, ImageTextureNode>;
  struct FieldSpec;

 private:
  struct Frame;
  // A finished node on its way to its parent's field (or the top level).
  struct Finished {
    NodeData node;
    std::string typeName;
    SourceLoc loc;
    int height = 1;    // nodes on the longest path down from this one, itself included
    size_t count = 1;  // nodes in the subtree, USE copies expanded
    std::vector<SourceLoc> memberLocs;  // BlendGroup: where each member string is
  };
  struct Definition {
    Finished finished;
    SourceLoc loc;
  };

  bool skipping() const;
  void deliver(Finished child);
  void deliverTop(Finished child);
  void storeField(Frame& frame, const FieldSpec& spec, const SourceLoc& nameLoc, const FieldValue& value);
  bool admitField(Frame& frame, const FieldSpec& spec, const SourceLoc& nameLoc);
  void storeStrings(Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const FieldValue& value);
  void storeNumbers(Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const FieldValue& value);
  void mismatch(const Frame& frame, const FieldSpec& spec, const SourceLoc& loc, const std::string& found);
  void checkBlendParams(const SceneNode& node, BlendKind inForce);

  std::string fileName_;
  DiagnosticSink& sink_;
  Scene scene_;
  std::vector<Frame> frames_;
  std::map<std::string, Definition> definitions_;
  std::set<std::string> failedDefinitions_;  // DEFs of nodes that had errors: USE of them is not reported again
  std::set<std::string> memberNames_;        // DEF names of shapes and RigidTransforms (BlendGroup members)
  std::vector<std::vector<SourceLoc>> memberLocs_;  // per scene_.blendGroups entry
  std::string rootType_;
  SourceLoc rootLoc_;
  size_t expandedNodes_ = 0;
};

}  // namespace imps::vrml
