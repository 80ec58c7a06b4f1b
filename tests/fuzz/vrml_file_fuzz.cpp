// SPDX-License-Identifier: MIT
// libFuzzer target for readVrml and readClips: any bytes (plain or gzip) give a file or diagnostics, never a crash or
// hang; a file that reads has no errors, its ROUTEs name DEF'd nodes, and its node graph is acyclic (PROTO bodies
// included).
#include <cstdint>
#include <set>
#include <string>
#include <string_view>

#include "fuzz_check.h"
#include "imps/vrml_clip.h"
#include "imps/vrml_file.h"

namespace {

// Visits every node once (USE shares nodes); a node met again on the current path would be a cycle.
void walk(const imps::VrmlNode& node, std::set<const imps::VrmlNode*>& path, std::set<const imps::VrmlNode*>& seen) {
  FUZZ_CHECK(!path.contains(&node));
  if (!seen.insert(&node).second) return;
  path.insert(&node);
  for (const imps::VrmlField& f : node.fields) {
    FUZZ_CHECK(f.booleans <= f.numbers.size());
    for (const imps::VrmlNodeRef& child : f.nodes) {
      FUZZ_CHECK(child != nullptr);
      walk(*child, path, seen);
    }
  }
  if (node.protoBody) walk(*node.protoBody, path, seen);
  path.erase(&node);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  imps::Diagnostics warnings;
  const auto file = imps::readVrml(bytes, "fuzz.wrl", &warnings);
  for (const imps::Diagnostic& d : warnings.all()) FUZZ_CHECK(d.severity != imps::Severity::Error);
  if (!file) {
    FUZZ_CHECK(file.error().hasErrors());
    return 0;
  }
  for (const imps::VrmlRoute& r : file->routes) {
    FUZZ_CHECK(file->defs.contains(r.fromNode));
    FUZZ_CHECK(file->defs.contains(r.toNode));
  }
  std::set<const imps::VrmlNode*> path, seen;
  for (const imps::VrmlNodeRef& root : file->roots) walk(*root, path, seen);
  for (const auto& [name, node] : file->defs) {
    FUZZ_CHECK(node->defName == name);
    walk(*node, path, seen);
  }
  // The clips its ROUTEs make: an error result carries an error; every track has as many values as keys.
  const auto clips = imps::readClips(*file);
  if (!clips) {
    FUZZ_CHECK(clips.error().hasErrors());
    return 0;
  }
  for (const imps::Clip& clip : clips->clips) {
    FUZZ_CHECK(clip.cycleInterval > 0.0);
    for (const imps::ClipTrack& t : clip.tracks)
      FUZZ_CHECK(t.keys.size() == t.positions.size() || t.keys.size() == t.rotations.size());
    for (double f : {0.0, 0.37, 1.0}) FUZZ_CHECK(clip.sample(f).size() == clip.rest.size());
  }
  return 0;
}
