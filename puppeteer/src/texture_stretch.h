// SPDX-License-Identifier: MIT
// `puppeteer stretch`: how far a painted dot slides over the skin when a joint bends and comes back, for the
// projective and the carried texture modes (issue 11, docs/cli.md).
#pragma once

#include <expected>
#include <optional>
#include <string>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "imps/character.h"
#include "imps/diagnostic.h"
#include "imps/mesh.h"
#include "imps/scene.h"
#include "imps/tesselator.h"

namespace imps::app {

struct StretchOptions {
  std::string joint = "L_Forearm";  // the joint that bends (the elbow); the dot is painted on its origin's surface
  glm::vec3 axis{0, 0, 1};          // the bend's axis, in the joint's parent's frame (unit or not)
  float degrees = 90.0f;            // the bend
  int frames = 30;                  // frames to bend, and as many back (each: updatesPerRender updates)
  int restFrames = 10;              // frames at rest before painting, and after coming back before measuring
  // The dot is where the ray from the joint's origin (inside the limb) this way (world, at rest) leaves the
  // surface: the outside of the default bend.
  glm::vec3 dotDirection{0, -1, 0};
  // Non-empty: the dot is also painted into the texture image (a red dab of 7 texels) and the joint is rendered
  // (software, 640 x 480, looking at its outside) at rest, bent and back into PREFIX_MODE_{rest,bent,back}.png.
  std::string pictures;
};

// One mode's figures. Lengths in metres; `radius` is the tesselator's desiredRadius.
struct StretchResult {
  TextureMode mode = TextureMode::Projective;
  float radius = 0.0f;
  int32_t layer = -1;          // the mesh layer (textured primitive) the dot is painted into
  glm::vec2 dotUv{0.0f};       // the dot's centre in that layer's (u, v)
  glm::vec3 dotRest{0.0f};     // the dot's centre on the surface at rest, after painting
  glm::vec3 dotBent{0.0f};     // ... at the bent pose
  glm::vec3 skinBent{0.0f};    // where the skin carried the dot's material point at the bent pose
  glm::vec3 dotBack{0.0f};     // ... back at rest
  glm::vec3 skinBack{0.0f};    // where the skin carried the material point back at rest (not where it started: the
                               // differential transforms are not reversible where ownership changes hands)
  float roundTrip = 0.0f;      // |dotBack - dotRest|: the drift after bending and coming back
  float slideBent = 0.0f;      // |dotBent - skinBent|: how far the texture slid under the bent skin
  float skinRoundTrip = 0.0f;  // |skinBack - dotRest|: the skin model's own round trip
  float slideBack = 0.0f;      // |dotBack - skinBack|
  size_t particles = 0;        // at the end
};

// The dot's centre on `mesh`: the surface point where layer `layer`'s interpolated coordinates (Mesh::layerUv over
// the triangles all of whose corners blend that layer) equal `uv` — the point the texture shows the texel at `uv`
// — the one nearest `near` when several do (u compared modulo 1). Empty if no such triangle holds `uv`.
std::optional<glm::vec3> surfacePointOfUv(const Mesh& mesh, int32_t layer, glm::vec2 uv, const glm::vec3& near);

// Runs the measurement on `character` (which must have a joint `options.joint` and a textured primitive at the dot)
// with the tesselator `tesselator` in texture mode `mode`: settle at rest (plus restFrames), paint the dot where the
// ray from the joint's origin along dotDirection leaves the surface (its centre: the heaviest layer's coordinates
// there), bend the joint by `degrees` about `axis` over `frames` frames, measure, come back over `frames` frames,
// restFrames frames at rest, measure. The skin's own motion is a marker moved as a particle without repulsion: by
// its owner's differential transform every frame, then projected back onto the surface, its ownership passing to
// blend neighbours as the tesselator's particles' does. Deterministic (the tesselator's options' seed and threads).
// Fails with one error without a location (the caller names the scene) saying what is missing (joint, surface,
// texture at the dot), or which image cannot be read or written.
std::expected<StretchResult, Diagnostics> measureStretch(const Character& character, TesselatorOptions tesselator,
                                                         TextureMode mode, const StretchOptions& options);

}  // namespace imps::app
