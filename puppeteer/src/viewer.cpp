// SPDX-License-Identifier: MIT
// The live app's window, input callbacks and frame loop.
#include "viewer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>

#include "camera.h"
#include "cli.h"
#include "frame_stats.h"
#include "interrupts.h"
#include "imps/scene_writer.h"
#include "manipulator.h"
#include "modeller.h"
#include "modeller_menu.h"
#include "painter.h"
#include "png.h"
#include "renderer.h"
#include "snapshot.h"
#include "imps/clock.h"

namespace imps::app {
namespace {

// Everything the GLFW callbacks (and the scripted input) touch, reached through the window's user pointer.
struct ViewerState {
  ViewerPipeline* pipeline = nullptr;
  PoseSource* source = nullptr;
  Hud* hud = nullptr;
  Modeller* modeller = nullptr;
  OrbitCamera orbit;
  float sceneRadius = 2.0f;
  int width = 0, height = 0;
  bool showParticles = false;
  float pointSize = 0.0f;  // particle points, pixels (0: the renderer's default)
  bool poseDirty = false;
  bool orbiting = false;  // a drag that turns the camera (else the modeller has it, if it grabbed anything)
  double lastX = 0, lastY = 0;
  bool screenshotRequested = false;
  bool resetRequested = false;
  bool saveRequested = false;
  std::string message;
  // 3D painting (`t`; painter.h): the brush, whether a stroke is on, which textures changed since the last upload
  // and since the start (saved under new names), and the modeller's state to restore when painting ends.
  bool painting = false;
  Brush brush;
  bool stroking = false;
  int dabs = 0;
  std::vector<bool> painted;
  bool texturesDirty = false;
  bool modellerWasEnabled = true;
};

ViewerState& state(GLFWwindow* w) { return *static_cast<ViewerState*>(glfwGetWindowUserPointer(w)); }

ScreenView currentView(const ViewerState& s) {
  return screenView(s.orbit.camera(), s.width, s.height, s.sceneRadius);
}

// Shows and prints a message (a key's result, an edit).
void report(ViewerState& s, std::string message) {
  if (message.empty()) return;
  std::printf("puppeteer: %s\n", message.c_str());
  std::fflush(stdout);
  s.message = std::move(message);
}

// One brush dab where the ray through window pixel (x, y) meets the current mesh (painter.h).
void paintAt(ViewerState& s, double x, double y) {
  const Mesh& mesh = s.pipeline->mesh();
  const auto hit = intersectMesh(mesh, pickRay(currentView(s), glm::vec2(float(x), float(y))));
  if (!hit) return;
  const int image = paintDab(mesh, *hit, s.brush, s.pipeline->mutableTextures());
  if (image < 0) return;
  s.painted.resize(s.pipeline->textures().size());
  s.painted[size_t(image)] = true;
  s.texturesDirty = true;
  ++s.dabs;
}

// Dabs along the cursor's path from the last position, one every two pixels, so a fast stroke has no gaps.
void paintAlong(ViewerState& s, double x, double y) {
  const double length = std::hypot(x - s.lastX, y - s.lastY);
  const int steps = std::max(1, int(std::ceil(length / 2.0)));
  for (int i = 1; i <= steps; ++i) {
    const double t = double(i) / double(steps);
    paintAt(s, s.lastX + t * (x - s.lastX), s.lastY + t * (y - s.lastY));
  }
}

void togglePainting(ViewerState& s) {
  s.painting = !s.painting;
  if (s.painting) {
    s.modellerWasEnabled = s.modeller->enabled();
    s.modeller->setEnabled(false);  // manipulators hide while painting
  } else {
    s.modeller->setEnabled(s.modellerWasEnabled);
  }
  report(s, s.painting ? "paint mode (brush size " + std::to_string(s.brush.size) + ")" : "paint mode off");
}

// Left press at (x, y): the modeller grabs a handle or a bone (modeller.h); elsewhere (or any other button): orbit.
// In paint mode a left press starts a stroke instead.
void pressButton(ViewerState& s, int button, double x, double y, bool shift) {
  s.lastX = x, s.lastY = y;
  if (s.painting && button == GLFW_MOUSE_BUTTON_LEFT) {
    s.orbiting = false;
    s.stroking = true;
    s.dabs = 0;
    paintAt(s, x, y);
    return;
  }
  s.orbiting = button != GLFW_MOUSE_BUTTON_LEFT ||
               !s.modeller->press(currentView(s), glm::vec2(float(x), float(y)), shift);
}

void moveCursor(ViewerState& s, double x, double y) {
  if (s.stroking) {
    paintAlong(s, x, y);
  } else if (s.orbiting) {
    s.orbit.turn(float(x - s.lastX), float(y - s.lastY));
  } else if (s.modeller->dragging()) {
    s.modeller->drag(currentView(s), glm::vec2(float(x), float(y)));
    s.poseDirty = true;
  }
  s.lastX = x, s.lastY = y;
}

void releaseButton(ViewerState& s) {
  s.orbiting = false;
  if (s.stroking) {
    s.stroking = false;
    report(s, "painted " + std::to_string(s.dabs) + " dabs (brush size " + std::to_string(s.brush.size) + ")");
  }
  if (s.modeller->dragging()) report(s, s.modeller->release());
}

void onMouseButton(GLFWwindow* w, int button, int action, int mods) {
  ViewerState& s = state(w);
  if (action == GLFW_RELEASE) {
    releaseButton(s);
    return;
  }
  if (s.hud && s.hud->wantsMouse()) return;
  double x = 0, y = 0;
  glfwGetCursorPos(w, &x, &y);
  pressButton(s, button, x, y, (mods & GLFW_MOD_SHIFT) != 0);
}

void onCursor(GLFWwindow* w, double x, double y) { moveCursor(state(w), x, y); }

void onScroll(GLFWwindow* w, double /*dx*/, double dy) {
  ViewerState& s = state(w);
  if (s.hud && s.hud->wantsMouse()) return;
  s.orbit.zoom(float(dy));
}

void handleKey(GLFWwindow* w, ViewerState& s, int key, int mods) {
  const int joints = int(s.pipeline->character().joints().size());
  Modeller& m = *s.modeller;
  if (mods & GLFW_MOD_CONTROL) {
    // Ctrl+Z undo, Ctrl+Shift+Z (or Ctrl+Y) redo.
    if (key == GLFW_KEY_Z || key == GLFW_KEY_Y) {
      report(s, key == GLFW_KEY_Z && !(mods & GLFW_MOD_SHIFT) ? m.undo() : m.redo());
      s.poseDirty = true;
    }
    return;
  }
  switch (key) {
    case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(w, GLFW_TRUE); break;
    case GLFW_KEY_T: togglePainting(s); break;
    case GLFW_KEY_R: s.resetRequested = true; break;
    case GLFW_KEY_S: s.saveRequested = true; break;
    case GLFW_KEY_P: s.showParticles = !s.showParticles; break;
    case GLFW_KEY_M:
      s.pipeline->setPolygonizer(s.pipeline->polygonizer() == Polygonizer::Particles ? Polygonizer::MarchingCubes
                                                                                     : Polygonizer::Particles);
      break;
    case GLFW_KEY_W: m.setMode(ManipulatorMode::Translate); break;
    case GLFW_KEY_E: m.setMode(ManipulatorMode::Rotate); break;
    case GLFW_KEY_X: m.setMode(ManipulatorMode::Scale); break;
    case GLFW_KEY_F12:
    case GLFW_KEY_C: s.screenshotRequested = true; break;
    case GLFW_KEY_BACKSPACE:
      s.pipeline->skeleton().resetPose();
      s.poseDirty = true;
      s.message = "rest pose";
      break;
    case GLFW_KEY_O:
      report(s, s.source ? s.source->toggleRecording() : "recording needs a live device (puppeteer live)");
      break;
    case GLFW_KEY_K:
      report(s, s.source ? s.source->recalibrate() : "re-calibration needs a live device (puppeteer live)");
      break;
    case GLFW_KEY_LEFT_BRACKET:
      m.selectJoint(joints > 0 ? (std::max(m.selectedJoint(), 0) + joints - 1) % joints : -1);
      break;
    case GLFW_KEY_RIGHT_BRACKET: m.selectJoint(joints > 0 ? (m.selectedJoint() + 1) % joints : -1); break;
    case GLFW_KEY_0:
      if (s.painting) {
        s.brush.size = 0;
        report(s, "brush size 0 (largest)");
      } else {
        m.selectJoint(-1);
      }
      break;
    default:
      if (s.painting && key >= GLFW_KEY_1 && key <= GLFW_KEY_9) {
        s.brush.size = key - GLFW_KEY_0;
        report(s, "brush size " + std::to_string(s.brush.size));
      } else if (key >= GLFW_KEY_1 && key <= GLFW_KEY_9 && key - GLFW_KEY_1 < joints) m.selectJoint(key - GLFW_KEY_1);
      break;
  }
}

void onKey(GLFWwindow* w, int key, int /*scancode*/, int action, int mods) {
  if (action != GLFW_PRESS) return;
  handleKey(w, state(w), key, mods);
}

// Delivers a scripted event through the same handlers as the callbacks.
void deliver(GLFWwindow* w, ViewerState& s, const ScriptedEvent& e) {
  if (e.kind == ScriptedEvent::Kind::Key) {
    std::printf("puppeteer: key %s\n", e.keyName.c_str());
    handleKey(w, s, e.key, e.mods);
    return;
  }
  pressButton(s, GLFW_MOUSE_BUTTON_LEFT, e.x0, e.y0, e.shift);
  const std::string what = s.orbiting ? "orbit" : s.modeller->grabbed();
  std::printf("puppeteer: drag %.0f,%.0f -> %.0f,%.0f: %s\n", double(e.x0), double(e.y0), double(e.x1),
              double(e.y1), what.c_str());
  const int steps = std::max(1, e.steps);
  for (int i = 1; i <= steps; ++i) {
    const float t = float(i) / float(steps);
    moveCursor(s, e.x0 + t * (e.x1 - e.x0), e.y0 + t * (e.y1 - e.y0));
  }
  releaseButton(s);
}

void onFramebufferSize(GLFWwindow* w, int width, int height) {
  ViewerState& s = state(w);
  s.width = width, s.height = height;
}

// Runs ViewerPipeline::frame() on its own thread, one job at a time (--overlap): start() hands it the current
// skeleton, wait() returns once the mesh is done. Between wait() and start() the caller owns the pipeline.
class PolygonizeWorker {
 public:
  explicit PolygonizeWorker(ViewerPipeline& pipeline) : pipeline_(pipeline), thread_([this] { run(); }) {}
  ~PolygonizeWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    changed_.notify_all();
    thread_.join();
  }
  void start() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = true;
    }
    changed_.notify_all();
  }
  void wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [this] { return !busy_; });
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      changed_.wait(lock, [this] { return busy_ || stop_; });
      if (stop_) return;
      lock.unlock();
      pipeline_.frame();
      lock.lock();
      busy_ = false;
      changed_.notify_all();
    }
  }
  ViewerPipeline& pipeline_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool busy_ = false, stop_ = false;
  std::thread thread_;
};

