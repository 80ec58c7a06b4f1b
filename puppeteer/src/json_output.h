// SPDX-License-Identifier: MIT
// `--json`: every reporting command can print its report as one JSON document on stdout for scripts, instead of
// the text for people. Messages (warnings, errors, progress) still go to stderr; the exit code is the same.
#pragma once

#include <nlohmann/json.hpp>

namespace imps::app {

using Json = nlohmann::ordered_json;

// Prints `report` to stdout, indented, with a final newline. Bytes that are not UTF-8 (a device's name) are
// written as U+FFFD, never thrown on.
void printJson(const Json& report);

}  // namespace imps::app
