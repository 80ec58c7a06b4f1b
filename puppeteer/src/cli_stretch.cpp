// SPDX-License-Identifier: MIT
// `puppeteer stretch`: paint a dot on a joint, bend it and bring it back, and report how far the dot moved over the
// skin in the projective and the carried texture modes (issue 11; texture_stretch.h).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli.h"
#include "json_output.h"
#include "texture_stretch.h"

namespace imps::app {
namespace {

struct StretchArgs {
  std::string scene;
  std::string mode = "both";
  StretchOptions options;
  std::vector<float> axis, direction;
  int threads = -1;
  bool json = false;
};

const char* modeName(TextureMode m) { return m == TextureMode::Carried ? "carried" : "projective"; }

Json vec(const glm::vec3& v) { return Json::array({v.x, v.y, v.z}); }

int runStretch(StretchArgs& a) {
  // The pictures' directory is checked before any work, as every command checks its outputs (docs/cli.md).
  if (!a.options.pictures.empty())
    if (int rc = checkOutputPath("stretch", "--pictures", a.options.pictures); rc != kExitOk) return rc;
  const auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  if (a.axis.size() == 3) a.options.axis = {a.axis[0], a.axis[1], a.axis[2]};
  if (a.direction.size() == 3) a.options.dotDirection = {a.direction[0], a.direction[1], a.direction[2]};
  TesselatorOptions o;
  if (const auto* node = std::get_if<Tesselator3MPNode>(&loaded->scene.polygonizer))
    o = TesselatorOptions::fromNode(*node);
  if (a.threads >= 0) o.threads = a.threads;
  std::vector<TextureMode> modes;
  if (a.mode != "carried") modes.push_back(TextureMode::Projective);
  if (a.mode != "projective") modes.push_back(TextureMode::Carried);
  std::vector<StretchResult> results;
  for (TextureMode m : modes) {
    auto r = measureStretch(loaded->character, o, m, a.options);
    if (!r) {
      std::fprintf(stderr, "puppeteer stretch: error: %s: %s\n", a.scene.c_str(),
                   r.error().all().front().message.c_str());
      return kExitInvalidInput;
    }
    results.push_back(*r);
  }
  if (a.json) {
    Json modesJson = Json::array();
    for (const StretchResult& r : results)
      modesJson.push_back(Json{{"mode", modeName(r.mode)},
                               {"roundTrip", r.roundTrip},
                               {"roundTripRadii", r.roundTrip / r.radius},
                               {"slideBent", r.slideBent},
                               {"slideBentRadii", r.slideBent / r.radius},
                               {"slideBack", r.slideBack},
                               {"slideBackRadii", r.slideBack / r.radius},
                               {"skinRoundTrip", r.skinRoundTrip},
                               {"dotRest", vec(r.dotRest)},
                               {"dotBent", vec(r.dotBent)},
                               {"skinBent", vec(r.skinBent)},
                               {"dotBack", vec(r.dotBack)},
                               {"skinBack", vec(r.skinBack)},
                               {"particles", r.particles}});
    printJson(Json{{"scene", a.scene},
                   {"joint", a.options.joint},
                   {"degrees", a.options.degrees},
                   {"frames", a.options.frames},
                   {"desiredRadius", results.front().radius},
                   {"layer", results.front().layer},
                   {"dotUv", Json::array({results.front().dotUv.x, results.front().dotUv.y})},
                   {"modes", std::move(modesJson)}});
    return kExitOk;
  }
  const StretchResult& f = results.front();
  std::printf(
      "%s: a dot on joint %s (layer %d, uv %.4f %.4f), bent %g degrees over %d frames and back; "
      "desiredRadius %.4g m\n",
      a.scene.c_str(), a.options.joint.c_str(), f.layer, f.dotUv.x, f.dotUv.y, double(a.options.degrees),
      a.options.frames, double(f.radius));
  std::printf("%-11s %22s %26s %26s\n", "mode", "round trip m (radii)", "slide when bent m (radii)",
              "slide when back m (radii)");
  for (const StretchResult& r : results)
    std::printf("%-11s %12.5f (%6.3f) %16.5f (%6.3f) %16.5f (%6.3f)\n", modeName(r.mode), double(r.roundTrip),
                double(r.roundTrip / r.radius), double(r.slideBent), double(r.slideBent / r.radius),
                double(r.slideBack), double(r.slideBack / r.radius));
  std::printf("the skin's own round trip (differential transforms): %.5f m (%.3f radii)\n",
              double(results.front().skinRoundTrip), double(results.front().skinRoundTrip / f.radius));
  return kExitOk;
}

}  // namespace

void addStretchCommands(CLI::App& app, Commands& commands) {
  auto a = std::make_shared<StretchArgs>();
  CLI::App* cmd =
      app.add_subcommand("stretch",
                         "Paint a dot on a joint, bend it and back, and report how far the dot slid over the skin "
                         "(projective and carried texture modes)");
  cmd->add_option("scene", a->scene, "A scene (.wrl) with a textured primitive at the joint")
      ->required()
      ->check(inputFile());
  cmd->add_option("--mode", a->mode, "both, projective or carried")
      ->capture_default_str()
      ->check(CLI::IsMember({"both", "projective", "carried"}));
  cmd->add_option("--joint", a->options.joint, "The joint that bends; the dot is painted at its origin")
      ->capture_default_str();
  cmd->add_option("--degrees", a->options.degrees, "The bend")->capture_default_str()->check(CLI::Range(-180.0, 180.0));
  cmd->add_option("--axis", a->axis, "AX,AY,AZ: the bend's axis in the joint's parent's frame (default 0,0,1)")
      ->expected(3)
      ->delimiter(',');
  cmd->add_option("--dot-direction", a->direction,
                  "DX,DY,DZ: the dot is where the ray from the joint's origin this way (world, at rest) meets the "
                  "surface (default 0,-1,0: the outside of the default bend)")
      ->expected(3)
      ->delimiter(',');
  cmd->add_option("--frames", a->options.frames, "Frames to bend, and as many to come back")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--rest-frames", a->options.restFrames, "Frames at rest before painting and before measuring")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000));
  cmd->add_option("--threads", a->threads, "Worker threads (0: all cores; default: the scene's numThreads)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--pictures", a->options.pictures,
                  "Also paint the dot into the texture and render the joint at rest, bent and back to "
                  "PREFIX_MODE_{rest,bent,back}.png");
  cmd->add_flag("--json", a->json, "Print the figures as JSON (for scripts)");
  commands.push_back({cmd, [a] { return runStretch(*a); }});
}

}  // namespace imps::app
