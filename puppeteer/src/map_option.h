// SPDX-License-Identifier: MIT
// `--map auto|names|FILE.json` for commands that put a BVH clip on a character (replay, export).
#pragma once

#include <optional>
#include <string>

#include "imps/character.h"
#include "retarget.h"
#include "sim/bvh.h"

namespace imps::app {

// The retargeting options for `--map VALUE`: "auto" (name rules + hierarchy), "names" (joints of the same name), or
// a joint map file checked against the clip's joints and the character's (docs/calibration.md, "Joint maps").
// Prints the file's diagnostics to stderr and returns nullopt on errors (exit kExitInvalidInput).
std::optional<RetargetOptions> retargetOptionsFor(const std::string& map, const sim::BvhClip& clip,
                                                  const Character& character);

// Prints "puppeteer: retargeting …: N of M clip joints drive the character" and the report (stdout).
void printRetargetReport(const std::string& clipName, const std::string& map, const RetargetReport& report);

}  // namespace imps::app
