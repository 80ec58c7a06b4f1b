// SPDX-License-Identifier: MIT
// libFuzzer target for the check-pose JSON reader (calibration/offset_calibration): any bytes give targets or
// diagnostics, never a crash; targets name joints of the character and carry finite angles.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "calibration/offset_calibration.h"
#include "fuzz_check.h"
#include "imps/character.h"
#include "imps/scene_reader.h"

namespace {

// A small hierarchical character: joints Pelvis, L_Leg, R_Leg.
const imps::Character& character() {
  static const imps::Character c = [] {
    auto scene = imps::readScene(
        "#VRML V2.0 utf8\n"
        "MarchingCubes { sceneGraph DEF Pelvis RigidTransform { children [\n"
        "  Metaball { radius 0.2 }\n"
        "  DEF L_Leg RigidTransform { translation 0.1 -0.2 0 children [ Metaball { radius 0.1 } ] }\n"
        "  DEF R_Leg RigidTransform { translation -0.1 -0.2 0 children [ Metaball { radius 0.1 } ] }\n"
        "] } }\n",
        "character.wrl");
    FUZZ_CHECK(scene.has_value());
    auto built = imps::Character::fromScene(*scene);
    FUZZ_CHECK(built.has_value());
    return std::move(*built);
  }();
  return c;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const imps::Character* c : {static_cast<const imps::Character*>(nullptr), &character()}) {
    auto targets = imps::calibration::parseCheckPose(text, "fuzz.json", c);
    if (!targets) {
      FUZZ_CHECK(targets.error().hasErrors());
      continue;
    }
    for (const imps::calibration::PoseTarget& t : *targets) {
      FUZZ_CHECK(std::isfinite(t.angle));
      if (c) FUZZ_CHECK(c->findJoint(t.joint) >= 0);
    }
  }
  return 0;
}
