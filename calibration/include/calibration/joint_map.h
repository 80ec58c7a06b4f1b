// SPDX-License-Identifier: MIT
// Joint maps: which joint of a motion clip (BVH) drives which joint of a character, when the automatic name rules
// (puppeteer's `--map auto`) do not know the clip's naming. Format and checks in docs/calibration.md ("Joint maps").
#pragma once

#include <expected>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "imps/character.h"
#include "imps/diagnostic.h"

namespace imps::calibration {

inline constexpr int kJointMapVersion = 1;

// One clip joint → one character joint.
struct JointMatch {
  std::string source;     // the clip's joint name
  std::string character;  // the character's joint name
  SourceLoc loc;          // where the file names the pair (the source key); empty when made by rules
};

// Parses {"version": 1, "joints": {"LeftArm": "L_UpperArm", …}}. Every problem is reported as
// `file:line:column: error: …`: syntax, unknown fields, a source joint that is not in `sourceJoints` or a
// character joint that is not in `character` (both with "did you mean"), a character joint driven twice, values that
// are not strings. `sourceJoints` empty / `character` null skip those checks.
std::expected<std::vector<JointMatch>, Diagnostics> parseJointMap(std::string_view json, std::string_view fileName,
                                                                  const std::vector<std::string>& sourceJoints = {},
                                                                  const Character* character = nullptr);
// Reads a file with parseJointMap; an unreadable file gives `path: error: cannot read …`.
std::expected<std::vector<JointMatch>, Diagnostics> readJointMapFile(const std::filesystem::path& path,
                                                                     const std::vector<std::string>& sourceJoints = {},
                                                                     const Character* character = nullptr);

}  // namespace imps::calibration