// Every character's texture images, the main pipeline's first (appendOthers offsets the others' layers to match).
std::vector<RgbaImage> allTextures(const ViewerPipeline& pipeline, const ViewerOptions& options) {
  std::vector<RgbaImage> images = pipeline.textures();
  for (const ViewerActor& a : options.others)
    images.insert(images.end(), a.pipeline->textures().begin(), a.pipeline->textures().end());
  return images;
}

// The other characters' meshes appended to the main one, their layers naming their images in allTextures' order.
void appendOthers(Mesh& mesh, const ViewerPipeline& pipeline, const ViewerOptions& options) {
  int32_t offset = int32_t(pipeline.textures().size());
  for (const ViewerActor& a : options.others) {
    if (a.pipeline->textures().empty()) {
      appendMesh(mesh, a.pipeline->mesh());
    } else {
      Mesh other = a.pipeline->mesh();
      for (int32_t& image : other.layerImages)
        if (image >= 0) image += offset;
      appendMesh(mesh, other);
    }
    appendPosedProps(mesh, a.props, a.pipeline->skeleton());
    offset += int32_t(a.pipeline->textures().size());
  }
}

// The union of every character's rest bounds (a world's camera frames them all).
MeshBounds worldBounds(const ViewerPipeline& pipeline, const ViewerOptions& options) {
  MeshBounds box;
  auto add = [&box](const ViewerPipeline& p) {
    const MeshBounds b = p.restBounds().empty() ? bounds(p.mesh()) : p.restBounds();
    if (b.empty()) return;
    box.min = glm::min(box.min, b.min);
    box.max = glm::max(box.max, b.max);
  };
  add(pipeline);
  for (const ViewerActor& a : options.others) add(*a.pipeline);
  for (const AttachedProp& p : options.props) {
    if (p.joint >= 0) continue;
    const MeshBounds b = bounds(p.mesh);
    if (b.empty()) continue;
    box.min = glm::min(box.min, b.min);
    box.max = glm::max(box.max, b.max);
  }
  return box;
}

