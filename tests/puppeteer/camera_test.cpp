// SPDX-License-Identifier: MIT
// The camera without a window: its basis and matrices agree with each other, known points land on known pixels, a
// framed box lies inside the picture at any aspect ratio, the orbit round-trips through eye/target, turning and
// zooming keep their limits, and a pick ray through a projected point passes through that point.
#include "camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include <glm/geometric.hpp>

namespace imps::app {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

void expectNear(const glm::vec3& a, const glm::vec3& b, float tolerance = 1e-4f) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

glm::vec2 project(const ScreenView& v, const glm::vec3& p) {
  glm::vec2 out(-1.0f);
  EXPECT_TRUE(projectToWindow(v, p, &out));
  return out;
}

// The eight corners of a box.
std::vector<glm::vec3> corners(const MeshBounds& box) {
  std::vector<glm::vec3> out;
  for (int i = 0; i < 8; ++i)
    out.emplace_back(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z);
  return out;
}

TEST(Camera, BasisIsOrthonormalAndFollowsThePose) {
  const Camera front{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f};
  const CameraBasis b = front.basis();
  expectNear(b.forward, {0, 0, -1});
  expectNear(b.right, {1, 0, 0});
  expectNear(b.up, {0, 1, 0});
  EXPECT_FLOAT_EQ(front.distance(), 5.0f);
  // A tilted `up` is made orthogonal to the view direction; the basis stays right-handed.
  const Camera oblique{{2, 1.5f, 4}, {0, 0.8f, 0}, {0.3f, 1, 0.2f}, 0.6f};
  const CameraBasis o = oblique.basis();
  EXPECT_NEAR(glm::length(o.right), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::length(o.up), 1.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(o.right, o.up), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::dot(o.up, o.forward), 0.0f, 1e-5f);
  expectNear(glm::cross(o.right, o.up), -o.forward);
  expectNear(o.forward, glm::normalize(oblique.target - oblique.eye));
}

TEST(Camera, ViewMatrixPutsTheEyeAtTheOriginLookingDownMinusZ) {
  const Camera c{{2, 1.5f, 4}, {0, 0.8f, 0}, {0, 1, 0}, 0.6f};
  const glm::mat4 view = c.viewMatrix();
  expectNear(glm::vec3(view * glm::vec4(c.eye, 1.0f)), {0, 0, 0});
  expectNear(glm::vec3(view * glm::vec4(c.target, 1.0f)), {0, 0, -c.distance()});
  const CameraBasis b = c.basis();
  expectNear(glm::vec3(view * glm::vec4(b.right, 0.0f)), {1, 0, 0});
  expectNear(glm::vec3(view * glm::vec4(b.up, 0.0f)), {0, 1, 0});
}

TEST(Camera, ProjectionClipPlanesHoldTheSceneAroundTheTarget) {
  const Camera c{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f};
  const float radius = 1.5f;
  const glm::mat4 vp = c.projectionMatrix(1.0f, radius) * c.viewMatrix();
  auto depth = [&](const glm::vec3& p) {
    const glm::vec4 clip = vp * glm::vec4(p, 1.0f);
    return clip.z / clip.w;
  };
  // Everything within 2 radii in front of the target and 4 behind it is inside the depth range.
  for (const float z : {2.0f * radius - 0.01f, 0.0f, -4.0f * radius + 0.01f}) {
    EXPECT_GT(depth({0, 0, z}), -1.0f) << z;
    EXPECT_LT(depth({0, 0, z}), 1.0f) << z;
  }
  // The near plane never reaches the eye, even for a scene larger than the distance.
  const glm::mat4 wide = c.projectionMatrix(1.0f, 10.0f) * c.viewMatrix();
  const glm::vec4 nearEye = wide * glm::vec4(0, 0, 4.995f, 1.0f);
  EXPECT_LT(nearEye.z / nearEye.w, -1.0f) << "a point 5 mm in front of the eye is nearer than the near plane";
  const glm::vec4 justIn = wide * glm::vec4(0, 0, 4.98f, 1.0f);
  EXPECT_LT(justIn.z / justIn.w, 1.0f);
  EXPECT_GT(justIn.z / justIn.w, -1.0f);
}

TEST(Camera, KnownPointsLandOnKnownPixels) {
  const ScreenView v = screenView(Camera{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f}, 640, 480, 2.0f);
  expectNear(v.right, {1, 0, 0});
  expectNear(v.up, {0, 1, 0});
  expectNear(v.towardsViewer, {0, 0, 1});
  const glm::vec2 centre = project(v, {0, 0, 0});
  EXPECT_NEAR(centre.x, 320.0f, 1e-3f);
  EXPECT_NEAR(centre.y, 240.0f, 1e-3f);
  // A point at the top edge of the field of view: y = 5 tan(0.3) above the target lands on row 0; the same
  // distance to the right lands 240 pixels right of the centre (square pixels).
  const float edge = 5.0f * std::tan(0.3f);
  const glm::vec2 top = project(v, {0, edge, 0});
  EXPECT_NEAR(top.x, 320.0f, 1e-3f);
  EXPECT_NEAR(top.y, 0.0f, 1e-2f);
  EXPECT_NEAR(project(v, {edge, 0, 0}).x, 560.0f, 1e-2f);
  // Behind the camera: no pixel, and the output is left alone.
  glm::vec2 behind(7.0f, 8.0f);
  EXPECT_FALSE(projectToWindow(v, {0, 0, 10}, &behind));
  EXPECT_EQ(behind, glm::vec2(7.0f, 8.0f));
}

TEST(Camera, AspectChangesWidenTheViewNotTheHeight) {
  const Camera c{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f};
  const ScreenView square = screenView(c, 480, 480, 2.0f);
  const ScreenView wide = screenView(c, 960, 480, 2.0f);
  const glm::vec3 p(0.7f, 0.4f, 0.0f);
  // The same vertical pixel, the same horizontal offset from the centre in pixels.
  EXPECT_NEAR(project(square, p).y, project(wide, p).y, 1e-3f);
  EXPECT_NEAR(project(square, p).x - 240.0f, project(wide, p).x - 480.0f, 1e-3f);
  // Sizes below 1 count as 1 (a minimised window).
  const ScreenView none = screenView(c, 0, -3, 2.0f);
  EXPECT_EQ(none.width, 1);
  EXPECT_EQ(none.height, 1);
}

TEST(Camera, PickRayPassesThroughTheProjectedPoint) {
  const ScreenView v = screenView(Camera{{2, 1.5f, 4}, {0, 0.8f, 0}, {0, 1, 0}, 0.6f}, 1280, 720, 1.2f);
  for (const glm::vec3 p : {glm::vec3(0.3f, 1.2f, -0.2f), glm::vec3(-0.7f, 0.1f, 0.4f), glm::vec3(0, 0.8f, 0)}) {
    const PickRay ray = pickRay(v, project(v, p));
    expectNear(ray.origin, {2, 1.5f, 4});
    EXPECT_NEAR(glm::length(ray.direction), 1.0f, 1e-5f);
    const glm::vec3 toP = p - ray.origin;
    const float t = glm::dot(toP, ray.direction);
    EXPECT_GT(t, 0.0f);
    EXPECT_LT(glm::length(toP - t * ray.direction), 1e-3f) << "ray misses the point it was cast through";
  }
  // And back: a point along the ray through a pixel projects to that pixel.
  const glm::vec2 pixel(100.0f, 650.0f);
  const PickRay ray = pickRay(v, pixel);
  const glm::vec2 back = project(v, ray.origin + 3.0f * ray.direction);
  EXPECT_NEAR(back.x, pixel.x, 0.05f);
  EXPECT_NEAR(back.y, pixel.y, 0.05f);
}

TEST(Camera, FramedBoxLiesInsideThePictureAtAnyAspect) {
  const MeshBounds box{{9.0f, -1.0f, -2.0f}, {14.0f, 3.0f, 1.0f}};
  for (const float aspect : {0.5f, 1.0f, 16.0f / 9.0f, 3.0f}) {
    for (const glm::vec3 from : {kFrontThreeQuarter, glm::vec3(0, 0, 1), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0)}) {
      const Camera c = frameBox(box, from, aspect);
      expectNear(c.target, 0.5f * (box.min + box.max));
      expectNear(glm::normalize(c.eye - c.target), glm::normalize(from));
      const int height = 400, width = int(std::lround(400.0f * aspect));
      const ScreenView v = screenView(c, width, height, sceneRadius(box));
      float xMin = 1e9f, xMax = -1e9f, yMin = 1e9f, yMax = -1e9f;
      for (const glm::vec3& p : corners(box)) {
        const glm::vec2 px = project(v, p);
        xMin = std::min(xMin, px.x), xMax = std::max(xMax, px.x), yMin = std::min(yMin, px.y),
        yMax = std::max(yMax, px.y);
      }
      EXPECT_GE(xMin, 0.0f) << aspect;
      EXPECT_LE(xMax, float(width)) << aspect;
      EXPECT_GE(yMin, 0.0f) << aspect;
      EXPECT_LE(yMax, float(height)) << aspect;
      // Not lost in the distance: the box spans at least a third of the picture in one direction.
      EXPECT_GT(std::max((xMax - xMin) / float(width), (yMax - yMin) / float(height)), 0.33f) << aspect;
    }
  }
  // Looking straight down y, "up" becomes -z; an empty box frames the unit cube at the origin.
  EXPECT_EQ(frameBox(box, {0, 1, 0}).up, glm::vec3(0, 0, -1));
  EXPECT_EQ(frameBox(MeshBounds{}).target, glm::vec3(0.0f));
  EXPECT_FLOAT_EQ(sceneRadius(MeshBounds{}), 1.0f);
  EXPECT_NEAR(sceneRadius(MeshBounds{{0, 0, 0}, {2, 0, 0}}), 1.0f, 1e-6f);
}

