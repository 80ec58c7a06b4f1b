// SPDX-License-Identifier: MIT
// Joint map files: clip joint → character joint, parsed with source locations and checked against both skeletons.
#include "calibration/joint_map.h"

#include <algorithm>

#include "json_document.h"
#include "object_reader.h"

namespace imps::calibration {

using detail::JsonValue;
using detail::ObjectReader;

namespace {

void unknownName(const SourceLoc& loc, const std::string& what, const std::string& name,
                 const std::vector<std::string>& known, Diagnostics& diags) {
  std::string message = "unknown " + what + " '" + name + "'";
  const std::string guess = closestMatch(name, known);
  if (!guess.empty()) message += "; did you mean '" + guess + "'?";
  diags.error(loc, message);
}

}  // namespace

std::expected<std::vector<JointMatch>, Diagnostics> parseJointMap(std::string_view json, std::string_view fileName,
                                                                  const std::vector<std::string>& sourceJoints,
                                                                  const Character* character) {
  Diagnostics diags;
  JsonValue root;
  if (!detail::parseJson(json, fileName, root, diags)) return std::unexpected(diags);
  if (root.kind != JsonValue::Kind::Object) {
    diags.error(root.loc, std::string("a joint map must be a JSON object, not ") + detail::describe(root.kind));
    return std::unexpected(diags);
  }
  ObjectReader r(root, "the joint map", {"version", "joints"}, diags);
  if (const JsonValue* v = r.typed("version", JsonValue::Kind::Number, "a number")) {
    if (!v->integral || v->number < 1) diags.error(v->loc, "'version' must be a positive integer");
    else if (v->number > kJointMapVersion)
      diags.error(v->loc, "file format version " + detail::integerText(v->number) +
                              " is newer than this program reads (" + std::to_string(kJointMapVersion) +
                              "); update puppeteer");
  } else if (!r.get("version")) {
    r.missing("version");
  }
  std::vector<std::string> characterJoints;
  if (character)
    for (const Joint& j : character->joints()) characterJoints.push_back(j.name);
  std::vector<JointMatch> out;
  if (const JsonValue* joints = r.typed("joints", JsonValue::Kind::Object, "an object")) {
    for (const JsonValue::Member& m : joints->members) {
      if (m.value.kind != JsonValue::Kind::String) {
        diags.error(m.value.loc, "the character joint for '" + m.key + "' must be a string, not " +
                                     detail::describe(m.value.kind));
        continue;
      }
      bool ok = true;
      if (!sourceJoints.empty() && std::find(sourceJoints.begin(), sourceJoints.end(), m.key) == sourceJoints.end()) {
        unknownName(m.keyLoc, "clip joint", m.key, sourceJoints, diags);
        ok = false;
      }
      if (character && character->findJoint(m.value.string) < 0) {
        unknownName(m.value.loc, "character joint", m.value.string, characterJoints, diags);
        ok = false;
      }
      for (const JointMatch& earlier : out)
        if (earlier.character == m.value.string) {
          diags.error(m.value.loc, "character joint '" + m.value.string + "' is already driven by '" + earlier.source +
                                       "' (line " + std::to_string(earlier.loc.line) + "): one clip joint per joint");
          ok = false;
        }
      if (ok) out.push_back({m.key, m.value.string, m.keyLoc});
    }
  } else if (!r.get("joints")) {
    r.missing("joints");
  }
  if (diags.hasErrors()) return std::unexpected(diags);
  return out;
}

std::expected<std::vector<JointMatch>, Diagnostics> readJointMapFile(const std::filesystem::path& path,
                                                                     const std::vector<std::string>& sourceJoints,
                                                                     const Character* character) {
  auto text = detail::readJsonFileText(path, "joint map");
  if (!text) return std::unexpected(text.error());
  return parseJointMap(*text, path.string(), sourceJoints, character);
}

}  // namespace imps::calibration
