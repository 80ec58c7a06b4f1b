// SPDX-License-Identifier: MIT
// The live app's frame loop, camera and hand-posing manipulators.
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

#include "cli.h"
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
    s.orbit.yaw -= float(x - s.lastX) * 0.008f;
    s.orbit.pitch = std::clamp(s.orbit.pitch + float(y - s.lastY) * 0.008f, -1.5f, 1.5f);
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
  s.orbit.distance = std::clamp(s.orbit.distance * std::pow(0.9f, float(dy)), 0.05f, 100.0f);
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

  int exitCode = kExitOk;
  catchInterrupts();
  {
    auto renderer = std::make_unique<Renderer>();
    if (!renderer->ok()) {
      std::fprintf(stderr, "puppeteer: error: %s\n", renderer->error().c_str());
      glfwDestroyWindow(window);
      return kExitIoError;
    }
    renderer->uploadTextures(allTextures(pipeline, options));
    std::unique_ptr<Hud> hud = options.hud ? std::make_unique<Hud>(window) : nullptr;
    s.hud = hud.get();

    // First pose and settled surface; the camera frames the character's rest pose from the front three-quarter
    // view, so a posed character (or a replay) does not move the camera.
    int64_t arrivalNs = 0;
    if (source && source->poll(pipeline.skeleton(), &arrivalNs)) pipeline.skeleton().update();
    pipeline.frame();
    for (const ViewerActor& a : options.others) {
      if (a.source && a.source->poll(a.pipeline->skeleton(), &arrivalNs)) a.pipeline->skeleton().update();
      a.pipeline->frame();
    }
    s.orbit = options.others.empty() ? initialOrbit(pipeline, s.width, s.height, &s.sceneRadius)
                                     : initialOrbit(worldBounds(pipeline, options), s.width, s.height, &s.sceneRadius);
    renderer->setSceneRadius(s.sceneRadius);
    renderer->setPointSize(options.pointSize);
    Modeller modeller(pipeline);
    modeller.setEnabled(options.manipulators);
    s.modeller = &modeller;
    MenuSettings menu{options.showParticles, options.pointSize};
    // Menu changes, run where the pipeline is idle (after the worker's wait, with the input events).
    std::vector<std::function<void(ViewerPipeline&, Modeller&)>> menuActions;

    HudInfo info;
    std::vector<double> latencies, frameTimes;  // ms
    std::vector<double> allLatencies;
    latencies.reserve(2048);
    frameTimes.reserve(options.frames > 0 ? size_t(options.frames) : 1 << 16);
    allLatencies.reserve(options.frames > 0 ? size_t(options.frames) : 1 << 16);
    // Per-phase times (ms): summed over the HUD's half-second window, and every frame's for the exit summary.
    enum Phase { kPose, kPolygonize, kUpload, kDraw, kHud, kSwap, kPhases };
    double phaseSum[kPhases] = {};
    std::vector<double> phaseTimes[kPhases];
    for (auto& v : phaseTimes) v.reserve(options.frames > 0 ? size_t(options.frames) : 1 << 16);
    int64_t phaseStart = 0;
    auto lap = [&](Phase p) {
      if (options.syncPhases) glFinish();  // charge the GL's deferred work to the phase that queued it
      const int64_t t = steadyNowNs();
      const double ms = double(t - phaseStart) * 1e-6;
      phaseSum[p] += ms;
      phaseTimes[p].push_back(ms);
      phaseStart = t;
    };
    const int64_t loopStart = steadyNowNs();
    int64_t windowStart = loopStart, lastFrameEnd = loopStart;
    int framesInWindow = 0, frame = 0, screenshotCount = 0;
    // --overlap: the worker polygonizes frame N+1 while this thread draws frame N. The pipeline and the skeleton
    // are touched here only while the worker is idle (after wait(), before start()).
    std::unique_ptr<PolygonizeWorker> worker = options.overlap ? std::make_unique<PolygonizeWorker>(pipeline) : nullptr;
    int64_t inFlightArrival = 0;  // arrival of the sample whose pose is being polygonized (0: none new)
    int64_t meshArrival = 0;      // arrival of the sample whose mesh is about to be drawn
    uint64_t uploadedVersion = ~uint64_t{0};
    std::vector<AttachedProp> props = options.props;  // moved by options.moveProps
    uint64_t propsVersion = 0;
    // 1. Newest pose: never waits for the source.
    auto pollPose = [&] {
      int64_t newArrival = 0;
      if (source && source->poll(pipeline.skeleton(), &newArrival)) {
        s.poseDirty = true;
        inFlightArrival = newArrival;
      }
      if (source) {
        // Already printed by the source, in order with its details.
        if (std::string m = source->takeMessage(); !m.empty()) s.message = std::move(m);
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
    };
    while (!glfwWindowShouldClose(window) && !interruptRequested()) {
      phaseStart = steadyNowNs();
      if (worker) {
        worker->wait();  // frame N's mesh (its time is the polygonize phase's: what the draw did not hide)
        lap(kPolygonize);
        meshArrival = std::exchange(inFlightArrival, 0);
      }
      glfwPollEvents();
      for (const ScriptedEvent& e : eventsAt(options.script, frame)) deliver(window, s, e);
      for (auto& action : std::exchange(menuActions, {})) {
        action(pipeline, modeller);
        s.poseDirty = true;
      }
      phaseStart = steadyNowNs();
      if (!worker) {
        // 2. Polygonize.
        pollPose();
        lap(kPose);
        pipeline.frame();
        for (const ViewerActor& a : options.others) {
          int64_t arrival = 0;
          if (a.source && a.source->poll(a.pipeline->skeleton(), &arrival)) {
            a.pipeline->skeleton().update();
            if (inFlightArrival == 0) inFlightArrival = arrival;
          }
          a.pipeline->frame();
        }
        lap(kPolygonize);
        meshArrival = std::exchange(inFlightArrival, 0);
      }
      // 3. Upload, only a new mesh.
      const bool drawParticles = s.showParticles && pipeline.polygonizer() == Polygonizer::Particles;
      if (options.moveProps && options.moveProps(frame, props)) ++propsVersion;
      uint64_t version = pipeline.meshVersion() * 1000003u + propsVersion;
      for (const ViewerActor& a : options.others) version = version * 1000003u + a.pipeline->meshVersion();
      if (version != uploadedVersion) {
        if ((props.empty() && options.others.empty()) || worker) {
          renderer->uploadMesh(pipeline.mesh());
        } else {
          Mesh withProps = pipeline.mesh();  // the props posed like the character this frame
          appendPosedProps(withProps, props, pipeline.skeleton());
          appendOthers(withProps, pipeline, options);
          renderer->uploadMesh(withProps);
        }
        uploadedVersion = version;
      }
      if (drawParticles) renderer->uploadParticles(pipeline.tesselator().particles().positions);
      if (s.texturesDirty) {
        renderer->uploadTextures(allTextures(pipeline, options));
        s.texturesDirty = false;
      }
      lap(kUpload);
      // What the HUD and the hashes say about this mesh, read before the worker rewrites it.
      const TesselatorStats& ts = pipeline.tesselator().stats();
      info.polygonizer = pipeline.polygonizer() == Polygonizer::Particles ? "particles" : "Marching Cubes";
      info.simulateMs = ts.simulateMs, info.addDeleteMs = ts.addDeleteMs, info.meshMs = ts.meshMs;
      info.marchingCubesMs = pipeline.marchingCubesStats().milliseconds;
      info.updatesPerRender = pipeline.updatesPerRender();
      info.particles = pipeline.polygonizer() == Polygonizer::Particles ? ts.particles : 0;
      info.triangles = pipeline.mesh().triangleCount();
      for (const ViewerActor& a : options.others) info.triangles += a.pipeline->mesh().triangleCount();
      if (options.printMeshHashes)
        std::printf("frame %d hash %016llx triangles %zu\n", frame, static_cast<unsigned long long>(meshHash(pipeline.mesh())),
                    pipeline.mesh().triangleCount());
      if (worker) {
        phaseStart = steadyNowNs();
        pollPose();
        lap(kPose);
        worker->start();  // frame N+1's mesh, from the pose just taken
      }
      // 4. Draw.
      renderer->draw(s.orbit.camera(), s.width, s.height, drawParticles);
      renderer->drawOverlay(handleOverlay(currentView(s), modeller.handles(), modeller.selected(), modeller.mode()),
                            s.width, s.height);
      lap(kDraw);

      // HUD.
      if (hud) {
        if (source) {
          source->describe(info);
        } else {
          info.source = "hand";
          info.mapping.clear();
          info.state = "posing";
        }
        info.selectedJoint = modeller.selected()
                                 ? targetName(pipeline.character(), *modeller.selected()) + " (" +
                                       modeName(modeller.mode()) + ")"
                                 : std::string();
        info.message = s.message;
        menu.showParticles = s.showParticles;
        info.deviceKeys = source && source->handlesDeviceKeys();
        hud->draw(info, [&] {
          drawModellerMenu(pipeline, modeller, menu, menuActions);
          if (s.painting) drawBrushWindow(s.brush);
        });
        s.showParticles = menu.showParticles;
        renderer->setPointSize(menu.pointSize);
      }
      lap(kHud);

      if (s.saveRequested) {
        s.saveRequested = false;
        const bool anyPainted = std::find(s.painted.begin(), s.painted.end(), true) != s.painted.end();
        const auto saved = savePaintedScene(pipeline.posedScene(), pipeline.character(), pipeline.textures(), s.painted,
                                            options.savePath);
        report(s, saved ? "saved " + options.savePath + (anyPainted ? " with its painted textures" : "")
                        : "save failed: " + saved.error().all().front().message);
      }
      const bool lastFrame = headless && frame + 1 >= options.frames;
      if (s.screenshotRequested || (lastFrame && !options.screenshot.empty())) {
        const std::string path =
            s.screenshotRequested ? "puppeteer-screenshot-" + std::to_string(++screenshotCount) + ".png" : options.screenshot;
        s.screenshotRequested = false;
        if (auto saved = savePng(Renderer::readPixels(s.width, s.height), s.width, s.height, path); saved) {
          s.message = "screenshot " + path;
        } else {
          const std::string& error = saved.error().all().front().message;
          s.message = "screenshot failed: " + error;
          std::fprintf(stderr, "puppeteer: error: %s\n", error.c_str());
          if (lastFrame) exitCode = kExitIoError;
        }
        phaseStart = steadyNowNs();  // not part of the swap
      }
      // 5. Swap; the frame is on screen once the GL has finished it.
      glfwSwapBuffers(window);
      if (source) glFinish();
      lap(kSwap);
      const int64_t now = phaseStart;
      if (meshArrival > 0) {
        const double latency = double(now - meshArrival) * 1e-6;
        latencies.push_back(latency);
        allLatencies.push_back(latency);
        meshArrival = 0;
      }
      if (source) source->frameDone();
      for (const ViewerActor& a : options.others)
        if (a.source) a.source->frameDone();
      frameTimes.push_back(double(now - lastFrameEnd) * 1e-6);
      if (info.fps == 0.0 && frameTimes.back() > 0.0) info.frameMs = frameTimes.back(), info.fps = 1e3 / info.frameMs;
      lastFrameEnd = now;
      ++framesInWindow;
      ++frame;
      if (now - windowStart >= 500'000'000) {
        info.fps = framesInWindow / (double(now - windowStart) * 1e-9);
        info.frameMs = double(now - windowStart) * 1e-6 / framesInWindow;
        double* fields[kPhases] = {&info.poseMs, &info.polygonizeMs, &info.uploadMs, &info.drawMs, &info.hudMs, &info.swapMs};
        for (int p = 0; p < kPhases; ++p) *fields[p] = phaseSum[p] / framesInWindow, phaseSum[p] = 0.0;
        const auto [median, p99] = medianP99(latencies);
        info.latencyMedianMs = median, info.latencyP99Ms = p99;
        if (latencies.size() > 2000) latencies.erase(latencies.begin(), latencies.end() - 1000);
        windowStart = now, framesInWindow = 0;
      }
      if (lastFrame) break;
    }
    if (worker) worker->wait();
    if (source) report(s, source->finish());
    if (source && exitCode == kExitOk) exitCode = source->exitCode();
    for (const ViewerActor& a : options.others) {
      if (!a.source) continue;
      report(s, a.source->finish());
      if (exitCode == kExitOk) exitCode = a.source->exitCode();
    }

    // Summary: frame rate over the whole loop (the settle before it excluded).
    const double seconds = double(lastFrameEnd - loopStart) * 1e-9;
    const auto [frameMedian, frameP99] = medianP99(frameTimes);
    std::printf("puppeteer: %d frames in %.2f s: %.1f FPS (frame time median %.1f ms, p99 %.1f ms), %zu triangles, %dx%d\n",
                frame, seconds, seconds > 0 ? frame / seconds : 0.0, frameMedian, frameP99, info.triangles, s.width,
                s.height);
    static const char* const kPhaseNames[kPhases] = {"pose", "polygonize", "upload", "draw", "hud", "swap"};
    std::printf("puppeteer: median ms per phase%s:", options.syncPhases ? " (GL finished after each)" : "");
    for (int p = 0; p < kPhases; ++p) std::printf(" %s %.2f", kPhaseNames[p], medianP99(phaseTimes[p]).first);
    std::printf("\n");
    if (!allLatencies.empty()) {
      const auto [median, p99] = medianP99(allLatencies);
      std::printf("puppeteer: sample-to-screen latency over %zu frames: median %.1f ms, p99 %.1f ms\n",
                  allLatencies.size(), median, p99);
    }
    s.hud = nullptr;
    s.modeller = nullptr;
  }
  glfwDestroyWindow(window);
  return exitCode;
}

}  // namespace imps::app
