// SPDX-License-Identifier: MIT
// The live app's window and frame loop: GLFW 3.3 + OpenGL 3.3 core. Each frame takes the newest pose (from a pose
// source, or from the mouse), updates the skeleton cache, runs the polygonizer, uploads, draws, shows the HUD.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include <vector>

#include "hud.h"
#include "prop_attachment.h"
#include "scripted_input.h"
#include "viewer_pipeline.h"

namespace imps::app {

// Where poses come from besides the mouse: a replayed session or a live device. Called from the frame loop only.
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  // Never blocks. Applies the newest pose, if one arrived since the last call, to `skeleton` (without update())
  // and returns true; then *arrivalNs is that sample's arrival time on the steady clock (0 if unknown).
  virtual bool poll(SkeletonCache& skeleton, int64_t* arrivalNs) = 0;
  // Fills the HUD's source, state, sample rate, fault and age fields.
  virtual void describe(HudInfo& info) = 0;
  // Called once per frame after the frame is on screen (for per-frame bookkeeping such as deterministic replay).
  virtual void frameDone() {}
  // Key `o`: starts or stops recording the raw samples to a session file. Returns the message to show (the viewer
  // also prints it). Sources that cannot record say so.
  virtual std::string toggleRecording() { return "recording needs a live device (puppeteer live)"; }
  // Key `k`: starts re-calibration (countdown, averaging window, offsets, save); progress and result reach the HUD
  // through describe() and takeMessage().
  virtual std::string recalibrate() { return "re-calibration needs a live device (puppeteer live)"; }
  // Whether toggleRecording() and recalibrate() do something here (the HUD offers keys o and k only then).
  virtual bool handlesDeviceKeys() const { return false; }
  // A message produced on the source's own schedule (a calibration finished, a recording failed), once; "" if none.
  // The source prints it itself; the viewer shows it in the HUD.
  virtual std::string takeMessage() { return {}; }
  // Called once after the last frame: closes what is open (a recording). Returns a message to print, or "".
  virtual std::string finish() { return {}; }
  // After finish(): the run's exit code (cli.h) as far as the source is concerned: kExitIoError when a live device
  // never delivered a sample (the source has printed why), else kExitOk.
  virtual int exitCode() const { return 0; }
};

// Another character in the same window (a world, `puppeteer view WORLD`): its own pipeline (polygonizer, skeleton
// cache, placement) and its own pose source (null: it keeps its pose). Neither is owned.
struct ViewerActor {
  ViewerPipeline* pipeline = nullptr;
  PoseSource* source = nullptr;
  std::vector<AttachedProp> props;  // riding on its joints (joint >= 0), posed by its skeleton cache
};

struct ViewerOptions {
  int width = 1280, height = 720;  // window size in pixels
  // More characters drawn beside the main pipeline's, each polygonized and posed every frame like it; their meshes
  // (and textures) join the main mesh for upload. The modeller, painter and HUD serve the main pipeline; the camera
  // frames them all. Not with `overlap`.
  std::vector<ViewerActor> others;
  // Polygonal props drawn with the character's mesh, attached ones following their joints (`--prop`; not with
  // `overlap`, where the worker thread owns the skeleton cache).
  std::vector<AttachedProp> props;
  // Called once per frame before the upload with the frame's number and the props (a world's own clips moving
  // them); returns true when it moved any. Null: the props stay.
  std::function<bool(int frame, std::vector<AttachedProp>& props)> moveProps;
  // > 0: render this many frames (after the initial settle), then close; the headless mode for tests and docs.
  int frames = 0;
  // Written after the last frame when frames > 0 (PNG).
  std::string screenshot;
  bool showParticles = false;
  float pointSize = 0.0f;     // particle points in pixels (the thesis's -s); 0: 4, or 3 below 600 pixels of height
  bool manipulators = true;   // the modeller's handles and mouse edits (off: the thesis's -n)
  bool hud = true;
  // Multisampling samples (0 off); -1: 4 on a GPU, off under a software renderer (llvmpipe), where it costs more
  // than the rest of the frame.
  int msaaSamples = -1;
  bool vsync = true;          // ignored (off) when frames > 0
  std::string savePath;       // target of the `s` key
  uint8_t brushColor[3] = {200, 30, 40};  // the painter's starting colour (sRGB bytes; `t`, docs/app.md)
  bool printMeshHashes = false;  // print "frame N hash H triangles T" per frame to stdout
  // glFinish after every phase so the per-phase times include the GL's deferred work (profiling; slower).
  bool syncPhases = false;
  // Polygonize frame N+1 on a worker thread while this thread draws frame N: more frames per second when the
  // polygonizer and the GL do not already share every core, at up to one frame more sample-to-screen latency.
  bool overlap = false;
  std::string title = "IMPS Puppeteer";
  // Scripted input (scripted_input.h): key presses and mouse drags delivered at given frames, through the same
  // handlers as the window's callbacks.
  std::vector<ScriptedEvent> script;
};

// Opens the window and runs until Esc / close / `frames` are done, or SIGINT / SIGTERM arrives (Ctrl-C closes the
// app as Esc does: the source finishes, a take is closed, the summary is printed). `source` may be null (hand
// posing only). Returns an ExitCode (cli.h): kExitIoError when no window / GL 3.3 context can be created, the
// screenshot cannot be written, or the source says so (PoseSource::exitCode). Prints a one-line performance
// summary (frames per second, sample-to-screen latency) at the end.
int runViewer(ViewerPipeline& pipeline, PoseSource* source, const ViewerOptions& options);

}  // namespace imps::app
