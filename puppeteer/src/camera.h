// SPDX-License-Identifier: MIT
// The one camera of the app and the snapshots, free of any window or GL: a pinhole pose and lens, its view and
// projection matrices, framing a box, the viewer's orbit (turn, zoom), and the mapping between world points and
// window pixels (projection to a pixel, the pick ray through one). The software rasteriser (snapshot.h), the GL
// renderer (renderer.h), the manipulators (manipulator.h) and the modeller all see the scene through it.
//
// Conventions, stated once here: world space is metres with y up; window pixels have their origin at the top-left
// corner, x to the right, y down (GLFW's cursor convention); clip space is OpenGL's (z in [-1, 1]).
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "imps/mesh.h"

namespace imps::app {

// The camera's orthonormal world-space basis: `right` and `up` span the image plane, `forward` points from the eye
// towards the target (the viewer looks along it; -forward points towards the viewer).
struct CameraBasis {
  glm::vec3 right{1, 0, 0}, up{0, 1, 0}, forward{0, 0, -1};
};

// A pinhole (perspective) camera in world space (metres). Pose: it looks from `eye` towards `target`; `up` only
// needs to be non-parallel to the view direction. Lens: verticalFov is the full vertical opening angle in radians;
// the horizontal one follows from the image's aspect ratio (width / height), and the GL clip planes from the radius
// of the scene around the target (projectionMatrix). eye != target.
struct Camera {
  glm::vec3 eye{0.0f, 0.0f, 3.0f};
  glm::vec3 target{0.0f, 0.0f, 0.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  float verticalFov = 0.6f;

  // right = normalize(forward x up), up = right x forward.
  CameraBasis basis() const;
  // Distance from the eye to the target (metres).
  float distance() const;
  // World → eye space (glm::lookAt: the eye at the origin looking down -z, y up).
  glm::mat4 viewMatrix() const;
  // Eye → clip space for an image of `aspect` (width / height, > 0) and a scene of `sceneRadius` metres around the
  // target: near = max(0.01, distance - 2 sceneRadius), far = distance + 4 sceneRadius + 1, so the scene fits
  // between them as the camera turns around it.
  glm::mat4 projectionMatrix(float aspect, float sceneRadius) const;
};

// Direction from the subject towards the camera for the front-three-quarter view: in front (+z), to the right
// (+x) and a little above (+y), with y up. Need not be normalised.
inline constexpr glm::vec3 kFrontThreeQuarter{0.65f, 0.4f, 1.0f};

// A camera looking at the centre of `box` from `fromDirection` (world space, need not be normalised, not zero),
// with y up (z up when looking straight along y), far enough that the box's bounding sphere fits in the view
// with `margin` (>= 1) to spare, for an image of the given aspect ratio (width / height). An empty box frames
// the unit cube around the origin.
Camera frameBox(const MeshBounds& box, glm::vec3 fromDirection = kFrontThreeQuarter, float aspect = 1.0f,
                float verticalFov = 0.6f, float margin = 1.08f);

// frameBox(bounds(mesh), ...).
Camera frameMesh(const Mesh& mesh, glm::vec3 fromDirection = kFrontThreeQuarter, float aspect = 1.0f);

// The radius the GL clip planes use for a scene bounded by `box`: half its diagonal, 1 for an empty box.
float sceneRadius(const MeshBounds& box);

// The viewer's camera as an orbit around a target: yaw about +y (0: looking down -z from +z), pitch above the
// horizon (radians), distance in metres; always y up.
struct OrbitCamera {
  glm::vec3 target{0.0f};
  float yaw = 0.0f, pitch = 0.0f, distance = 3.0f;
  float verticalFov = 0.6f;

  // The camera at target + distance * (cos pitch sin yaw, sin pitch, cos pitch cos yaw), looking at the target.
  Camera camera() const;
  // The orbit through `camera`'s eye around its target (its `up` is dropped: the orbit keeps y up). Round trip:
  // around(o.camera()) reproduces o for |pitch| < pi/2 and yaw in (-pi, pi].
  static OrbitCamera around(const Camera& camera);
  // A mouse drag of (dx, dy) window pixels: right turns the camera to the left around the target, down raises it;
  // pitch stays within [-1.5, 1.5] radians, short of the poles.
  void turn(float dx, float dy);
  // `steps` scroll-wheel steps: each step up (> 0) brings the camera 10 % closer; the distance stays within
  // [0.05, 100] metres.
  void zoom(float steps);
};

// The app's first camera for a scene bounded by `box`: frameBox from the front three-quarter view in a width x
// height window, as an orbit; *radius (optional) receives sceneRadius(box).
OrbitCamera initialOrbit(const MeshBounds& box, int width, int height, float* radius);

// A camera's view of a width x height window: world → clip (projection * view), the window size in pixels (>= 1)
// and the camera's basis and eye, for the mapping between world points and window pixels.
struct ScreenView {
  glm::mat4 viewProjection{1.0f};
  int width = 1, height = 1;
  // The camera's world-space basis: right, up (both unit, orthogonal) and the unit direction towards the viewer.
  glm::vec3 right{1, 0, 0}, up{0, 1, 0}, towardsViewer{0, 0, 1};
  glm::vec3 eye{0, 0, 3};
};

// The view of `camera` (its viewMatrix and projectionMatrix with `sceneRadius`) in a width x height window (sizes
// below 1 count as 1).
ScreenView screenView(const Camera& camera, int width, int height, float sceneRadius);

// Window pixel position of a world point; false (and *pixel untouched) when the point is behind the camera.
bool projectToWindow(const ScreenView& view, const glm::vec3& world, glm::vec2* pixel);

// A ray from the eye through a window pixel (world space, unit direction). Every point the ray passes in front of
// the eye projects back to that pixel.
struct PickRay {
  glm::vec3 origin{0.0f};
  glm::vec3 direction{0, 0, -1};
};
PickRay pickRay(const ScreenView& view, const glm::vec2& pixel);

// The angle (radians) that `pixels` pixels subtend at the centre of a window `windowHeight` pixels high seen
// through a lens of `verticalFov` (for manipulator.h's pickJoint).
float pixelsToAngle(float pixels, int windowHeight, float verticalFov);

}  // namespace imps::app
