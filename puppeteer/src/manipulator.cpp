// SPDX-License-Identifier: MIT
// The hand-posing manipulators' maths (see manipulator.h).
#include "manipulator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

namespace imps::app {

std::vector<Bone> skeletonBones(std::span<const int> parents, std::span<const glm::vec3> world) {
  std::vector<Bone> bones;
  std::vector<bool> hasChild(parents.size(), false);
  for (size_t c = 0; c < parents.size(); ++c) {
    const int p = parents[c];
    if (p < 0 || size_t(p) >= parents.size()) continue;
    bones.push_back(Bone{p, world[size_t(p)], world[c]});
    hasChild[size_t(p)] = true;
  }
  for (size_t j = 0; j < parents.size(); ++j)
    if (!hasChild[j]) bones.push_back(Bone{int(j), world[j], world[j]});
  return bones;
}

int pickJoint(const PickRay& ray, std::span<const Bone> bones, float maxAngle) {
  int best = -1;
  float bestScore = std::numeric_limits<float>::infinity();
  for (const Bone& bone : bones) {
    // The segment point (a + s (b - a), s in [0, 1]) seen at the smallest angle from the ray: for each s on a
    // 33-point grid the angle follows from the point's projection onto the ray (bones are few, and a grid is
    // exact enough at pixel precision).
    const glm::vec3 ab = bone.b - bone.a;
    const int steps = glm::length(ab) > 0.0f ? 32 : 0;
    float boneBest = std::numeric_limits<float>::infinity();
    float boneS = 0.0f;
    for (int i = 0; i <= steps; ++i) {
      const float s = steps ? float(i) / float(steps) : 0.0f;
      const glm::vec3 p = bone.a + s * ab - ray.origin;
      const float t = glm::dot(p, ray.direction);
      if (t <= 0.0f) continue;  // behind the eye
      const float angle = std::atan2(glm::length(p - t * ray.direction), t);
      if (angle < boneBest) boneBest = angle, boneS = s;
    }
    if (boneBest > maxAngle) continue;
    // Ties where bones meet: prefer the bone whose nearest point is nearest its start (its joint's origin).
    const float score = boneBest + 0.05f * maxAngle * boneS;
    if (score < bestScore) bestScore = score, best = bone.joint;
  }
  return best;
}

namespace {
// A window point on the arcball, in view coordinates (x right, y up, z towards the viewer).
glm::vec3 onArcball(const glm::vec2& center, float radius, const glm::vec2& p) {
  const glm::vec2 s((p.x - center.x) / radius, -(p.y - center.y) / radius);
  const float r2 = glm::dot(s, s);
  if (r2 <= 1.0f) return glm::vec3(s, std::sqrt(1.0f - r2));
  return glm::vec3(s / std::sqrt(r2), 0.0f);
}
}  // namespace

glm::quat arcballRotation(const glm::vec2& center, float radius, const glm::vec2& from, const glm::vec2& to,
                          const ScreenView& view) {
  if (!(radius > 0.0f)) return glm::quat(1, 0, 0, 0);
  const glm::vec3 v0 = onArcball(center, radius, from), v1 = onArcball(center, radius, to);
  const glm::vec3 axis = glm::cross(v0, v1);
  const float sinAngle = glm::length(axis);
  if (!(sinAngle > 1e-7f)) return glm::quat(1, 0, 0, 0);
  const float angle = std::atan2(sinAngle, glm::dot(v0, v1));
  const glm::vec3 worldAxis = view.right * axis.x + view.up * axis.y + view.towardsViewer * axis.z;
  return glm::angleAxis(angle, glm::normalize(worldAxis));
}

float arcballRadius(const glm::vec2& center, const glm::vec2& press, float minRadius) {
  return std::max(glm::length(press - center), minRadius);
}

glm::quat twistRotation(const glm::vec2& center, const glm::vec2& from, const glm::vec2& to, const ScreenView& view) {
  // Window y points down: negate it for counter-clockwise-positive angles.
  const float a0 = std::atan2(-(from.y - center.y), from.x - center.x);
  const float a1 = std::atan2(-(to.y - center.y), to.x - center.x);
  float angle = a1 - a0;
  if (angle > std::numbers::pi_v<float>) angle -= 2.0f * std::numbers::pi_v<float>;
  if (angle < -std::numbers::pi_v<float>) angle += 2.0f * std::numbers::pi_v<float>;
  return glm::angleAxis(angle, view.towardsViewer);
}

glm::quat rotateJointLocal(const glm::quat& local, const glm::quat& parentWorld, const glm::quat& worldRotation) {
  return glm::normalize(glm::inverse(parentWorld) * worldRotation * parentWorld * local);
}

bool handleLayout(const ScreenView& view, const glm::vec3& origin, const glm::quat& frame, float lengthPixels,
                  HandleLayout* layout) {
  HandleLayout out;
  if (!projectToWindow(view, origin, &out.center)) return false;
  // Pixels per metre at the origin's depth, measured along the screen's right axis (no field of view needed).
  const float probe = 1e-3f * std::max(1e-3f, glm::length(view.eye - origin));
  glm::vec2 side;
  if (!projectToWindow(view, origin + probe * view.right, &side)) return false;
  const float pixelsPerMetre = glm::length(side - out.center) / probe;
  if (!(pixelsPerMetre > 0.0f)) return false;
  out.worldLength = lengthPixels / pixelsPerMetre;
  for (int a = 0; a < 3; ++a) {
    glm::vec3 axis(0.0f);
    axis[a] = 1.0f;
    if (!projectToWindow(view, origin + out.worldLength * (frame * axis), &out.tips[a])) out.tips[a] = out.center;
  }
  *layout = out;
  return true;
}

namespace {
float distanceToSegment(const glm::vec2& p, const glm::vec2& a, const glm::vec2& b) {
  const glm::vec2 ab = b - a;
  const float len2 = glm::dot(ab, ab);
  const float t = len2 > 0.0f ? std::clamp(glm::dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}
}  // namespace

HandlePart pickHandlePart(const HandleLayout& layout, const glm::vec2& cursor, float tolerance, float* distance) {
  const float toCenter = glm::length(cursor - layout.center);
  if (toCenter <= tolerance) {
    if (distance) *distance = toCenter;
    return HandlePart::Center;
  }
  HandlePart best = HandlePart::None;
  float bestDistance = tolerance;
  for (int a = 0; a < 3; ++a) {
    // Only the outer part of an axis grabs it, so a press near the centre is never taken for an axis.
    const glm::vec2 start = layout.center + 0.25f * (layout.tips[a] - layout.center);
    const float d = distanceToSegment(cursor, start, layout.tips[a]);
    if (glm::length(layout.tips[a] - layout.center) > 4.0f && d <= bestDistance)
      bestDistance = d, best = static_cast<HandlePart>(int(HandlePart::AxisX) + a);
  }
  if (distance) *distance = best == HandlePart::None ? toCenter : bestDistance;
  return best;
}

namespace {
// The parameter s of the point origin + s * axis nearest the pick ray through `pixel`; false when the two are
// (almost) parallel.
bool nearestOnAxis(const ScreenView& view, const glm::vec3& origin, const glm::vec3& axis, const glm::vec2& pixel,
                   float* s) {
  const PickRay ray = pickRay(view, pixel);
  const glm::vec3 w = origin - ray.origin;
  const float b = glm::dot(axis, ray.direction);
  const float denominator = 1.0f - b * b;  // |axis| = |direction| = 1
  if (denominator < 1e-4f) return false;
  *s = (b * glm::dot(ray.direction, w) - glm::dot(axis, w)) / denominator;
  return true;
}
}  // namespace

float axisDrag(const ScreenView& view, const glm::vec3& origin, const glm::vec3& axis, const glm::vec2& from,
               const glm::vec2& to) {
  const glm::vec3 unit = glm::normalize(axis);
  float s0 = 0.0f, s1 = 0.0f;
  if (!nearestOnAxis(view, origin, unit, from, &s0) || !nearestOnAxis(view, origin, unit, to, &s1)) return 0.0f;
  return s1 - s0;
}

glm::vec3 planeDrag(const ScreenView& view, const glm::vec3& origin, const glm::vec2& from, const glm::vec2& to) {
  auto hit = [&](const glm::vec2& pixel) {
    const PickRay ray = pickRay(view, pixel);
    const float along = glm::dot(ray.direction, view.towardsViewer);
    if (std::fabs(along) < 1e-6f) return origin;
    const float t = glm::dot(origin - ray.origin, view.towardsViewer) / along;
    return ray.origin + t * ray.direction;
  };
  return hit(to) - hit(from);
}

float scaleFactor(const glm::vec2& center, const glm::vec2& press, const glm::vec2& cursor, float minRadius) {
  const float r0 = glm::length(press - center), r1 = glm::length(cursor - center);
  const float scale = std::max(r0, std::max(minRadius, 1e-3f));
  return std::clamp((scale + r1 - r0) / scale, 0.01f, 100.0f);
}

}  // namespace imps::app
