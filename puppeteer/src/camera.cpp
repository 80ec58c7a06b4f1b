// SPDX-License-Identifier: MIT
// The camera: pose, lens, matrices, framing, the orbit and the world ↔ window mapping (see camera.h).
#include "camera.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

namespace imps::app {

CameraBasis Camera::basis() const {
  CameraBasis b;
  b.forward = glm::normalize(target - eye);
  b.right = glm::normalize(glm::cross(b.forward, up));
  b.up = glm::cross(b.right, b.forward);
  return b;
}

float Camera::distance() const { return glm::length(eye - target); }

glm::mat4 Camera::viewMatrix() const { return glm::lookAt(eye, target, up); }

glm::mat4 Camera::projectionMatrix(float aspect, float sceneRadius) const {
  const float d = distance();
  const float nearPlane = std::max(0.01f, d - 2.0f * sceneRadius);
  const float farPlane = d + 4.0f * sceneRadius + 1.0f;
  return glm::perspective(verticalFov, aspect, nearPlane, farPlane);
}

Camera frameBox(const MeshBounds& box, glm::vec3 fromDirection, float aspect, float verticalFov, float margin) {
  const glm::vec3 lo = box.empty() ? glm::vec3(-0.5f) : box.min;
  const glm::vec3 hi = box.empty() ? glm::vec3(0.5f) : box.max;
  const glm::vec3 centre = 0.5f * (lo + hi);
  const float radius = std::max(0.5f * glm::length(hi - lo), 1e-4f);
  const float halfY = 0.5f * verticalFov;
  const float halfX = std::atan(std::tan(halfY) * aspect);
  const float distance = radius * std::max(margin, 1.0f) / std::sin(std::min(halfX, halfY));
  const glm::vec3 direction = glm::normalize(fromDirection);
  Camera camera;
  camera.target = centre;
  camera.eye = centre + direction * distance;
  camera.verticalFov = verticalFov;
  // Looking straight down or up the y axis, y cannot be "up"; use -z (the front of the subject at the bottom).
  camera.up = std::abs(direction.y) > 0.999f ? glm::vec3(0.0f, 0.0f, -1.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
  return camera;
}

Camera frameMesh(const Mesh& mesh, glm::vec3 fromDirection, float aspect) {
  return frameBox(bounds(mesh), fromDirection, aspect);
}

float sceneRadius(const MeshBounds& box) { return box.empty() ? 1.0f : 0.5f * glm::length(box.max - box.min); }

Camera OrbitCamera::camera() const {
  const glm::vec3 dir(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
  return Camera{target + distance * dir, target, glm::vec3(0, 1, 0), verticalFov};
}

OrbitCamera OrbitCamera::around(const Camera& camera) {
  const glm::vec3 d = glm::normalize(camera.eye - camera.target);
  OrbitCamera orbit;
  orbit.target = camera.target;
  orbit.distance = glm::length(camera.eye - camera.target);
  orbit.yaw = std::atan2(d.x, d.z);
  orbit.pitch = std::asin(std::clamp(d.y, -1.0f, 1.0f));
  orbit.verticalFov = camera.verticalFov;
  return orbit;
}

void OrbitCamera::turn(float dx, float dy) {
  yaw -= dx * 0.008f;
  pitch = std::clamp(pitch + dy * 0.008f, -1.5f, 1.5f);
}

void OrbitCamera::zoom(float steps) { distance = std::clamp(distance * std::pow(0.9f, steps), 0.05f, 100.0f); }

OrbitCamera initialOrbit(const MeshBounds& box, int width, int height, float* radius) {
  const OrbitCamera orbit =
      OrbitCamera::around(frameBox(box, kFrontThreeQuarter, float(width) / float(std::max(1, height))));
  if (radius) *radius = sceneRadius(box);
  return orbit;
}

ScreenView screenView(const Camera& camera, int width, int height, float sceneRadius) {
  ScreenView v;
  v.width = std::max(1, width), v.height = std::max(1, height);
  v.viewProjection = camera.projectionMatrix(float(v.width) / float(v.height), sceneRadius) * camera.viewMatrix();
  const CameraBasis b = camera.basis();
  v.right = b.right;
  v.up = b.up;
  v.towardsViewer = -b.forward;
  v.eye = camera.eye;
  return v;
}

bool projectToWindow(const ScreenView& view, const glm::vec3& world, glm::vec2* pixel) {
  const glm::vec4 clip = view.viewProjection * glm::vec4(world, 1.0f);
  if (clip.w <= 0.0f) return false;
  *pixel = glm::vec2((clip.x / clip.w * 0.5f + 0.5f) * float(view.width),
                     (0.5f - clip.y / clip.w * 0.5f) * float(view.height));
  return true;
}

PickRay pickRay(const ScreenView& view, const glm::vec2& pixel) {
  // The pixel at the near and far planes, unprojected; the ray starts at the eye.
  const glm::mat4 inverse = glm::inverse(view.viewProjection);
  const float ndcX = pixel.x / float(view.width) * 2.0f - 1.0f;
  const float ndcY = 1.0f - pixel.y / float(view.height) * 2.0f;
  glm::vec4 nearPoint = inverse * glm::vec4(ndcX, ndcY, -1.0f, 1.0f);
  glm::vec4 farPoint = inverse * glm::vec4(ndcX, ndcY, 1.0f, 1.0f);
  nearPoint /= nearPoint.w;
  farPoint /= farPoint.w;
  return PickRay{view.eye, glm::normalize(glm::vec3(farPoint - nearPoint))};
}

float pixelsToAngle(float pixels, int windowHeight, float verticalFov) {
  return std::atan(pixels / (0.5f * float(std::max(1, windowHeight))) * std::tan(0.5f * verticalFov));
}

}  // namespace imps::app
