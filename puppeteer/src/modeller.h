// SPDX-License-Identifier: MIT
// The interactive modeller (thesis chapter 5, appendix A.2.2), free of any window: the visible manipulators
// (handles) of a scene, picking them with the mouse, dragging them into edits of the scene document, and
// undo/redo. The viewer feeds it window-pixel mouse events and draws its handles; tests drive it directly.
//
// Handles: in a hierarchical scene one per RigidTransform (joint), at its origin, and for the selected joint one per
// primitive it holds and per LineSeg endpoint; in a flat scene one per primitive and per LineSeg endpoint (the
// thesis's viewer did the same). Modes: translate (the centre moves in the screen plane, an axis along itself),
// rotate (the arcball and, with Shift, the twist of manipulator.h), scale (the distance from the centre sets the
// factor: a metaball's or an endpoint's radius, an ellipsoid's semi-axes — one axis when an axis is grabbed — a
// LineSeg's radii, a joint's limb length). Every drag becomes one undoable edit when the button is released.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera.h"
#include "manipulator.h"
#include "renderer.h"
#include "scene_edit.h"
#include "viewer_pipeline.h"

namespace imps::app {

// The app's first camera (camera.h's initialOrbit): the pipeline's rest bounds (else the mesh's) framed from the
// front three-quarter view in a width x height window; *sceneRadius (optional) receives the radius the clip planes
// use.
OrbitCamera initialOrbit(const ViewerPipeline& pipeline, int width, int height, float* sceneRadius);

enum class ManipulatorMode { Translate, Rotate, Scale };
const char* modeName(ManipulatorMode mode);

// One visible manipulator.
struct Handle {
  EditTarget target;
  glm::vec3 origin{0.0f};           // world position (metres)
  glm::quat frame{1, 0, 0, 0};      // world rotation of the drawn axes (translate along / scale along them)
  glm::quat container{1, 0, 0, 0};  // world rotation of the frame the target's values live in
};

// The handles as overlay triangles (window pixels): the selected handle with its three axes (red, green, blue for
// its frame's x, y, z; arrowheads in translate mode, squares in scale mode, a ring around it in rotate mode) and a
// yellow centre square; every other handle as a small centre square (joints grey, primitives white, LineSeg
// endpoints orange). Only the selected handle's axes can be grabbed; every handle's centre can.
std::vector<OverlayVertex> handleOverlay(const ScreenView& view, const std::vector<Handle>& handles,
                                         const std::optional<EditTarget>& selected, ManipulatorMode mode);

class Modeller {
 public:
  // Handles are this many pixels long on screen; a press within kPickPixels of a part grabs it.
  static constexpr float kHandlePixels = 70.0f;
  static constexpr float kPickPixels = 10.0f;

  // Starts in rotate mode for a hierarchical scene (dragging a limb turns it), translate mode for a flat one.
  explicit Modeller(ViewerPipeline& pipeline);

  // Off (--no-manipulators): no handles, no edits by the mouse; undo/redo and menu edits still work.
  bool enabled() const { return enabled_; }
  void setEnabled(bool on) { enabled_ = on; }
  ManipulatorMode mode() const { return mode_; }
  void setMode(ManipulatorMode mode) { mode_ = mode; }

  std::vector<Handle> handles() const;
  // The selected target (the last one grabbed or chosen), if any.
  const std::optional<EditTarget>& selected() const { return selected_; }
  // Selects joint j (-1: nothing), as the number and bracket keys do.
  void selectJoint(int joint);
  // The selected joint: the selected target's joint (a primitive's owner), or -1.
  int selectedJoint() const;

  // Left button pressed at window pixel `pixel`: grabs the handle part under the cursor, else (hierarchical scene)
  // the joint whose bone is under it (as manipulator.h's pickJoint; it turns, whatever the mode), else with Shift
  // the selected joint (twist). Returns false when nothing was grabbed (the viewer orbits instead).
  bool press(const ScreenView& view, const glm::vec2& pixel, bool shift);
  // The cursor moved to `pixel` with the button held: applies the drag to the pose or the document.
  void drag(const ScreenView& view, const glm::vec2& pixel);
  // Button released: the drag becomes one undoable edit (a joint's pose is written into its RigidTransform).
  // Returns what was done ("translate LEFT by 0.2 0 0 m"), why nothing could be ("translate metaball1: a USE of
  // A: edit A itself"), or "" when nothing changed.
  std::string release();
  bool dragging() const { return drag_ != Drag::None; }
  // What the last press grabbed, for messages: "translate LEFT", "arcball L_UpperArm", "".
  const std::string& grabbed() const { return grabbed_; }

  // Ctrl+Z / Ctrl+Shift+Z: the previous / next document state (and pose). Return what happened.
  std::string undo();
  std::string redo();
  const EditHistory& history() const { return history_; }

  // A change to the document made elsewhere (the menu: blend, iso-value), shown at once. Changes with
  // `final` false are previews (a slider being dragged): they and the final one make one undoable edit. Returns ""
  // or the reason nothing changed (the changed document does not compile).
  std::string editDocument(const std::function<void(Scene&)>& change, bool final = true);

 private:
  enum class Drag { None, Pose, Document } drag_ = Drag::None;
  std::optional<Handle> handleOf(const EditTarget& target) const;
  bool grab(const ScreenView& view, const Handle& handle, HandlePart part, const glm::vec2& pixel, bool shift);
  // Translate mode: the world delta of the drag so far (in the screen plane, or along the grabbed axis).
  glm::vec3 translation(const ScreenView& view, const glm::vec2& pixel) const;
  void dragPose(const ScreenView& view, const glm::vec2& pixel);
  void dragDocument(const ScreenView& view, const glm::vec2& pixel);
  std::string apply(DocumentState state);

  ViewerPipeline& pipeline_;
  EditHistory history_;
  bool enabled_ = true;
  ManipulatorMode mode_ = ManipulatorMode::Rotate;
  std::optional<EditTarget> selected_;
  // The drag in progress: what was grabbed, how, where, and the state it started from.
  Handle handle_;
  HandlePart part_ = HandlePart::None;
  bool twist_ = false;
  float arcballRadius_ = 60.0f;
  glm::vec2 press_{0.0f}, last_{0.0f}, center_{0.0f};
  DocumentState start_;
  std::optional<DocumentState> previewStart_;  // editDocument: the state before the first preview
  std::string grabbed_;
  std::string refused_;    // why the drag in progress cannot edit its target ("" when it can)
  glm::vec3 moved_{0.0f};  // translate: the world delta so far
  float factor_ = 1.0f;    // scale: the factor so far
};

}  // namespace imps::app
