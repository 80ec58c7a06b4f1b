// SPDX-License-Identifier: MIT
// The live app's per-frame work without any window: scene → character → skeleton cache → particle tesselator or
// Marching Cubes → Mesh. The viewer drives it once per rendered frame; tests drive it headless.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "imps/mesh.h"
#include "imps/scene.h"
#include "imps/skeleton_cache.h"
#include "imps/tesselator.h"
#include "png.h"
#include "scene_edit.h"

namespace imps::app {

enum class Polygonizer { Particles, MarchingCubes };

struct PipelineOptions {
  Polygonizer polygonizer = Polygonizer::Particles;
  // Tesselator threads; -1 keeps the scene's numThreads.
  int threads = -1;
  // The particle tesselator's texture mode (--texture-mode); unset keeps the scene's textureMode.
  std::optional<TextureMode> textureMode;
  // Particle updates run by the constructor (and by reset()) before the first frame, so the first picture is a
  // settled surface rather than a few seed particles (Tesselator::settle; stops earlier once settled).
  int settleUpdates = 400;
  // Marching Cubes cells along the longest side of the surface bounds (when the scene has no MarchingCubes node).
  int mcResolution = 64;
};

// One character being puppeteered. Owns the scene document, the compiled character, its skeleton cache and both
// polygonizers (only the active one runs). Not thread-safe: the frame loop owns it.
class ViewerPipeline {
 public:
  // `scene` must compile (Character::fromScene succeeded on it): pass the compiled character too.
  ViewerPipeline(Scene scene, Character character, const PipelineOptions& options);

  const Scene& scene() const { return scene_; }
  const Character& character() const { return *character_; }
  SkeletonCache& skeleton() { return *skeleton_; }
  const SkeletonCache& skeleton() const { return *skeleton_; }

  // Places the character in the world (a world file's Transform; SkeletonCache::setPlacement), updates the skeleton
  // cache and moves restBounds() with it. Call before the first frame.
  void setPlacement(const Rigid& placement);

  // Runs the active polygonizer against the skeleton cache's current field (call skeleton().update() first when
  // the pose changed): updatesPerRender particle updates and a triangulation, or one Marching Cubes pass.
  void frame();
  const Mesh& mesh() const { return mesh_; }
  // The character's texture images (textures.h's loadTextures, in Character::textures() order), which the mesh's
  // layers name. Set once after construction; the renderer uploads them.
  const std::vector<RgbaImage>& textures() const { return textures_; }
  void setTextures(std::vector<RgbaImage> images) { textures_ = std::move(images); }
  // The painter's access (painter.h): call only while no worker polygonizes (the images are not read there).
  std::vector<RgbaImage>& mutableTextures() { return textures_; }
  // Incremented whenever frame() rewrites mesh(): the renderer re-uploads only a new mesh. Marching Cubes skips its
  // pass (and keeps the version) while the skeleton cache's generation has not changed.
  uint64_t meshVersion() const { return meshVersion_; }

  Polygonizer polygonizer() const { return options_.polygonizer; }
  void setPolygonizer(Polygonizer p);
  // Drops every particle and settles again from the current pose (the thesis's `r` key).
  void resetPolygonizer();

  const Tesselator& tesselator() const { return *tesselator_; }
  const MarchingCubesStats& marchingCubesStats() const { return mcStats_; }
  // The Marching Cubes options in force (the scene's MarchingCubes node, else a resolution).
  const MarchingCubesOptions& marchingCubesOptions() const { return mcOptions_; }
  int updatesPerRender() const { return tesselator_->options().updatesPerRender; }
  double lastFrameMs() const { return lastFrameMs_; }
  // The character's surface bounds in the file's pose (conservative), for framing a camera that posing does not move.
  const MeshBounds& restBounds() const { return restBounds_; }

  // The scene document with the current pose written into its RigidTransforms' rotations and translations
  // (joints are matched by their place in the document, named or not), ready for saveSceneFile().
  Scene posedScene() const;

  // Every joint's current local transform (the skeleton cache's), in joint order.
  std::vector<Rigid> pose() const;
  // The document and the pose (DocumentState{scene(), pose()}).
  DocumentState state() const { return DocumentState{scene_, pose()}; }
  // Replaces the document and the pose (an edit, an undo): recompiles the character and the skeleton cache and sets
  // every joint's local transform from state.pose (one per joint; missing entries keep the new document's rest
  // pose). The particles stay (they follow the new surface; when the number of primitives changed they are
  // dropped); Marching Cubes runs again; the camera's rest bounds stay. When the document does not compile, nothing
  // changes and the diagnostics are returned.
  std::optional<Diagnostics> setState(DocumentState state);

 private:
  Scene scene_;
  std::vector<RgbaImage> textures_;
  std::unique_ptr<Character> character_;  // stable address: the skeleton cache points to it
  std::unique_ptr<SkeletonCache> skeleton_;
  std::unique_ptr<Tesselator> tesselator_;
  MarchingCubes marchingCubes_;
  MarchingCubesOptions mcOptions_;
  MarchingCubesStats mcStats_;
  PipelineOptions options_;
  Mesh mesh_;
  MeshBounds restBounds_;
  bool settled_ = false;
  uint64_t meshVersion_ = 0;
  uint64_t mcGeneration_ = 0;  // skeleton generation of the last Marching Cubes pass
  bool mcValid_ = false;       // mesh_ holds that pass
  double lastFrameMs_ = 0.0;
};

// FNV-1a 64 over the mesh's positions, normals, colours and indices (bytes as stored): equal meshes hash equal.
uint64_t meshHash(const Mesh& mesh);

}  // namespace imps::app