struct GlfwSession {
  bool ok = false;
  GlfwSession() { ok = glfwInit() == GLFW_TRUE; }
  ~GlfwSession() {
    if (ok) glfwTerminate();
  }
};

void onGlfwError(int code, const char* description) {
  std::fprintf(stderr, "puppeteer: GLFW error %d: %s\n", code, description);
}

// Opens the window with a current GL 3.3 core context, or returns null. msaaSamples < 0 asks for 4 samples and, when
// the GL turns out to be a software renderer (llvmpipe, softpipe), where multisampling costs more than the rest of
// the frame, closes that window and opens one without. Headless runs (frames > 0) get a fixed-size window.
GLFWwindow* openWindow(const ViewerOptions& options) {
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_RESIZABLE, options.frames > 0 ? GLFW_FALSE : GLFW_TRUE);
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
  return window;
}

// Fills the state the callbacks share (`s` must outlive the window's callbacks) and installs them: mouse buttons,
// cursor, scroll, keys and framebuffer size. Sets the swap interval (no vsync when headless or asked).
void installCallbacks(GLFWwindow* window, ViewerState& s, ViewerPipeline& pipeline, PoseSource* source,
                      const ViewerOptions& options) {
  glfwSwapInterval(options.frames > 0 || !options.vsync ? 0 : 1);
  s.pipeline = &pipeline;
  s.source = source;
  s.showParticles = options.showParticles;
  for (int k = 0; k < 3; ++k) s.brush.color[k] = options.brushColor[k];
  glfwGetFramebufferSize(window, &s.width, &s.height);
  glfwSetWindowUserPointer(window, &s);
  glfwSetMouseButtonCallback(window, onMouseButton);
  glfwSetCursorPosCallback(window, onCursor);
  glfwSetScrollCallback(window, onScroll);
  glfwSetKeyCallback(window, onKey);
  glfwSetFramebufferSizeCallback(window, onFramebufferSize);
}

