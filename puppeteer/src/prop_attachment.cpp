// Props attached to joints (see prop_attachment.h).
#include "prop_attachment.h"

#include "imps/vrml_file.h"
#include "imps/vrml_props.h"

namespace imps::app {

std::expected<std::vector<AttachedProp>, std::string> loadProps(const std::vector<std::string>& specs,
                                                                const Character& character, std::string* warnings) {
  std::vector<AttachedProp> out;
  for (const std::string& spec : specs) {
    const size_t at = spec.rfind('@');
    const std::string path = at == std::string::npos ? spec : spec.substr(0, at);
    const std::string joint = at == std::string::npos ? std::string() : spec.substr(at + 1);
    const int j = joint.empty() ? -1 : character.findJoint(joint);
    if (!joint.empty() && j < 0) return std::unexpected("puppeteer: error: --prop " + spec + ": the scene has no joint '" + joint + "'\n");
    Diagnostics diagnostics;
    auto file = readVrmlFile(path, &diagnostics);
    if (!file) return std::unexpected(file.error().str());
    for (Prop& p : readProps(*file, &diagnostics)) out.push_back({p.name, std::move(p.mesh), j});
    if (warnings != nullptr) *warnings += diagnostics.str();
  }
  return out;
}

void appendPosedProps(Mesh& mesh, const std::vector<AttachedProp>& props, const SkeletonCache& skeleton) {
  for (const AttachedProp& p : props) appendMesh(mesh, p.joint >= 0 ? transformed(p.mesh, skeleton.world(p.joint)) : p.mesh);
}

}  // namespace imps::app
