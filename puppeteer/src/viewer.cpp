// The live app's frame loop, camera and hand-posing manipulators.
#include "viewer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include "cli.h"
#include "imps/scene_writer.h"
#include "renderer.h"
#include "snapshot.h"
#include "png.h"

namespace imps::app {
namespace {

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// An orbit camera around a target: yaw about +y, pitch above the horizon, distance in metres.
struct Orbit {
  glm::vec3 target{0.0f};
  float yaw = 0.0f, pitch = 0.0f, distance = 3.0f;
  float verticalFov = 0.6f;
  Camera camera() const {
    const glm::vec3 dir(std::cos(pitch) * std::sin(yaw), std::sin(pitch), std::cos(pitch) * std::cos(yaw));
    return Camera{target + distance * dir, target, glm::vec3(0, 1, 0), verticalFov};
  }
};

// Everything the GLFW callbacks touch (reached through the window's user pointer).
struct ViewerState {
  ViewerPipeline* pipeline = nullptr;
  Hud* hud = nullptr;
  Orbit orbit;
  int width = 0, height = 0;
  bool showParticles = false;
  bool poseDirty = false;
  int selectedJoint = -1;
  enum class Drag { None, Orbit, Joint } drag = Drag::None;
  double lastX = 0, lastY = 0;
  bool screenshotRequested = false;
  bool resetRequested = false;
  bool saveRequested = false;
  std::string message;
};

ViewerState& state(GLFWwindow* w) { return *static_cast<ViewerState*>(glfwGetWindowUserPointer(w)); }

// Window pixel position of a world point, y down; false when behind the camera.
bool project(const ViewerState& s, const glm::vec3& world, glm::vec2* out) {
  const Camera cam = s.orbit.camera();
  const glm::vec4 clip = Renderer::projectionMatrix(cam, float(s.width) / float(std::max(1, s.height)), 2.0f) *
                         Renderer::viewMatrix(cam) * glm::vec4(world, 1.0f);
  if (clip.w <= 0.0f) return false;
  *out = glm::vec2((clip.x / clip.w * 0.5f + 0.5f) * float(s.width), (0.5f - clip.y / clip.w * 0.5f) * float(s.height));
  return true;
}

// The joint whose origin is drawn nearest to the cursor, within 24 pixels, or -1.
int pickJoint(const ViewerState& s, double x, double y) {
  const SkeletonCache& skeleton = s.pipeline->skeleton();
  int best = -1;
  float bestDistance = 24.0f;
  for (size_t j = 0; j < skeleton.character().joints().size(); ++j) {
    glm::vec2 p;
    if (!project(s, skeleton.world(int(j)).translation, &p)) continue;
    const float d = glm::length(p - glm::vec2(float(x), float(y)));
    if (d < bestDistance) bestDistance = d, best = int(j);
  }
  return best;
}

// The manipulator: turns the picked joint about the view axis through its origin by the angle the cursor swept
// around the joint's position on screen (counter-clockwise on screen = counter-clockwise seen from the camera).
void rotateJoint(ViewerState& s, double x0, double y0, double x1, double y1) {
  SkeletonCache& skeleton = s.pipeline->skeleton();
  const int j = s.selectedJoint;
  const glm::vec3 origin = skeleton.world(j).translation;
  glm::vec2 c;
  if (!project(s, origin, &c)) return;
  const float a0 = std::atan2(-(float(y0) - c.y), float(x0) - c.x);
  const float a1 = std::atan2(-(float(y1) - c.y), float(x1) - c.x);
  const float angle = a1 - a0;
  const glm::vec3 axis = glm::normalize(s.orbit.camera().eye - origin);  // towards the viewer
  const int parent = skeleton.character().joints()[size_t(j)].parent;
  const glm::quat parentWorld = parent >= 0 ? skeleton.world(parent).rotation : glm::quat(1, 0, 0, 0);
  // world(j) = parentWorld * local(j); turning world(j) by q gives local' = parentWorld^-1 * q * parentWorld * local.
  const glm::quat q = glm::angleAxis(angle, axis);
  skeleton.setRotation(j, glm::normalize(glm::inverse(parentWorld) * q * parentWorld * skeleton.local(j).rotation));
  s.poseDirty = true;
}

void onMouseButton(GLFWwindow* w, int button, int action, int /*mods*/) {
  ViewerState& s = state(w);
  if (action == GLFW_RELEASE) {
    s.drag = ViewerState::Drag::None;
    return;
  }
  if (s.hud && s.hud->wantsMouse()) return;
  glfwGetCursorPos(w, &s.lastX, &s.lastY);
  if (button == GLFW_MOUSE_BUTTON_LEFT) {
    const int j = pickJoint(s, s.lastX, s.lastY);
    if (j >= 0) s.selectedJoint = j;
    s.drag = j >= 0 || (s.selectedJoint >= 0 && (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS))
                 ? ViewerState::Drag::Joint
                 : ViewerState::Drag::Orbit;
  } else {
    s.drag = ViewerState::Drag::Orbit;
  }
}

void onCursor(GLFWwindow* w, double x, double y) {
  ViewerState& s = state(w);
  if (s.drag == ViewerState::Drag::Orbit) {
    s.orbit.yaw -= float(x - s.lastX) * 0.008f;
    s.orbit.pitch = std::clamp(s.orbit.pitch + float(y - s.lastY) * 0.008f, -1.5f, 1.5f);
  } else if (s.drag == ViewerState::Drag::Joint && s.selectedJoint >= 0) {
    rotateJoint(s, s.lastX, s.lastY, x, y);
  }
  s.lastX = x, s.lastY = y;
}

void onScroll(GLFWwindow* w, double /*dx*/, double dy) {
  ViewerState& s = state(w);
  if (s.hud && s.hud->wantsMouse()) return;
  s.orbit.distance = std::clamp(s.orbit.distance * std::pow(0.9f, float(dy)), 0.05f, 100.0f);
}

void onKey(GLFWwindow* w, int key, int /*scancode*/, int action, int /*mods*/) {
  if (action != GLFW_PRESS) return;
  ViewerState& s = state(w);
  const int joints = int(s.pipeline->character().joints().size());
  switch (key) {
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    case GLFW_KEY_R: s.resetRequested = true; break;
    case GLFW_KEY_S: s.saveRequested = true; break;
    case GLFW_KEY_P: s.showParticles = !s.showParticles; break;
    case GLFW_KEY_M:
      s.pipeline->setPolygonizer(s.pipeline->polygonizer() == Polygonizer::Particles ? Polygonizer::MarchingCubes
                                                                                     : Polygonizer::Particles);
      break;
    case GLFW_KEY_F12:
    case GLFW_KEY_C: s.screenshotRequested = true; break;
    case GLFW_KEY_BACKSPACE:
      s.pipeline->skeleton().resetPose();
      s.poseDirty = true;
      s.message = "rest pose";
      break;
    case GLFW_KEY_O: s.message = "recording: not available yet in the app (use `puppeteer record`)"; break;
    case GLFW_KEY_K: s.message = "re-calibrate: not available yet in the app (use `puppeteer calibrate`)"; break;
    case GLFW_KEY_LEFT_BRACKET: s.selectedJoint = joints > 0 ? (s.selectedJoint + joints - 1) % joints : -1; break;
    case GLFW_KEY_RIGHT_BRACKET: s.selectedJoint = joints > 0 ? (s.selectedJoint + 1) % joints : -1; break;
    case GLFW_KEY_0: s.selectedJoint = -1; break;
    default:
      if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9 && key - GLFW_KEY_1 < joints) s.selectedJoint = key - GLFW_KEY_1;
      break;
  }
}

void onFramebufferSize(GLFWwindow* w, int width, int height) {
  ViewerState& s = state(w);
  s.width = width, s.height = height;
}

// Median and 99th percentile of `values` (copied; empty gives -1).
std::pair<double, double> medianP99(std::vector<double> values) {
  if (values.empty()) return {-1.0, -1.0};
  auto at = [&](double q) {
    const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * double(values.size() - 1) + 0.5));
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(k), values.end());
    return values[k];
  };
  const double median = at(0.5);
  return {median, at(0.99)};
}