// The first pose and a settled surface for every character, before the first frame is timed.
void settle(ViewerPipeline& pipeline, PoseSource* source, const ViewerOptions& options) {
  int64_t arrivalNs = 0;
  if (source && source->poll(pipeline.skeleton(), &arrivalNs)) pipeline.skeleton().update();
  pipeline.frame();
  for (const ViewerActor& a : options.others) {
    if (a.source && a.source->poll(a.pipeline->skeleton(), &arrivalNs)) a.pipeline->skeleton().update();
    a.pipeline->frame();
  }
}

// The first camera: the character's rest pose (a world: every character's) framed from the front three-quarter view,
// so a posed character (or a replay) does not move the camera. Sets s.orbit and s.sceneRadius.
void frameCamera(ViewerState& s, const ViewerPipeline& pipeline, const ViewerOptions& options) {
  s.orbit = options.others.empty() ? initialOrbit(pipeline, s.width, s.height, &s.sceneRadius)
                                   : initialOrbit(worldBounds(pipeline, options), s.width, s.height, &s.sceneRadius);
}

// The frame loop over a window whose renderer, HUD and modeller are ready. Each frame: input (events, script, menu
// actions), pose, polygonize, upload, draw, HUD, save / screenshot, swap, statistics; until the window closes, an
// interrupt arrives or the headless frame count is done. run() returns the exit code.
class FrameLoop {
 public:
  FrameLoop(GLFWwindow* window, ViewerState& s, ViewerPipeline& pipeline, PoseSource* source,
            const ViewerOptions& options, Renderer& renderer, Hud* hud, Modeller& modeller)
      : window_(window),
        s_(s),
        pipeline_(pipeline),
        source_(source),
        options_(options),
        renderer_(renderer),
        hud_(hud),
        modeller_(modeller),
        menu_{options.showParticles, options.pointSize},
        stats_(options.frames),
        worker_(options.overlap ? std::make_unique<PolygonizeWorker>(pipeline) : nullptr),
        props_(options.props) {}

