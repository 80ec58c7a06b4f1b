// SPDX-License-Identifier: MIT
// Checks for the modeller's headless app test (modeller_app_test.sh), from the scene files alone and the app's
// first camera (modeller.h's initialOrbit, as the app frames a scene):
//   modeller_check handle SCENE W H TARGET                 prints "CX,CY TX,TY": the target's handle centre and
//                                                           the tip of its x axis, in window pixels
//   modeller_check moved SCENE SAVED W H TARGET X Y        the target in SAVED lies under pixel (X, Y) of SCENE's
//                                                           first view (within 0.5 px), at the same depth
//   modeller_check radius SAVED PRIMITIVE R                the metaball's radius in SAVED is R (within 1e-4 R)
// TARGET: a primitive's name, NAME.point1 / NAME.point2 for a LineSeg's endpoints, or joint:N for joint N.
// Exit 0 when the check holds, 1 (with a message) otherwise.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>

#include "imps/character.h"
#include "imps/scene_reader.h"
#include "modeller.h"

namespace {

using namespace imps;
using namespace imps::app;

std::unique_ptr<ViewerPipeline> load(const std::string& path) {
  auto scene = readSceneFile(path);
  if (!scene) {
    std::fprintf(stderr, "%s", scene.error().str().c_str());
    std::exit(1);
  }
  auto character = Character::fromScene(*scene);
  if (!character) {
    std::fprintf(stderr, "%s", character.error().str().c_str());
    std::exit(1);
  }
  PipelineOptions o;
  o.polygonizer = Polygonizer::MarchingCubes;
  return std::make_unique<ViewerPipeline>(std::move(*scene), std::move(*character), o);
}

ScreenView viewOf(const ViewerPipeline& pipeline, int w, int h) {
  float radius = 1.0f;
  const OrbitCamera orbit = initialOrbit(pipeline, w, h, &radius);
  return screenView(orbit.camera(), w, h, radius);
}

Handle handleOf(const ViewerPipeline& pipeline, const std::string& target) {
  Modeller m(const_cast<ViewerPipeline&>(pipeline));
  EditTarget t;
  if (target.rfind("joint:", 0) == 0) {
    t = {EditTarget::Kind::Joint, std::atoi(target.c_str() + 6)};
    m.selectJoint(t.index);
  } else {
    // NAME, NAME.point1 or NAME.point2 (a LineSeg's endpoints).
    std::string name = target;
    EditTarget::Kind kind = EditTarget::Kind::Primitive;
    for (const auto& [suffix, k] : {std::pair{".point1", EditTarget::Kind::Endpoint1},
                                    std::pair{".point2", EditTarget::Kind::Endpoint2}})
      if (name.size() > 7 && name.ends_with(suffix)) name.resize(name.size() - 7), kind = k;
    const auto& prims = pipeline.character().primitives();
    for (size_t i = 0; i < prims.size(); ++i)
      if (prims[i].name == name) t = {kind, int(i)};
    if (t.index >= 0 && prims[size_t(t.index)].joint >= 0) m.selectJoint(prims[size_t(t.index)].joint);
  }
  for (const Handle& h : m.handles())
    if (h.target == t) return h;
  std::fprintf(stderr, "modeller_check: no handle for '%s'\n", target.c_str());
  std::exit(1);
}

int fail(const char* what) {
  std::fprintf(stderr, "modeller_check: FAIL: %s\n", what);
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "handle" && argc == 6) {
    auto p = load(argv[2]);
    const int w = std::atoi(argv[3]), h = std::atoi(argv[4]);
    const Handle handle = handleOf(*p, argv[5]);
    HandleLayout layout;
    if (!handleLayout(viewOf(*p, w, h), handle.origin, handle.frame, Modeller::kHandlePixels, &layout))
      return fail("the handle is behind the camera");
    std::printf("%.2f,%.2f %.2f,%.2f\n", double(layout.center.x), double(layout.center.y), double(layout.tips[0].x),
                double(layout.tips[0].y));
    return 0;
  }
  if (command == "moved" && argc == 9) {
    auto before = load(argv[2]);
    auto after = load(argv[3]);
    const int w = std::atoi(argv[4]), h = std::atoi(argv[5]);
    const ScreenView view = viewOf(*before, w, h);
    const Handle a = handleOf(*before, argv[6]), b = handleOf(*after, argv[6]);
    glm::vec2 pixel;
    if (!projectToWindow(view, b.origin, &pixel)) return fail("the moved target is behind the camera");
    const glm::vec2 expected(std::atof(argv[7]), std::atof(argv[8]));
    std::printf("modeller_check: %s moved from %.4g %.4g %.4g to %.4g %.4g %.4g, at pixel %.2f,%.2f (dragged to "
                "%.2f,%.2f)\n",
                argv[6], double(a.origin.x), double(a.origin.y), double(a.origin.z), double(b.origin.x),
                double(b.origin.y), double(b.origin.z), double(pixel.x), double(pixel.y), double(expected.x),
                double(expected.y));
    if (glm::length(pixel - expected) > 0.5f) return fail("the target is not where it was dragged");
    if (std::fabs(glm::dot(b.origin - a.origin, view.towardsViewer)) > 1e-4f) return fail("the depth changed");
    if (glm::length(b.origin - a.origin) < 1e-3f) return fail("the target did not move");
    return 0;
  }
  if (command == "radius" && argc == 5) {
    auto p = load(argv[2]);
    for (const CharacterPrimitive& prim : p->character().primitives()) {
      if (prim.name != argv[3]) continue;
      const float want = float(std::atof(argv[4]));
      std::printf("modeller_check: %s radius %.6g (want %.6g)\n", argv[3], double(prim.local.radius), double(want));
      return std::fabs(prim.local.radius - want) <= 1e-4f * want ? 0 : fail("wrong radius");
    }
    return fail("no such primitive");
  }
  std::fprintf(stderr, "usage: modeller_check handle|moved|radius ... (see the source)\n");
  return 2;
}
