// SPDX-License-Identifier: MIT
// Props attached to joints (see prop_attachment.h).
#include "prop_attachment.h"

#include <cmath>
#include <stdexcept>

#include "imps/vrml_file.h"
#include "imps/vrml_props.h"

namespace imps::app {

std::expected<std::vector<AttachedProp>, Diagnostics> loadProps(const std::vector<std::string>& specs,
                                                                const Character& character, Diagnostics* warnings) {
  std::vector<AttachedProp> out;
  for (const std::string& spec : specs) {
    const size_t at = spec.rfind('@');
    const std::string path = at == std::string::npos ? spec : spec.substr(0, at);
    const std::string joint = at == std::string::npos ? std::string() : spec.substr(at + 1);
    const int j = joint.empty() ? -1 : character.findJoint(joint);
    if (!joint.empty() && j < 0)
      return std::unexpected(singleError({"puppeteer"}, "--prop " + spec + ": the scene has no joint '" + joint + "'"));
    Diagnostics diagnostics;
    auto file = readVrmlFile(path, &diagnostics);
    if (!file) return std::unexpected(file.error());
    for (Prop& p : readProps(*file, &diagnostics)) out.push_back({p.name, std::move(p.mesh), j});
    if (warnings != nullptr) warnings->append(diagnostics);
  }
  return out;
}

std::expected<std::pair<std::string, Grab>, Diagnostics> parseGrab(const std::string& spec,
                                                                   const Character& character) {
  auto refuse = [&](const std::string& why) {
    return std::unexpected(singleError({"puppeteer"}, "--grab " + spec + ": " + why));
  };
  const size_t times = spec.rfind('@');
  const size_t joint = times == std::string::npos || times == 0 ? std::string::npos : spec.rfind('@', times - 1);
  const size_t colon = times == std::string::npos ? std::string::npos : spec.find(':', times);
  if (joint == std::string::npos || colon == std::string::npos)
    return refuse("expected FILE.wrl@JOINT@PICK:DROP (seconds)");
  Grab grab;
  const std::string name = spec.substr(joint + 1, times - joint - 1);
  grab.joint = character.findJoint(name);
  if (grab.joint < 0) return refuse("the scene has no joint '" + name + "'");
  try {
    size_t used = 0;
    const std::string pick = spec.substr(times + 1, colon - times - 1), drop = spec.substr(colon + 1);
    grab.pickSeconds = std::stod(pick, &used);
    if (used != pick.size()) throw std::invalid_argument(pick);
    grab.dropSeconds = std::stod(drop, &used);
    if (used != drop.size()) throw std::invalid_argument(drop);
  } catch (const std::exception&) {
    return refuse("PICK and DROP must be numbers of seconds");
  }
  if (!(grab.pickSeconds >= 0.0) || !(grab.pickSeconds <= grab.dropSeconds) || !std::isfinite(grab.dropSeconds))
    return refuse("expected 0 <= PICK <= DROP");
  return std::pair{spec.substr(0, joint), grab};
}

void appendPosedProps(Mesh& mesh, const std::vector<AttachedProp>& props, const SkeletonCache& skeleton) {
  for (const AttachedProp& p : props)
    appendMesh(mesh, p.joint >= 0 ? transformed(p.mesh, skeleton.world(p.joint)) : p.mesh);
}

}  // namespace imps::app