  int run();

 private:
  void lap(FramePhase phase);
  void takeInput();
  void pollPose();
  void polygonize();
  void upload(bool drawParticles);
  void describeMesh();
  void drawHud();
  void saveIfRequested();
  void screenshotIfDue(bool lastFrame);
  void swapAndCount();
  void finishSources();

  GLFWwindow* window_;
  ViewerState& s_;
  ViewerPipeline& pipeline_;
  PoseSource* source_;
  const ViewerOptions& options_;
  Renderer& renderer_;
  Hud* hud_;
  Modeller& modeller_;
  MenuSettings menu_;
  // Menu changes, run where the pipeline is idle (after the worker's wait, with the input events).
  std::vector<std::function<void(ViewerPipeline&, Modeller&)>> menuActions_;
  HudInfo info_;
  FrameStats stats_;
  int64_t phaseStart_ = 0;
  int frame_ = 0, screenshotCount_ = 0;
  int exitCode_ = kExitOk;
  // --overlap: the worker polygonizes frame N+1 while this thread draws frame N. The pipeline and the skeleton
  // are touched here only while the worker is idle (after wait(), before start()).
  std::unique_ptr<PolygonizeWorker> worker_;
  int64_t inFlightArrival_ = 0;  // arrival of the sample whose pose is being polygonized (0: none new)
  int64_t meshArrival_ = 0;      // arrival of the sample whose mesh is about to be drawn
  uint64_t uploadedVersion_ = ~uint64_t{0};
  uint64_t describedVersion_ = ~uint64_t{0};  // the mesh describeMesh() last counted
  std::vector<AttachedProp> props_;  // moved by options.moveProps
  uint64_t propsVersion_ = 0;
};

// Ends the current phase: its time since the last lap joins the statistics.
void FrameLoop::lap(FramePhase phase) {
  if (options_.syncPhases) glFinish();  // charge the GL's deferred work to the phase that queued it
  const int64_t t = steadyNowNs();
  stats_.addPhase(phase, double(t - phaseStart_) * 1e-6);
  phaseStart_ = t;
}

// Window events, this frame's scripted events and the menu's queued changes (the worker is idle here).
void FrameLoop::takeInput() {
  glfwPollEvents();
  for (const ScriptedEvent& e : eventsAt(options_.script, frame_)) deliver(window_, s_, e);
  for (auto& action : std::exchange(menuActions_, {})) {
    action(pipeline_, modeller_);
    s_.poseDirty = true;
  }
}

// The newest pose (never waits for the source), the source's messages, and a requested polygonizer reset.
void FrameLoop::pollPose() {
  int64_t newArrival = 0;
  if (source_ && source_->poll(pipeline_.skeleton(), &newArrival)) {
    s_.poseDirty = true;
    inFlightArrival_ = newArrival;
  }
  if (source_) {
    // Already printed by the source, in order with its details.
    if (std::string m = source_->takeMessage(); !m.empty()) s_.message = std::move(m);
  }
  if (s_.poseDirty) {
    pipeline_.skeleton().update();
    s_.poseDirty = false;
  }
  if (s_.resetRequested) {
    pipeline_.resetPolygonizer();
    s_.resetRequested = false;
    s_.message = "polygonizer reset";
  }
}