TEST(Camera, OrbitRoundTripsThroughEyeAndTarget) {
  for (const float yaw : {0.0f, 0.7f, -2.5f, kPi}) {
    for (const float pitch : {0.0f, 0.4f, -1.2f}) {
      OrbitCamera o;
      o.target = {0.3f, 1.1f, -0.4f};
      o.yaw = yaw, o.pitch = pitch, o.distance = 2.5f, o.verticalFov = 0.5f;
      const Camera c = o.camera();
      EXPECT_NEAR(c.distance(), 2.5f, 1e-5f);
      EXPECT_EQ(c.target, o.target);
      EXPECT_EQ(c.up, glm::vec3(0, 1, 0));
      const OrbitCamera back = OrbitCamera::around(c);
      EXPECT_NEAR(std::remainder(back.yaw - yaw, 2.0f * kPi), 0.0f, 1e-4f) << yaw << " " << pitch;  // same angle
      EXPECT_NEAR(back.pitch, pitch, 1e-4f);
      EXPECT_NEAR(back.distance, 2.5f, 1e-5f);
      EXPECT_EQ(back.verticalFov, 0.5f);
      expectNear(back.camera().eye, c.eye);
    }
  }
  // yaw 0, pitch 0: on +z looking down -z.
  OrbitCamera o;
  expectNear(o.camera().eye, {0, 0, 3});
}

