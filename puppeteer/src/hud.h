// SPDX-License-Identifier: MIT
// The live app's heads-up display (Dear ImGui): frame rate, polygonizer timings and counts, the pose source's
// state, sample rate, faults, sample age and sample-to-screen latency, and the key help.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

struct GLFWwindow;

namespace imps::app {

// What the HUD shows; the frame loop fills it every frame. Times in milliseconds; negative means "not known".
struct HudInfo {
  double fps = 0.0;
  double frameMs = 0.0;       // whole frame (pose, polygonize, upload, draw, swap), averaged
  std::string polygonizer;    // "particles" or "Marching Cubes"
  double simulateMs = 0.0, addDeleteMs = 0.0, meshMs = 0.0;  // tesselator phases (per update, per triangulation)
  double marchingCubesMs = 0.0;
  int updatesPerRender = 1;
  size_t particles = 0, triangles = 0;
  // The particle mesh shown is the tesselator's Marching Cubes stand-in (its own had a hole or a pinch, or cut a part
  // off: standInCutOff); and how many of the particle meshes shown so far (particleMeshes) were one.
  bool standIn = false, standInCutOff = false;
  uint64_t particleMeshes = 0, standIns = 0;
  std::string source;         // "hand" / "replay: NAME" / device name
  std::string state;          // "posing", "playing (loop 2)", "Streaming" …
  bool problem = false;       // the source is not delivering (no device, lost, reconnecting): state in a warning colour
  std::string lastError;      // the source's latest problem ("cannot open /dev/ttyNOPE: …"); "" when none
  std::string mapping;        // how samples become joint rotations ("calibration FILE, 18 joints"); "" for hand
  double sampleRateHz = -1.0;
  uint64_t dropped = 0, corrupt = 0, overwritten = 0;
  std::string faults;  // the live device's non-zero fault counters ("timeouts: 3, CRC errors: 1"); "" when none
  double sampleAgeMs = -1.0;
  double latencyMedianMs = -1.0, latencyP99Ms = -1.0;
  // Recording (key `o`): shown as "REC m:ss.s  N samples  FILE" while active.
  bool recording = false;
  double recordSeconds = 0.0;
  uint64_t recordSamples = 0;
  std::string recordPath;
  std::string calibrationProgress;  // re-calibration (key `k`) in progress; "" otherwise
  // Where a frame's time goes (ms, averaged like fps): pose (poll + skeleton update), polygonize, upload, draw,
  // HUD (previous frame's), swap (glfwSwapBuffers + glFinish).
  double poseMs = 0, polygonizeMs = 0, uploadMs = 0, drawMs = 0, hudMs = 0, swapMs = 0;
  std::string selectedJoint;  // "" when none
  std::string message;        // the last key's result ("saved …", "not available yet")
  bool deviceKeys = false;    // keys o (record) and k (calibrate) work: a live device (puppeteer live)
};

// The HUD's line about the particles' Marching Cubes stand-in: "" when no particle mesh shown so far was one; else
// "MC stand-in (part cut off | hole or pinch)  N of M meshes" for a frame showing one (in the warning colour), "MC
// stand-ins: N of M meshes" for one that does not.
std::string standInText(const HudInfo& info);

// The key help line at the bottom of the HUD: only keys that work here (o and k only with deviceKeys).
std::string keyHelp(bool deviceKeys);

// Owns the ImGui context and its GLFW / OpenGL 3 backends for one window. Construct after the window's GL context
// is current and after installing the app's own GLFW callbacks (ImGui chains to them). Not thread-safe.
class Hud {
 public:
  explicit Hud(GLFWwindow* window);
  ~Hud();
  Hud(const Hud&) = delete;
  Hud& operator=(const Hud&) = delete;

  // Draws the HUD over the current frame; `extra` (optional) adds its own ImGui windows in the same frame (the
  // modeller's menu).
  void draw(const HudInfo& info, const std::function<void()>& extra = {});
  // True when the mouse is over the HUD (the app then leaves the click to ImGui).
  bool wantsMouse() const;

 private:
  bool visible_ = true;
};

}  // namespace imps::app