// Without --overlap: the pose, then every character's surface on this thread.
void FrameLoop::polygonize() {
  pollPose();
  lap(FramePhase::Pose);
  pipeline_.frame();
  for (const ViewerActor& a : options_.others) {
    int64_t arrival = 0;
    if (a.source && a.source->poll(a.pipeline->skeleton(), &arrival)) {
      a.pipeline->skeleton().update();
      if (inFlightArrival_ == 0) inFlightArrival_ = arrival;
    }
    a.pipeline->frame();
  }
  lap(FramePhase::Polygonize);
  meshArrival_ = std::exchange(inFlightArrival_, 0);
}

// Uploads the mesh (with the props and the other characters) only when one of them changed, the particles when
// drawn, and the textures when painted.
void FrameLoop::upload(bool drawParticles) {
  if (options_.moveProps && options_.moveProps(frame_, props_)) ++propsVersion_;
  uint64_t version = pipeline_.meshVersion() * 1000003u + propsVersion_;
  for (const ViewerActor& a : options_.others) version = version * 1000003u + a.pipeline->meshVersion();
  if (version != uploadedVersion_) {
    if ((props_.empty() && options_.others.empty()) || worker_) {
      renderer_.uploadMesh(pipeline_.mesh());
    } else {
      Mesh withProps = pipeline_.mesh();  // the props posed like the character this frame
      appendPosedProps(withProps, props_, pipeline_.skeleton());
      appendOthers(withProps, pipeline_, options_);
      renderer_.uploadMesh(withProps);
    }
    uploadedVersion_ = version;
  }
  if (drawParticles) renderer_.uploadParticles(pipeline_.tesselator().particles().positions);
  if (s_.texturesDirty) {
    renderer_.uploadTextures(allTextures(pipeline_, options_));
    s_.texturesDirty = false;
  }
}

// What the HUD and the hashes say about this mesh, read before the worker rewrites it.
void FrameLoop::describeMesh() {
  const TesselatorStats& ts = pipeline_.tesselator().stats();
  const bool particles = pipeline_.polygonizer() == Polygonizer::Particles;
  info_.polygonizer = particles ? "particles" : "Marching Cubes";
  info_.simulateMs = ts.simulateMs, info_.addDeleteMs = ts.addDeleteMs, info_.meshMs = ts.meshMs;
  info_.marchingCubesMs = pipeline_.marchingCubesStats().milliseconds;
  info_.updatesPerRender = pipeline_.updatesPerRender();
  info_.particles = particles ? ts.particles : 0;
  info_.triangles = pipeline_.mesh().triangleCount();
  if (particles && pipeline_.meshVersion() != describedVersion_)
    stats_.addParticleMesh(ts.fallback, ts.cutOffParts > 0);
  describedVersion_ = pipeline_.meshVersion();
  info_.standIn = particles && ts.fallback, info_.standInCutOff = info_.standIn && ts.cutOffParts > 0;
  info_.particleMeshes = stats_.particleMeshes(), info_.standIns = stats_.standIns();
  for (const ViewerActor& a : options_.others) info_.triangles += a.pipeline->mesh().triangleCount();
  if (options_.printMeshHashes)
    std::printf("frame %d hash %016llx triangles %zu\n", frame_,
                static_cast<unsigned long long>(meshHash(pipeline_.mesh())), pipeline_.mesh().triangleCount());
}

// The HUD (when on) with the source's state, the selection, the last message, the modeller's menu and, while
// painting, the brush window; takes back what the menu changed.
void FrameLoop::drawHud() {
  if (!hud_) return;
  if (source_) {
    source_->describe(info_);
  } else {
    info_.source = "hand";
    info_.mapping.clear();
    info_.state = "posing";
  }
  info_.selectedJoint = modeller_.selected() ? targetName(pipeline_.character(), *modeller_.selected()) + " (" +
                                                   modeName(modeller_.mode()) + ")"
                                             : std::string();
  info_.message = s_.message;
  menu_.showParticles = s_.showParticles;
  info_.deviceKeys = source_ && source_->handlesDeviceKeys();
  hud_->draw(info_, [&] {
    drawModellerMenu(pipeline_, modeller_, menu_, menuActions_);
    if (s_.painting) drawBrushWindow(s_.brush);
  });
  s_.showParticles = menu_.showParticles;
  renderer_.setPointSize(menu_.pointSize);
}