TEST(Camera, TurnAndZoomKeepTheirLimits) {
  OrbitCamera o;
  // Dragging right moves the camera to the left of the subject as seen from the front: yaw decreases.
  o.turn(100.0f, 0.0f);
  EXPECT_LT(o.yaw, 0.0f);
  EXPECT_EQ(o.pitch, 0.0f);
  EXPECT_LT(o.camera().eye.x, 0.0f);
  // Dragging down raises the camera, never past the pole.
  o.turn(0.0f, 50.0f);
  EXPECT_GT(o.pitch, 0.0f);
  EXPECT_GT(o.camera().eye.y, 0.0f);
  o.turn(0.0f, 1e5f);
  EXPECT_FLOAT_EQ(o.pitch, 1.5f);
  o.turn(0.0f, -1e5f);
  EXPECT_FLOAT_EQ(o.pitch, -1.5f);
  // Turning keeps the distance; zooming keeps the direction.
  const glm::vec3 direction = glm::normalize(o.camera().eye - o.target);
  o.zoom(1.0f);
  EXPECT_NEAR(o.distance, 2.7f, 1e-5f);
  o.zoom(-1.0f);
  EXPECT_NEAR(o.distance, 3.0f, 1e-5f);
  expectNear(glm::normalize(o.camera().eye - o.target), direction);
  o.zoom(1000.0f);
  EXPECT_FLOAT_EQ(o.distance, 0.05f);
  o.zoom(-1000.0f);
  EXPECT_FLOAT_EQ(o.distance, 100.0f);
}

TEST(Camera, InitialOrbitIsTheFramedCamera) {
  const MeshBounds box{{-0.3f, 0.0f, -0.2f}, {0.3f, 1.8f, 0.2f}};
  float radius = 0.0f;
  const OrbitCamera o = initialOrbit(box, 1280, 720, &radius);
  const Camera framed = frameBox(box, kFrontThreeQuarter, 1280.0f / 720.0f);
  expectNear(o.camera().eye, framed.eye, 1e-4f);
  expectNear(o.camera().target, framed.target);
  EXPECT_FLOAT_EQ(radius, sceneRadius(box));
  EXPECT_NO_FATAL_FAILURE(initialOrbit(box, 640, 0, nullptr));  // a zero height does not divide by zero
  EXPECT_TRUE(std::isfinite(initialOrbit(box, 640, 0, nullptr).distance));
}

TEST(Camera, PixelsToAngle) {
  // Half the window's height subtends half the vertical field of view.
  EXPECT_NEAR(pixelsToAngle(240.0f, 480, 0.6f), 0.3f, 1e-5f);
  EXPECT_NEAR(pixelsToAngle(0.0f, 480, 0.6f), 0.0f, 1e-7f);
  // Consistent with the projection: a point `pixels` above the centre is seen at that angle from the axis.
  const ScreenView v = screenView(Camera{{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.6f}, 640, 480, 2.0f);
  const PickRay ray = pickRay(v, {320.0f, 240.0f - 100.0f});
  EXPECT_NEAR(std::acos(glm::dot(ray.direction, glm::vec3(0, 0, -1))), pixelsToAngle(100.0f, 480, 0.6f), 1e-4f);
}

}  // namespace
}  // namespace imps::app
