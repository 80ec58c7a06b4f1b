// SPDX-License-Identifier: MIT
// The hand-posing manipulators' maths, free of any window or GL: the joint whose bone a ray passes nearest, and a
// screen drag turned into a joint rotation (an arcball centred on the joint — a two-axis trackball about the
// screen's up/right axes near its centre — or a twist about the view axis). The mapping between world points and
// window pixels (ScreenView, projectToWindow, pickRay, pixelsToAngle) is the camera's (camera.h).
// Based on: K. Shoemake, "ARCBALL: A User Interface for Specifying Three-Dimensional Orientation Using a Mouse",
// 1992; M. Chen, S. J. Mountford, A. Sellen, "A Study in Interactive 3-D Rotation Using 2-D Control Devices", 1988
// (the "virtual trackball": horizontal drag turns about the vertical screen axis, vertical about the horizontal).
#pragma once

#include <span>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "camera.h"

namespace imps::app {

// A pickable piece of the skeleton: the segment from joint `joint`'s origin to one of its children's origins (world
// space, metres), or a single point (a == b) for a joint without children. Picking a bone picks the joint that
// turns it.
struct Bone {
  int joint = -1;
  glm::vec3 a{0.0f}, b{0.0f};
};

// The bones of a posed skeleton: one per (joint, child) pair and one point per leaf joint. `parents[j]` is joint
// j's parent (-1 for a root), `world[j]` its world origin; both have one entry per joint.
std::vector<Bone> skeletonBones(std::span<const int> parents, std::span<const glm::vec3> world);

// The joint whose bone passes nearest the ray, measured as the angle (radians) between the ray and the bone's
// nearest point seen from the ray's origin; -1 when none is within `maxAngle` or lies in front of the origin. Where
// two bones meet (an elbow), the bone that starts there wins, so a click on a joint picks that joint.
int pickJoint(const PickRay& ray, std::span<const Bone> bones, float maxAngle);

// The arcball (Shoemake), centred on the picked joint's window position `center` with radius `radius` pixels: the
// window points `from` and `to` are lifted onto the ball's front hemisphere (or its rim, outside the ball) and the
// result is the world-space rotation that carries the first onto the second (single angle, so the point under the
// cursor follows it). Near the centre it is the two-axis trackball: dragging right turns about the screen's up axis,
// dragging down about the screen's right axis (the side facing the viewer follows the cursor). A press on a limb
// with the radius set to the press's distance from the joint (see arcballRadius) makes the limb follow the cursor
// around the joint on screen; the identity when the points coincide.
glm::quat arcballRotation(const glm::vec2& center, float radius, const glm::vec2& from, const glm::vec2& to,
                          const ScreenView& view);

// The arcball radius for a press at `press` on a joint drawn at `center`: the press's distance, so a limb grabbed
// anywhere follows the cursor, but at least `minRadius` pixels, so a press on the joint itself turns it like a
// trackball.
float arcballRadius(const glm::vec2& center, const glm::vec2& press, float minRadius);

// The twist: the angle the cursor swept around `center` (window pixels) from `from` to `to`, as a world rotation
// about the view axis; counter-clockwise on screen turns counter-clockwise as seen from the camera.
glm::quat twistRotation(const glm::vec2& center, const glm::vec2& from, const glm::vec2& to, const ScreenView& view);

// A joint's new local rotation (relative to its parent) after turning its world frame by `worldRotation` about its
// own origin: world = parentWorld * local, so local' = parentWorld^-1 * worldRotation * parentWorld * local. The
// world rotation is thereby expressed in the parent's frame. Normalised.
glm::quat rotateJointLocal(const glm::quat& local, const glm::quat& parentWorld, const glm::quat& worldRotation);

// --- Handles (the modeller's visible manipulators) ---
//
// A handle sits at a world point with three axes (a frame's x, y, z; drawn red, green, blue) of a fixed length on
// screen. Its centre translates in the screen plane, an axis along itself; in scale mode the distance from the centre
// sets the factor. All window pixels.

// Where a handle's parts fall in the window: its centre and the tips of its three axes (world length chosen so that
// an axis lying in the screen plane is `lengthPixels` long; axes pointing at the viewer are foreshortened). False
// when the centre is behind the camera.
struct HandleLayout {
  glm::vec2 center{0.0f};
  glm::vec2 tips[3] = {};
  float worldLength = 0.0f;  // metres: the world length of each axis
};
bool handleLayout(const ScreenView& view, const glm::vec3& origin, const glm::quat& frame, float lengthPixels,
                  HandleLayout* layout);

// Which part of a handle lies under `cursor`: the centre (within `tolerance` pixels of it), else the axis whose
// segment (centre → tip) passes nearest within `tolerance`, else None. *distance (optional) receives that distance.
enum class HandlePart { None, Center, AxisX, AxisY, AxisZ };
HandlePart pickHandlePart(const HandleLayout& layout, const glm::vec2& cursor, float tolerance, float* distance);

// Translation along a world axis (unit `axis` through `origin`) for a drag from window point `from` to `to`: the
// change in the parameter of the axis point nearest the pick ray (metres). 0 when the axis points (almost) at the
// viewer, where a drag along it is undefined.
float axisDrag(const ScreenView& view, const glm::vec3& origin, const glm::vec3& axis, const glm::vec2& from,
               const glm::vec2& to);

// Translation in the screen plane through `origin` (world metres) for a drag from `from` to `to`: the point under
// the cursor follows it, so origin + result projects to origin's pixel + (to - from).
glm::vec3 planeDrag(const ScreenView& view, const glm::vec3& origin, const glm::vec2& from, const glm::vec2& to);

// The scale factor of a drag that started at `press` and is now at `cursor`, around a handle drawn at `center`, from
// their distances r0, r1 from the centre: r1 / r0 for a press at least `minRadius` pixels out (an axis tip), else
// 1 + (r1 - r0) / minRadius (a press near the centre scales smoothly, doubling `minRadius` pixels further out);
// clamped to [0.01, 100]. 1 while the cursor has not moved.
float scaleFactor(const glm::vec2& center, const glm::vec2& press, const glm::vec2& cursor, float minRadius);

}  // namespace imps::app