// Key `s`: saves the posed scene (and the painted textures) to options.savePath.
void FrameLoop::saveIfRequested() {
  if (!s_.saveRequested) return;
  s_.saveRequested = false;
  const bool anyPainted = std::find(s_.painted.begin(), s_.painted.end(), true) != s_.painted.end();
  const auto saved = savePaintedScene(pipeline_.posedScene(), pipeline_.character(), pipeline_.textures(), s_.painted,
                                      options_.savePath);
  report(s_, saved ? "saved " + options_.savePath + (anyPainted ? " with its painted textures" : "")
                   : "save failed: " + saved.error().all().front().message);
}

// Key `c` / F12: a numbered screenshot; the last headless frame: options.screenshot (a failure there fails the run).
// The time it takes is not charged to the swap.
void FrameLoop::screenshotIfDue(bool lastFrame) {
  if (!s_.screenshotRequested && !(lastFrame && !options_.screenshot.empty())) return;
  const std::string path = s_.screenshotRequested
                               ? "puppeteer-screenshot-" + std::to_string(++screenshotCount_) + ".png"
                               : options_.screenshot;
  s_.screenshotRequested = false;
  if (auto saved = savePng(Renderer::readPixels(s_.width, s_.height), s_.width, s_.height, path); saved) {
    s_.message = "screenshot " + path;
  } else {
    const std::string& error = saved.error().all().front().message;
    s_.message = "screenshot failed: " + error;
    std::fprintf(stderr, "puppeteer: error: %s\n", error.c_str());
    if (lastFrame) exitCode_ = kExitIoError;
  }
  phaseStart_ = steadyNowNs();
}

// Swaps (with a source, waits until the GL has finished, so the frame is on screen), then counts the frame: its
// sample-to-screen latency, the sources' per-frame bookkeeping and, every half second, the HUD's figures.
void FrameLoop::swapAndCount() {
  glfwSwapBuffers(window_);
  if (source_) glFinish();
  lap(FramePhase::Swap);
  const int64_t now = phaseStart_;
  if (meshArrival_ > 0) {
    stats_.addLatency(double(now - meshArrival_) * 1e-6);
    meshArrival_ = 0;
  }
  if (source_) source_->frameDone();
  for (const ViewerActor& a : options_.others)
    if (a.source) a.source->frameDone();
  const bool windowClosed = stats_.endFrame(now);
  if (info_.fps == 0.0 && stats_.lastFrameMs() > 0.0)
    info_.frameMs = stats_.lastFrameMs(), info_.fps = 1e3 / info_.frameMs;
  ++frame_;
  if (!windowClosed) return;
  const FrameWindow& w = stats_.window();
  info_.fps = w.fps;
  info_.frameMs = w.frameMs;
  double* fields[kFramePhases] = {&info_.poseMs, &info_.polygonizeMs, &info_.uploadMs,
                                  &info_.drawMs, &info_.hudMs,        &info_.swapMs};
  for (int p = 0; p < kFramePhases; ++p) *fields[p] = w.phaseMs[size_t(p)];
  info_.latencyMedianMs = w.latencyMedianMs, info_.latencyP99Ms = w.latencyP99Ms;
}

// After the last frame: the sources close what they have open (a take); the first failing exit code wins.
void FrameLoop::finishSources() {
  if (worker_) worker_->wait();
  if (source_) report(s_, source_->finish());
  if (source_ && exitCode_ == kExitOk) exitCode_ = source_->exitCode();
  for (const ViewerActor& a : options_.others) {
    if (!a.source) continue;
    report(s_, a.source->finish());
    if (exitCode_ == kExitOk) exitCode_ = a.source->exitCode();
  }
}