struct GlfwSession {
  bool ok = false;
  GlfwSession() { ok = glfwInit() == GLFW_TRUE; }
  ~GlfwSession() {
    if (ok) glfwTerminate();
  }
};

void onGlfwError(int code, const char* description) { std::fprintf(stderr, "puppeteer: GLFW error %d: %s\n", code, description); }

}  // namespace

int runViewer(ViewerPipeline& pipeline, PoseSource* source, const ViewerOptions& options) {
  glfwSetErrorCallback(onGlfwError);
  GlfwSession glfw;
  if (!glfw.ok) {
    std::fprintf(stderr, "puppeteer: error: cannot initialise GLFW (no display? try xvfb-run -a)\n");
    return kExitIoError;
  }
  const bool headless = options.frames > 0;
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_RESIZABLE, headless ? GLFW_FALSE : GLFW_TRUE);
  auto open = [&](int samples) {
    glfwWindowHint(GLFW_SAMPLES, samples);
    GLFWwindow* w = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (w) glfwMakeContextCurrent(w);
    return w;
  };
  GLFWwindow* window = open(options.msaaSamples < 0 ? 4 : options.msaaSamples);
  if (window && options.msaaSamples < 0) {
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const std::string name = renderer ? renderer : "";
    if (name.find("llvmpipe") != std::string::npos || name.find("softpipe") != std::string::npos) {
      glfwDestroyWindow(window);
      window = open(0);
    }
  }
  if (!window) {
    std::fprintf(stderr, "puppeteer: error: cannot open a window with an OpenGL 3.3 core context\n");
    return kExitIoError;
  }
  glfwSwapInterval(headless || !options.vsync ? 0 : 1);

  ViewerState s;
  s.pipeline = &pipeline;
  s.showParticles = options.showParticles;
  glfwGetFramebufferSize(window, &s.width, &s.height);
  glfwSetWindowUserPointer(window, &s);
  glfwSetMouseButtonCallback(window, onMouseButton);
  glfwSetCursorPosCallback(window, onCursor);
  glfwSetScrollCallback(window, onScroll);
  glfwSetKeyCallback(window, onKey);
  glfwSetFramebufferSizeCallback(window, onFramebufferSize);

  int exitCode = kExitOk;
  {
    auto renderer = std::make_unique<Renderer>();
    if (!renderer->ok()) {
      std::fprintf(stderr, "puppeteer: error: %s\n", renderer->error().c_str());
      glfwDestroyWindow(window);
      return kExitIoError;
    }
    std::unique_ptr<Hud> hud = options.hud ? std::make_unique<Hud>(window) : nullptr;
    s.hud = hud.get();

    // First pose and settled surface; the camera frames the character's rest pose from the front three-quarter
    // view, so a posed character (or a replay) does not move the camera.
    int64_t arrivalNs = 0;
    if (source && source->poll(pipeline.skeleton(), &arrivalNs)) pipeline.skeleton().update();
    pipeline.frame();
    {
      const MeshBounds box = pipeline.restBounds().empty() ? bounds(pipeline.mesh()) : pipeline.restBounds();
      const Camera cam = frameBox(box, kFrontThreeQuarter, float(s.width) / float(std::max(1, s.height)));
      const glm::vec3 d = glm::normalize(cam.eye - cam.target);
      s.orbit.target = cam.target;
      s.orbit.distance = glm::length(cam.eye - cam.target);
      s.orbit.yaw = std::atan2(d.x, d.z);
      s.orbit.pitch = std::asin(std::clamp(d.y, -1.0f, 1.0f));
      s.orbit.verticalFov = cam.verticalFov;
      renderer->setSceneRadius(box.empty() ? 1.0f : 0.5f * glm::length(box.max - box.min));
    }

    HudInfo info;
    std::vector<double> latencies, frameTimes;  // ms
    std::vector<double> allLatencies;
    const int64_t loopStart = steadyNowNs();
    int64_t windowStart = loopStart, lastFrameEnd = loopStart;
    int framesInWindow = 0, frame = 0, screenshotCount = 0;
    bool havePendingArrival = false;
    while (!glfwWindowShouldClose(window)) {
      glfwPollEvents();
      // 1. Newest pose: never waits for the source.
      int64_t newArrival = 0;
      if (source && source->poll(pipeline.skeleton(), &newArrival)) {
        s.poseDirty = true;
        arrivalNs = newArrival;
        havePendingArrival = newArrival > 0;
      }
      if (s.poseDirty) {
        pipeline.skeleton().update();
        s.poseDirty = false;
      }
      if (s.resetRequested) {
        pipeline.resetPolygonizer();
        s.resetRequested = false;
        s.message = "polygonizer reset";
      }
      // 2. Polygonize, 3. upload, 4. draw.
      pipeline.frame();
      renderer->uploadMesh(pipeline.mesh());
      if (s.showParticles && pipeline.polygonizer() == Polygonizer::Particles)
        renderer->uploadParticles(pipeline.tesselator().particles().positions);
      const bool drawParticles = s.showParticles && pipeline.polygonizer() == Polygonizer::Particles;
      renderer->draw(s.orbit.camera(), s.width, s.height, drawParticles);

      // HUD.
      const TesselatorStats& ts = pipeline.tesselator().stats();
      info.polygonizer = pipeline.polygonizer() == Polygonizer::Particles ? "particles" : "Marching Cubes";
      info.simulateMs = ts.simulateMs, info.addDeleteMs = ts.addDeleteMs, info.meshMs = ts.meshMs;
      info.marchingCubesMs = pipeline.marchingCubesStats().milliseconds;
      info.updatesPerRender = pipeline.updatesPerRender();
      info.particles = pipeline.polygonizer() == Polygonizer::Particles ? ts.particles : 0;
      info.triangles = pipeline.mesh().triangleCount();
      if (source) {
        source->describe(info);
      } else {
        info.source = "hand";
        info.mapping.clear();
        info.state = "posing";
      }
      info.selectedJoint =
          s.selectedJoint >= 0 ? pipeline.character().joints()[size_t(s.selectedJoint)].name : std::string();
      info.message = s.message;
      if (hud) hud->draw(info);

      if (s.saveRequested) {
        s.saveRequested = false;
        std::string error;
        s.message = saveSceneFile(pipeline.posedScene(), options.savePath, &error) ? "saved " + options.savePath
                                                                                     : "save failed: " + error;
        std::printf("puppeteer: %s\n", s.message.c_str());
      }
      const bool lastFrame = headless && frame + 1 >= options.frames;
      if (s.screenshotRequested || (lastFrame && !options.screenshot.empty())) {
        const std::string path =
            s.screenshotRequested ? "puppeteer-screenshot-" + std::to_string(++screenshotCount) + ".png" : options.screenshot;
        s.screenshotRequested = false;
        std::string error;
        if (savePng(Renderer::readPixels(s.width, s.height), s.width, s.height, path, &error)) {
          s.message = "screenshot " + path;
        } else {
          s.message = "screenshot failed: " + error;
          std::fprintf(stderr, "puppeteer: error: %s\n", error.c_str());
          if (lastFrame) exitCode = kExitIoError;
        }
      }
      // 5. Swap; the frame is on screen once the GL has finished it.
      glfwSwapBuffers(window);
      if (source) glFinish();
      const int64_t now = steadyNowNs();
      if (havePendingArrival) {
        const double latency = double(now - arrivalNs) * 1e-6;
        latencies.push_back(latency);
        allLatencies.push_back(latency);
        havePendingArrival = false;
      }
      if (source) source->frameDone();
      if (options.printMeshHashes)
        std::printf("frame %d hash %016llx triangles %zu\n", frame, static_cast<unsigned long long>(meshHash(pipeline.mesh())),
                    pipeline.mesh().triangleCount());
      frameTimes.push_back(double(now - lastFrameEnd) * 1e-6);
      if (info.fps == 0.0 && frameTimes.back() > 0.0) info.frameMs = frameTimes.back(), info.fps = 1e3 / info.frameMs;
      lastFrameEnd = now;
      ++framesInWindow;
      ++frame;
      if (now - windowStart >= 500'000'000) {
        info.fps = framesInWindow / (double(now - windowStart) * 1e-9);
        info.frameMs = double(now - windowStart) * 1e-6 / framesInWindow;
        const auto [median, p99] = medianP99(latencies);
        info.latencyMedianMs = median, info.latencyP99Ms = p99;
        if (latencies.size() > 2000) latencies.erase(latencies.begin(), latencies.end() - 1000);
        windowStart = now, framesInWindow = 0;
      }
      if (lastFrame) break;
    }

    // Summary: frame rate over the whole loop (the settle before it excluded).
    const double seconds = double(lastFrameEnd - loopStart) * 1e-9;
    const auto [frameMedian, frameP99] = medianP99(frameTimes);
    std::printf("puppeteer: %d frames in %.2f s: %.1f FPS (frame time median %.1f ms, p99 %.1f ms), %zu triangles, %dx%d\n",
                frame, seconds, seconds > 0 ? frame / seconds : 0.0, frameMedian, frameP99,
                pipeline.mesh().triangleCount(), s.width, s.height);
    if (!allLatencies.empty()) {
      const auto [median, p99] = medianP99(allLatencies);
      std::printf("puppeteer: sample-to-screen latency over %zu frames: median %.1f ms, p99 %.1f ms\n",
                  allLatencies.size(), median, p99);
    }
    s.hud = nullptr;
  }
  glfwDestroyWindow(window);
  return exitCode;
}

}  // namespace imps::app
