// SPDX-License-Identifier: MIT
// The bundled example characters (examples/*.wrl), loaded once per test binary.
#pragma once

#include <string>

#include "imps/character.h"

namespace imps::test {

// The character of examples/<name>.wrl, compiled once and kept for the whole run. Fails the calling test (and
// aborts) when the example does not load.
const Character& exampleCharacter(const std::string& name);

}  // namespace imps::test
