// SPDX-License-Identifier: MIT
// A world (imps/world.h) on the command line: reading it with its diagnostics, `--drive NAME=SOURCE` checked
// against its characters, and every character posed at a time and polygonized beside the props, for `render`,
// `mesh` and `view` (docs/world-format.md#worlds, docs/cli.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/world.h"
#include "png.h"
#include "viewer.h"

namespace imps::app {

// Reads the world, printing its warnings (and errors) to stderr; nullopt on errors (exit kExitInvalidInput).
std::optional<World> loadWorld(const std::string& path);

// Each character's pose source from the command line's `--drive NAME=SOURCE` (repeatable), one entry per character
// in world order ("" where none is given: the clip inlined beside it plays, or it stands in its rest pose). A NAME
// naming no character, a spec without '=' or an empty SOURCE, or a character driven twice: prints
// "WORLD: error: --drive SPEC: …" (with "did you mean" and the characters' names) and returns nullopt
// (exit kExitUsage).
std::optional<std::vector<std::string>> driveSources(const World& world, const std::vector<std::string>& drives);

// Whether a --drive SOURCE is a VRML 97 clip: FILE.wrl, .wrz or .wrl.gz, optionally with #TIMESENSOR.
bool isClipSource(const std::string& source);
// FILE and TIMESENSOR of a clip source ("" when not given).
std::pair<std::string, std::string> splitClipSource(const std::string& source);

// One object of a posed world: a character's surface (placed) or a prop, in world coordinates.
struct WorldObject {
  std::string name;
  Mesh mesh;
  bool character = false;
};

// Every character posed at `seconds` by its clip (its --drive clip, else the clip inlined beside it; none: rest
// pose), polygonized by Marching Cubes with `options` (each character its own grid around its own surface), then the
// world's props. `sources` as driveSources gives them; a source that is not a clip is refused ("render/mesh sample
// clips only; view plays sessions and devices"). Character meshes keep their texture layers, the images' indices offset
// into `textures` (all the characters' images, in order), which this fills. Prints errors; nullopt on failure.
std::optional<std::vector<WorldObject>> poseWorld(const World& world, const std::vector<std::string>& sources,
                                                  double seconds, const MarchingCubesOptions& options,
                                                  std::vector<RgbaImage>* textures, const char* command);

// The time of a world's own clips in the app: a fixed step per frame (headless runs, repeatable), else the steady
// clock since construction.
class WorldTime {
 public:
  explicit WorldTime(double fixedStepSeconds);
  double seconds(int frame) const;

 private:
  double fixedStep_ = 0.0;
  int64_t startNs_ = 0;
};

// A character's pose source in an animated world: its own source (may be null) plus its placement under the
// world's clips (World::chainMatrix of its Transforms), set on the skeleton cache every frame it moves. Forwards
// everything else to the inner source, which must outlive it.
class PlacedPoseSource : public PoseSource {
 public:
  PlacedPoseSource(const World& world, size_t character, PoseSource* inner, WorldTime time);
  bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) override;
  void describe(HudInfo& info) override;
  void frameDone() override;
  std::string toggleRecording() override { return inner_ ? inner_->toggleRecording() : PoseSource::toggleRecording(); }
  std::string recalibrate() override { return inner_ ? inner_->recalibrate() : PoseSource::recalibrate(); }
  bool handlesDeviceKeys() const override { return inner_ && inner_->handlesDeviceKeys(); }
  std::string takeMessage() override { return inner_ ? inner_->takeMessage() : std::string(); }
  std::string finish() override { return inner_ ? inner_->finish() : std::string(); }
  int exitCode() const override { return inner_ ? inner_->exitCode() : 0; }

 private:
  const World& world_;
  size_t character_;
  PoseSource* inner_;
  WorldTime time_;
  int frames_ = 0;
};

}  // namespace imps::app
