// SPDX-License-Identifier: MIT
// Worlds on the command line (see world_scene.h).
#include "world_scene.h"

#include <cstdio>
#include <filesystem>

#include "clip_pose.h"
#include "imps/skeleton_cache.h"
#include "imps/vrml_props.h"
#include <memory>
#include "imps/texturing.h"
#include "textures.h"
#include "imps/clock.h"

namespace imps::app {

std::optional<World> loadWorld(const std::string& path) {
  Diagnostics warnings;
  auto world = readWorldFile(path, &warnings);
  std::fputs(warnings.str().c_str(), stderr);
  if (!world) {
    std::fputs(world.error().str().c_str(), stderr);
    return std::nullopt;
  }
  return std::move(*world);
}

std::optional<std::vector<std::string>> driveSources(const World& world, const std::vector<std::string>& drives) {
  std::vector<std::string> sources(world.characters.size());
  const std::vector<std::string> names = world.characterNames();
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  for (const std::string& spec : drives) {
    const std::string form = world.fileName + ": error: --drive " + spec + ": ";
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
      std::fprintf(stderr, "%sexpected NAME=SOURCE (a character of the world: %s)\n", form.c_str(), list.c_str());
      return std::nullopt;
    }
    const std::string name = spec.substr(0, eq);
    const int k = world.findCharacter(name);
    if (k < 0) {
      const std::string guess = closestMatch(name, names);
      std::fprintf(stderr, "%sthe world places no character '%s'%s (its characters: %s)\n", form.c_str(), name.c_str(),
                   guess.empty() ? "" : (" (did you mean '" + guess + "'?)").c_str(),
                   list.empty() ? "none" : list.c_str());
      return std::nullopt;
    }
    if (!sources[size_t(k)].empty()) {
      std::fprintf(stderr, "%s%s is already driven by %s\n", form.c_str(), name.c_str(), sources[size_t(k)].c_str());
      return std::nullopt;
    }
    sources[size_t(k)] = spec.substr(eq + 1);
  }
  return sources;
}

std::pair<std::string, std::string> splitClipSource(const std::string& source) {
  const size_t hash = source.rfind('#');
  if (hash == std::string::npos) return {source, ""};
  return {source.substr(0, hash), source.substr(hash + 1)};
}

bool isClipSource(const std::string& source) {
  const std::string file = splitClipSource(source).first;
  auto ends = [&file](const char* tail) { return file.ends_with(tail); };
  return ends(".wrl") || ends(".wrz") || ends(".wrl.gz") || ends(".WRL");
}

std::optional<std::vector<WorldObject>> poseWorld(const World& world, const std::vector<std::string>& sources,
                                                  double seconds, const MarchingCubesOptions& options,
                                                  std::vector<RgbaImage>* textures, const char* command) {
  std::vector<WorldObject> out;
  World::Pose pose = world.poseAt(seconds);  // the world's own clips move placements and props
  std::vector<std::unique_ptr<SkeletonCache>> skeletons;  // kept for the props riding on joints
  for (size_t k = 0; k < world.characters.size(); ++k) {
    const WorldCharacter& c = world.characters[k];
    SkeletonCache& skeleton = *skeletons.emplace_back(std::make_unique<SkeletonCache>(c.character));
    skeleton.setPlacement(pose.placements[k]);
    const std::string& source = k < sources.size() ? sources[k] : std::string();
    std::optional<ClipDriver> driver;
    if (!source.empty()) {
      if (!isClipSource(source)) {
        std::fprintf(stderr,
                     "puppeteer %s: error: --drive %s=%s: %s samples VRML clips only (FILE.wrl[#TIMESENSOR]); "
                     "`puppeteer view WORLD` plays sessions, BVH clips and devices\n",
                     command, c.name.c_str(), source.c_str(), command);
        return std::nullopt;
      }
      const auto [file, clipName] = splitClipSource(source);
      auto loaded = ClipDriver::load(file, clipName, "names", c.character);
      if (!loaded) {
        std::fputs(loaded.error().str().c_str(), stderr);
        return std::nullopt;
      }
      driver = std::move(*loaded);
    } else if (c.clip) {
      driver.emplace(*c.clip, c.character);
    }
    if (driver) driver->apply(seconds, skeleton);
    skeleton.update();
    MarchingCubesOptions mc = options;  // each character its own grid around its own surface
    if (auto plan = planGrid(skeleton.field(), mc); !plan) {
      std::fprintf(stderr, "%s: error: character %s: %s; use larger cells or raise --max-cells\n", c.scenePath.c_str(),
                   c.name.c_str(), plan.error().all().front().message.c_str());
      return std::nullopt;
    }
    Mesh mesh = polygonize(skeleton.field(), mc);
    textureMesh(mesh, skeleton, mc.threads);
    if (textures != nullptr && c.character.textured()) {
      auto images = loadTextures(c.character);
      if (!images) {
        std::fputs(images.error().str().c_str(), stderr);
        return std::nullopt;
      }
      const int32_t offset = int32_t(textures->size());
      for (int32_t& i : mesh.layerImages)
        if (i >= 0) i += offset;
      textures->insert(textures->end(), images->begin(), images->end());
    }
    out.push_back({c.name, std::move(mesh), true});
  }
  for (size_t p = 0; p < world.props.size(); ++p) {
    const int c = p < world.propCharacter.size() ? world.propCharacter[p] : -1;
    if (c >= 0)  // riding on a joint: posed with its character
      pose.props[p] = transformed(world.propLocal[p], skeletons[size_t(c)]->world(world.propJoint[p]));
    out.push_back({world.props[p].name, std::move(pose.props[p]), false});
  }
  return out;
}

WorldTime::WorldTime(double fixedStepSeconds) : fixedStep_(fixedStepSeconds), startNs_(steadyNowNs()) {}

double WorldTime::seconds(int frame) const {
  return fixedStep_ > 0.0 ? fixedStep_ * frame : double(steadyNowNs() - startNs_) * 1e-9;
}

PlacedPoseSource::PlacedPoseSource(const World& world, size_t character, PoseSource* inner, WorldTime time)
    : world_(world), character_(character), inner_(inner), time_(time) {}

bool PlacedPoseSource::poll(SkeletonCache& skeleton, int64_t* arrivalNs) {
  bool changed = inner_ != nullptr && inner_->poll(skeleton, arrivalNs);
  const auto moved = world_.transformsAt(time_.seconds(frames_));
  glm::mat4 m = World::chainMatrix(world_.characters[character_].chain, moved);
  glm::mat3 r(m);
  for (int k = 0; k < 3; ++k)
    if (const float length = glm::length(r[k]); length > 0.0f) r[k] /= length;
  Rigid placement;
  placement.rotation = glm::normalize(glm::quat_cast(r));
  placement.translation = glm::vec3(m[3]);
  if (placement.rotation != skeleton.placement().rotation ||
      placement.translation != skeleton.placement().translation) {
    skeleton.setPlacement(placement);
    changed = true;
  }
  return changed;
}

void PlacedPoseSource::describe(HudInfo& info) {
  if (inner_ != nullptr) {
    inner_->describe(info);
  } else {
    info.source = world_.characters[character_].name + ": world clips";
    info.state = "playing";
  }
}

void PlacedPoseSource::frameDone() {
  ++frames_;
  if (inner_ != nullptr) inner_->frameDone();
}

}  // namespace imps::app
