// SPDX-License-Identifier: MIT
// `--map` for clips on characters: choosing the joint mapping and telling the user what it did.
#include "map_option.h"

#include <cstdio>

#include "calibration/joint_map.h"

namespace imps::app {

std::optional<RetargetOptions> retargetOptionsFor(const std::string& map, const sim::BvhClip& clip,
                                                  const Character& character) {
  RetargetOptions o;
  if (map == "auto") return o;
  if (map == "names") {
    o.map = RetargetOptions::Map::Names;
    return o;
  }
  std::vector<std::string> names;
  for (const sim::BvhJoint& j : clip.joints) names.push_back(j.name);
  auto matches = calibration::readJointMapFile(map, names, &character);
  if (!matches) {
    std::fputs(matches.error().str().c_str(), stderr);
    return std::nullopt;
  }
  o.map = RetargetOptions::Map::Explicit;
  o.matches = std::move(*matches);
  return o;
}

void printRetargetReport(const std::string& clipName, const std::string& map, const RetargetReport& report) {
  std::printf("puppeteer: retargeting %s (--map %s): %zu of %zu clip joints drive the character\n%s",
              clipName.c_str(), map.c_str(), report.mapped(), report.entries.size(), report.str().c_str());
}

}  // namespace imps::app