int FrameLoop::run() {
  const bool headless = options_.frames > 0;
  stats_.start(steadyNowNs());
  while (!glfwWindowShouldClose(window_) && !interruptRequested()) {
    phaseStart_ = steadyNowNs();
    if (worker_) {
      worker_->wait();  // frame N's mesh (its time is the polygonize phase's: what the draw did not hide)
      lap(FramePhase::Polygonize);
      meshArrival_ = std::exchange(inFlightArrival_, 0);
    }
    takeInput();
    phaseStart_ = steadyNowNs();
    if (!worker_) polygonize();
    const bool drawParticles = s_.showParticles && pipeline_.polygonizer() == Polygonizer::Particles;
    upload(drawParticles);
    lap(FramePhase::Upload);
    describeMesh();
    if (worker_) {
      phaseStart_ = steadyNowNs();
      pollPose();
      lap(FramePhase::Pose);
      worker_->start();  // frame N+1's mesh, from the pose just taken
    }
    renderer_.draw(s_.orbit.camera(), s_.width, s_.height, drawParticles);
    renderer_.drawOverlay(handleOverlay(currentView(s_), modeller_.handles(), modeller_.selected(), modeller_.mode()),
                          s_.width, s_.height);
    lap(FramePhase::Draw);
    drawHud();
    lap(FramePhase::Hud);
    saveIfRequested();
    const bool lastFrame = headless && frame_ + 1 >= options_.frames;
    screenshotIfDue(lastFrame);
    swapAndCount();
    if (lastFrame) break;
  }
  finishSources();
  // Frame rate over the whole loop (the settle before it excluded).
  std::fputs(summaryText(stats_.summary(), info_.triangles, s_.width, s_.height, options_.syncPhases).c_str(), stdout);
  return exitCode_;
}

// The window's renderer, HUD and modeller, the settled first frame and camera, then the frame loop. Returns the
// exit code; everything it made is gone (the HUD before the window) when it returns.
int runFrames(GLFWwindow* window, ViewerState& s, ViewerPipeline& pipeline, PoseSource* source,
              const ViewerOptions& options) {
  auto renderer = std::make_unique<Renderer>();
  if (!renderer->ok()) {
    std::fprintf(stderr, "puppeteer: error: %s\n", renderer->error().c_str());
    return kExitIoError;
  }
  renderer->uploadTextures(allTextures(pipeline, options));
  std::unique_ptr<Hud> hud = options.hud ? std::make_unique<Hud>(window) : nullptr;
  s.hud = hud.get();
  settle(pipeline, source, options);
  frameCamera(s, pipeline, options);
  renderer->setSceneRadius(s.sceneRadius);
  renderer->setPointSize(options.pointSize);
  Modeller modeller(pipeline);
  modeller.setEnabled(options.manipulators);
  s.modeller = &modeller;
  const int exitCode = FrameLoop(window, s, pipeline, source, options, *renderer, hud.get(), modeller).run();
  s.hud = nullptr;
  s.modeller = nullptr;
  return exitCode;
}

}  // namespace

// The steps, top to bottom: GLFW, the window (with the MSAA fallback), the callbacks, then the renderer, the first
// frame and camera and the frame loop (runFrames), the exit summary at its end.
int runViewer(ViewerPipeline& pipeline, PoseSource* source, const ViewerOptions& options) {
  glfwSetErrorCallback(onGlfwError);
  GlfwSession glfw;
  if (!glfw.ok) {
    std::fprintf(stderr, "puppeteer: error: cannot initialise GLFW (no display? try xvfb-run -a)\n");
    return kExitIoError;
  }
  GLFWwindow* window = openWindow(options);
  if (!window) {
    std::fprintf(stderr, "puppeteer: error: cannot open a window with an OpenGL 3.3 core context\n");
    return kExitIoError;
  }
  ViewerState s;
  installCallbacks(window, s, pipeline, source, options);
  catchInterrupts();
  const int exitCode = runFrames(window, s, pipeline, source, options);
  glfwDestroyWindow(window);
  return exitCode;
}

}  // namespace imps::app
