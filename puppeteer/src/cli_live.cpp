// SPDX-License-Identifier: MIT
// `puppeteer view` (pose by hand), `puppeteer replay` (play a recorded session) and `puppeteer live` (drive the
// character from an armature): the live app's commands.
#include "cli.h"
#include "cli_world.h"
#include "clip_pose.h"
#include "device_opener.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "imps/character.h"
#include "imps/marching_cubes.h"
#include "calibration/calibration.h"
#include "drivers/device_session.h"
#include "drivers/device_spec.h"
#include "drivers/osc_sender.h"
#include "drivers/serial_transport.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "sim/session_file.h"
#include "sim/simulated_armature.h"
#include "viewer.h"
#include "viewer_live.h"
#include "viewer_pipeline.h"
#include "viewer_replay.h"
#include "calibration_flow.h"
#include "osc_stream.h"
#include "scripted_input.h"
#include "session_calibration.h"
#include "pose_argument.h"
#include "map_option.h"
#include "textures.h"
#include "world_scene.h"

namespace imps::app {
namespace {

struct LiveArgs {
  std::string scene;
  int frames = 0;
  std::string screenshot;
  std::string polygonizer;  // "" : the one the scene file names (MarchingCubes → mc), else particles
  bool particles = false;
  bool noManipulators = false;
  float pointSize = 0.0f;
  bool noHud = false;
  bool printHashes = false;
  int width = 1280, height = 720;
  int threads = -1;
  std::string textureMode;  // "", "projective" or "carried"
  int msaa = -1;
  std::vector<std::string> poses;
  std::string save;
  std::vector<int> brush;  // --brush R,G,B
  std::string keys;
  std::vector<std::string> drags;
  bool syncPhases = false;
  bool overlap = false;
  std::vector<std::string> oscOut;  // live, replay: --osc-out targets
  std::vector<std::string> props;   // --prop FILE.wrl[@JOINT]
  std::vector<std::string> drives;  // view WORLD: --drive NAME=SOURCE
  // replay
  std::string session;
  std::string rig, calibration;
  std::string map = "auto";
  double speed = 1.0;
  bool stepped = false;
  std::string exportSession;
  // view, replay: a VRML clip (docs/world-format.md); replay takes it in place of SESSION
  std::string clip, clipName;
  // live
  std::string device;
  std::string record, recordDir = ".";
  std::string calibrationOut;
  CalibrationFlowOptions calibrate;
};

void addCommonOptions(CLI::App* cmd, LiveArgs& a) {
  cmd->add_option("--prop", a.props,
                  "Polygonal props from a VRML 97 file, FILE.wrl@JOINT to attach them to a joint (repeatable; "
                  "docs/world-format.md)");
  cmd->add_option("--frames", a.frames, "Render this many frames, then exit (headless use; 0 = until closed)")
      ->check(nonNegativeNumber());
  cmd->add_option("--screenshot", a.screenshot, "With --frames: save the last frame to this PNG file");
  cmd->add_option("--polygonizer", a.polygonizer,
                  "particles (the tesselator) or mc (Marching Cubes); default: the scene file's polygonizer node")
      ->check(CLI::IsMember({"particles", "mc"}));
  cmd->add_flag("--particles", a.particles, "Show the particles as points (key p; the thesis viewer's -p)");
  cmd->add_option("--point-size", a.pointSize, "Diameter of the particle points in pixels (the thesis viewer's -s)")
      ->check(CLI::Range(1.0f, 64.0f));
  cmd->add_flag("--no-manipulators", a.noManipulators,
                "No handles and no editing with the mouse, which then only orbits (the thesis viewer's -n)");
  cmd->add_flag("--no-hud", a.noHud, "Hide the heads-up display");
  cmd->add_flag("--mesh-hashes", a.printHashes, "Print a hash of every frame's mesh (determinism checks)");
  cmd->add_option("--width", a.width, "Window width in pixels")->check(CLI::Range(64, 8192));
  cmd->add_option("--height", a.height, "Window height in pixels")->check(CLI::Range(64, 8192));
  cmd->add_option("--threads", a.threads, "Tesselator threads (default: the scene's numThreads; 0 = all cores)")
      ->check(nonNegativeNumber());
  cmd->add_option("--texture-mode", a.textureMode,
                  "projective (textures slide over the skin as it bends) or carried (the particles carry their "
                  "texture coordinates: textures stretch with the skin); default: the scene's textureMode")
      ->check(CLI::IsMember({"projective", "carried"}));
  cmd->add_option("--msaa", a.msaa, "Multisampling samples (0 = off; default: 4, or off under software GL)")
      ->check(CLI::Range(0, 16));
  cmd->add_option("--pose", a.poses,
                  "JOINT=AX,AY,AZ,ANGLE: turn a joint by ANGLE degrees (or e.g. 1.2rad) about axis (AX,AY,AZ) of its "
                  "parent's frame, on top of its rest rotation; JOINT=TX,TY,TZ: move it by TX,TY,TZ metres in its "
                  "parent's frame (repeatable)");
  cmd->add_option("--save-as", a.save, "Where the s key saves the posed scene (default: SCENE with .posed.wrl)");
  cmd->add_option("--brush", a.brush, "R,G,B: the painter's starting colour, 0-255 each (t paints; default 200,30,40)")
      ->expected(3)
      ->delimiter(',')
      ->check(CLI::Range(0, 255));
  cmd->add_option("--keys", a.keys,
                  "Scripted key presses KEY@FRAME,... (e.g. \"o@5,k@10,p@20\"; keys a-z 0-9 [ ] F12 Esc Backspace)");
  cmd->add_option("--drag", a.drags,
                  "Scripted left-button drag X0,Y0,X1,Y1@FRAME[+shift] in window pixels (repeatable)");
  cmd->add_flag("--overlap", a.overlap,
                "Polygonize the next frame on a worker thread while the GL draws this one");
  cmd->add_flag("--sync-phases", a.syncPhases,
                "glFinish after every phase so the per-phase times include the GL's work (profiling)");
}

void addOscOutOption(CLI::App* cmd, LiveArgs& a) {
  cmd->add_option("--osc-out", a.oscOut,
                  "Also stream every pose as OSC over UDP to osc.udp://HOST:PORT (repeatable; docs/osc.md)");
}

// Loads and compiles the scene, applies --pose; prints diagnostics and returns nullptr on bad input.
std::unique_ptr<ViewerPipeline> makePipeline(const LiveArgs& a, int* exitCode) {
  auto loaded = loadScene(a.scene);
  if (!loaded) {
    *exitCode = kExitInvalidInput;
    return nullptr;
  }
  auto textures = loadTextures(loaded->character);
  if (!textures) {
    std::fputs(textures.error().str().c_str(), stderr);
    *exitCode = kExitInvalidInput;
    return nullptr;
  }
  PipelineOptions o;
  const bool fileNamesMc = std::holds_alternative<MarchingCubesNode>(loaded->scene.polygonizer);
  o.polygonizer = a.polygonizer == "mc" || (a.polygonizer.empty() && fileNamesMc) ? Polygonizer::MarchingCubes
                                                                                 : Polygonizer::Particles;
  o.threads = a.threads;
  if (!a.textureMode.empty())
    o.textureMode = a.textureMode == "carried" ? TextureMode::Carried : TextureMode::Projective;
  auto pipeline = std::make_unique<ViewerPipeline>(std::move(loaded->scene), std::move(loaded->character), o);
  pipeline->setTextures(std::move(*textures));
  for (const std::string& text : a.poses) {
    const auto p = parsePoseArgument(text);
    const int j = p ? pipeline->character().findJoint(p->joint) : -2;
    if (j < 0) {
      std::fprintf(stderr, "puppeteer: error: --pose %s: %s\n", text.c_str(),
                   j == -2 ? p.error().all().front().message.c_str() : "no joint of that name");
      *exitCode = kExitUsage;
      return nullptr;
    }
    applyPoseArgument(*p, j, pipeline->skeleton());
  }
  pipeline->skeleton().update();
  // A Marching Cubes grid the scene asks for beyond the cell limit is refused here, as `mesh` refuses it, instead
  // of showing an empty window.
  if (auto plan = planGrid(pipeline->skeleton().field(), pipeline->marchingCubesOptions()); !plan) {
    std::fprintf(stderr,
                 "%s: error: %s; give the scene's MarchingCubes node a larger cellSize or smaller resolutions\n",
                 a.scene.c_str(), plan.error().all().front().message.c_str());
    *exitCode = kExitInvalidInput;
    return nullptr;
  }
  return pipeline;
}

// --prop specs loaded for `character`; nullopt after printing the errors.
std::optional<std::vector<AttachedProp>> propsFor(const LiveArgs& a, const Character& character) {
  Diagnostics warnings;
  auto props = loadProps(a.props, character, &warnings);
  std::fputs(warnings.str().c_str(), stderr);
  if (!props) {
    std::fputs(props.error().str().c_str(), stderr);
    return std::nullopt;
  }
  return std::move(*props);
}

ViewerOptions viewerOptions(const LiveArgs& a, const std::string& title) {
  ViewerOptions v;
  v.width = a.width, v.height = a.height;
  v.frames = a.frames;
  v.screenshot = a.screenshot;
  v.showParticles = a.particles;
  v.pointSize = a.pointSize;
  v.manipulators = !a.noManipulators;
  v.hud = !a.noHud;
  v.msaaSamples = a.msaa;
  v.printMeshHashes = a.printHashes;
  v.title = title;
  v.syncPhases = a.syncPhases;
  v.overlap = a.overlap;
  if (a.brush.size() == 3)
    for (int k = 0; k < 3; ++k) v.brushColor[k] = uint8_t(a.brush[size_t(k)]);
  if (!a.save.empty()) {
    v.savePath = a.save;
  } else {
    std::filesystem::path p(a.scene);
    v.savePath = (p.parent_path() / (p.stem().string() + ".posed.wrl")).string();
  }
  return v;
}

// The command line's output files, before any frame is drawn: --screenshot (a PNG, needs --frames), and for replay
// and live the files they create. Prints the error; returns the exit code (kExitOk when fine).
int checkOutputArgs(const LiveArgs& a, std::string_view command) {
  if (!a.screenshot.empty() && a.frames <= 0) {
    std::fprintf(stderr, "puppeteer %.*s: error: --screenshot needs --frames N\n", int(command.size()),
                 command.data());
    return kExitUsage;
  }
  const std::pair<const char*, const std::string*> outputs[] = {
      {"--export-session", &a.exportSession}, {"--record", &a.record}, {"--calibration-out", &a.calibrationOut}};
  if (!a.screenshot.empty())
    if (int rc = checkOutputPath(command, "--screenshot", a.screenshot, {".png"}); rc != kExitOk) return rc;
  for (const auto& [option, path] : outputs)
    if (!path->empty())
      if (int rc = checkOutputPath(command, option, *path); rc != kExitOk) return rc;
  std::error_code ec;
  if (command == "live" && !std::filesystem::is_directory(a.recordDir, ec)) {
    std::fprintf(stderr, "puppeteer live: error: --record-dir %s: no such directory\n", a.recordDir.c_str());
    return kExitIoError;
  }
  return kExitOk;
}

// --keys and --drag as scripted events; nullopt after printing the error.
std::optional<std::vector<ScriptedEvent>> parseScript(const LiveArgs& a) {
  std::vector<ScriptedEvent> script;
  if (!a.keys.empty()) {
    auto keys = parseScriptedKeys(a.keys);
    if (!keys) {
      std::fprintf(stderr, "puppeteer: error: %s\n", keys.error().all().front().message.c_str());
      return std::nullopt;
    }
    script = std::move(*keys);
  }
  for (const std::string& d : a.drags) {
    auto drag = parseScriptedDrag(d);
    if (!drag) {
      std::fprintf(stderr, "puppeteer: error: %s\n", drag.error().all().front().message.c_str());
      return std::nullopt;
    }
    script.push_back(std::move(*drag));
  }
  return script;
}

// The viewer's props (--prop; not with --overlap) and scripted input, into `v`. Returns the exit code (kExitOk: go on).
int addPropsAndScript(const LiveArgs& a, const Character& character, std::vector<ScriptedEvent> script,
                      ViewerOptions& v) {
  if (!a.props.empty() && a.overlap) {
    std::fprintf(stderr, "puppeteer: error: --prop cannot be combined with --overlap\n");
    return kExitUsage;
  }
  auto props = propsFor(a, character);
  if (!props) return kExitInvalidInput;
  v.props = std::move(*props);
  v.script = std::move(script);
  return kExitOk;
}


int runClip(const LiveArgs& a, const std::string& command);
std::optional<sim::Session> loadSession(const std::string& path);
std::optional<SampleMapper> replayMapper(const std::string& sessionPath, const sim::Session& session,
                                         const Character& character, const std::string& calibrationPath,
                                         const std::string& map, const std::string& scenePath, int* code);

// One character of a world in the app, and what drives it.
struct WorldActor {
  std::unique_ptr<ViewerPipeline> pipeline;
  std::unique_ptr<sim::Session> session;  // a replayed session or BVH clip (the source reads it)
  std::unique_ptr<PoseSource> source;     // null: it keeps its pose
};

// The pose source `source` names for `actor` (--drive NAME=SOURCE, or the clip inlined beside it when ""): a VRML
// clip FILE.wrl[#TIMESENSOR], a session or .bvh file, a device spec (docs/devices.md; channels by joint name), or
// "hand"/"rest" for none. False after printing the error (*code set).
bool driveActor(const LiveArgs& a, const WorldCharacter& c, const std::string& source, WorldActor& actor,
                imps::Clock& clock, int* code) {
  const Character& character = actor.pipeline->character();
  const double step = a.frames > 0 ? 1.0 / 60.0 : 0.0;  // headless: a known moment per frame
  if (source.empty() || source == "hand" || source == "rest") {
    if (!source.empty() || !c.clip) return true;
    ClipDriver driver(*c.clip, character);
    std::printf("puppeteer: %s: playing %s of %s on %zu joints\n", c.name.c_str(), driver.describe().c_str(),
                std::filesystem::path(c.clipPath).filename().string().c_str(), driver.bound().size());
    actor.source = std::make_unique<ClipPoseSource>(std::move(driver), a.speed, step, c.name + ": " + c.clip->name);
    return true;
  }
  if (isClipSource(source)) {
    const auto [file, clipName] = splitClipSource(source);
    auto driver = ClipDriver::load(file, clipName, "names", character);
    if (!driver) {
      std::fputs(driver.error().str().c_str(), stderr);
      *code = kExitInvalidInput;
      return false;
    }
    std::printf("puppeteer: %s: playing %s\n", c.name.c_str(), driver->describe().c_str());
    actor.source = std::make_unique<ClipPoseSource>(std::move(*driver), a.speed, step,
                                                    c.name + ": " + std::filesystem::path(file).filename().string());
    return true;
  }
  std::error_code ec;
  if (std::filesystem::is_regular_file(source, ec)) {
    auto session = loadSession(source);
    if (!session) {
      *code = kExitInvalidInput;
      return false;
    }
    actor.session = std::make_unique<sim::Session>(std::move(*session));
    auto mapper = replayMapper(source, *actor.session, character, "", "auto", c.scenePath, code);
    if (!mapper) return false;
    const std::string name = c.name + ": " + std::filesystem::path(source).filename().string();
    actor.source = std::make_unique<ReplayPoseSource>(*actor.session, std::move(*mapper), a.speed, name);
    return true;
  }
  auto spec = drivers::parseDeviceSpec(source);
  if (!spec) {
    std::fprintf(stderr,
                 "puppeteer view: error: --drive %s=%s: not a clip (.wrl), a session or .bvh file, or a "
                 "device spec: %s\n",
                 c.name.c_str(), source.c_str(), spec.error().all().front().str().c_str());
    *code = kExitUsage;
    return false;
  }
  if (spec->kind == drivers::DeviceKind::Osc) {
    auto osc = OscPoseSource::open(*spec, character, std::nullopt);
    if (!osc) {
      std::fprintf(stderr, "puppeteer view: %s\n", drivers::errorText(osc.error()).c_str());
      *code = kExitIoError;
      return false;
    }
    actor.source = std::move(*osc);
    return true;
  }
  auto opener = openerForSpec(*spec, clock, "view");
  if (!opener) {
    std::fputs(opener.error().diagnostics.str().c_str(), stderr);
    *code = exitCodeFor(opener.error().kind);
    return false;
  }
  actor.source = std::make_unique<LivePoseSource>(*opener, drivers::sessionOptionsFor(*spec), character, source,
                                                  std::nullopt);
  return true;
}

// `puppeteer view WORLD`: every character of the world in one window, each with its own pipeline and source.
int runWorldView(const LiveArgs& a) {
  if (int rc = checkOutputArgs(a, "view"); rc != kExitOk) return rc;
  if (a.overlap || !a.props.empty() || !a.poses.empty()) {
    std::fprintf(stderr, "puppeteer view: error: %s is a world: --overlap, --prop and --pose apply to one character "
                         "(inline props in the world; drive characters with --drive NAME=SOURCE)\n",
                 a.scene.c_str());
    return kExitUsage;
  }
  auto script = parseScript(a);
  if (!script) return kExitUsage;
  auto world = loadWorld(a.scene);
  if (!world) return kExitInvalidInput;
  if (world->characters.empty()) {
    std::fprintf(stderr, "%s: error: the world places no character (an Inline of an IMPS scene file)\n",
                 a.scene.c_str());
    return kExitInvalidInput;
  }
  auto sources = driveSources(*world, a.drives);
  if (!sources) return kExitUsage;
  imps::SteadyClock clock;  // simulated armatures'; outlives the sources
  std::vector<WorldActor> actors;
  int code = kExitOk;
  for (size_t k = 0; k < world->characters.size(); ++k) {
    WorldCharacter& c = world->characters[k];
    auto textures = loadTextures(c.character);
    if (!textures) {
      std::fputs(textures.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    PipelineOptions o;
    const bool fileNamesMc = std::holds_alternative<MarchingCubesNode>(c.scene.polygonizer);
    o.polygonizer = a.polygonizer == "mc" || (a.polygonizer.empty() && fileNamesMc) ? Polygonizer::MarchingCubes
                                                                                   : Polygonizer::Particles;
    o.threads = a.threads;
    WorldActor actor;
    actor.pipeline = std::make_unique<ViewerPipeline>(c.scene, std::move(c.character), o);
    actor.pipeline->setTextures(std::move(*textures));
    actor.pipeline->setPlacement(c.placement);
    if (auto plan = planGrid(actor.pipeline->skeleton().field(), actor.pipeline->marchingCubesOptions()); !plan) {
      std::fprintf(stderr, "%s: error: %s\n", c.scenePath.c_str(), plan.error().all().front().message.c_str());
      return kExitInvalidInput;
    }
    if (!driveActor(a, c, (*sources)[k], actor, clock, &code)) return code;
    actors.push_back(std::move(actor));
  }
  ViewerOptions v = viewerOptions(a, "IMPS Puppeteer: " + a.scene);
  v.manipulators = false;  // a world is watched and driven; characters are edited in their own scene files
  // The world's props (worldProp[i]: v.props[i]'s index in world->props), then those riding on the first
  // character's joints; the others' ride with them (ViewerActor::props).
  std::vector<size_t> worldProp;
  std::vector<std::vector<AttachedProp>> riding(actors.size());
  for (size_t p = 0; p < world->props.size(); ++p) {
    const int c = p < world->propCharacter.size() ? world->propCharacter[p] : -1;
    if (c < 0) {
      worldProp.push_back(p);
      v.props.push_back({world->props[p].name, world->props[p].mesh, -1});
    } else {
      riding[size_t(c)].push_back({world->props[p].name, world->propLocal[p], world->propJoint[p]});
    }
  }
  v.props.insert(v.props.end(), riding[0].begin(), riding[0].end());
  // The world's own clips move placements (each character's source wrapped) and props, on one time line.
  const WorldTime time(a.frames > 0 ? 1.0 / 60.0 : 0.0);
  std::vector<std::unique_ptr<PlacedPoseSource>> placed;
  if (!world->clips.empty()) {
    for (size_t k = 0; k < actors.size(); ++k)
      placed.push_back(std::make_unique<PlacedPoseSource>(*world, k, actors[k].source.get(), time));
    v.moveProps = [&world, &worldProp, time](int frame, std::vector<AttachedProp>& props) {
      World::Pose pose = world->poseAt(time.seconds(frame));
      for (size_t i = 0; i < worldProp.size() && i < props.size(); ++i)
        props[i].mesh = std::move(pose.props[worldProp[i]]);
      return true;
    };
    std::printf("puppeteer: world %s: %zu clip%s of its own\n", a.scene.c_str(), world->clips.size(),
                world->clips.size() == 1 ? "" : "s");
  }
  auto sourceOf = [&](size_t k) -> PoseSource* {
    return placed.empty() ? actors[k].source.get() : placed[k].get();
  };
  for (size_t k = 1; k < actors.size(); ++k) v.others.push_back({actors[k].pipeline.get(), sourceOf(k), riding[k]});
  v.script = std::move(*script);
  std::printf("puppeteer: world %s: %zu characters, %zu props\n", a.scene.c_str(), actors.size(), world->props.size());
  return runViewer(*actors[0].pipeline, sourceOf(0), v);
}

int runView(const LiveArgs& a) {
  if (isWorldFile(a.scene) && a.clip.empty()) return runWorldView(a);
  if (!a.drives.empty()) {
    std::fprintf(stderr, "puppeteer view: error: --drive needs a world file (docs/world-format.md#worlds); for one "
                         "character use replay, live or --clip\n");
    return kExitUsage;
  }
  if (!a.clip.empty()) return runClip(a, "view");
  if (int rc = checkOutputArgs(a, "view"); rc != kExitOk) return rc;
  auto script = parseScript(a);
  if (!script) return kExitUsage;
  int code = kExitOk;
  auto pipeline = makePipeline(a, &code);
  if (!pipeline) return code;
  ViewerOptions v = viewerOptions(a, "IMPS Puppeteer: " + a.scene);
  if (int rc = addPropsAndScript(a, pipeline->character(), std::move(*script), v); rc != kExitOk) return rc;
  return runViewer(*pipeline, nullptr, v);
}

// A .bvh clip is converted in memory (bvhToSession); anything else is read as a session file.
std::optional<sim::Session> loadSession(const std::string& path) {
  if (std::filesystem::path(path).extension() == ".bvh") {
    auto clip = sim::readBvh(path);
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return std::nullopt;
    }
    auto session = sim::bvhToSession(*clip, std::filesystem::path(path).filename().string());
    if (!session) {
      std::fputs(session.error().str().c_str(), stderr);
      return std::nullopt;
    }
    return std::move(*session);
  }
  auto session = sim::readSession(path);
  if (!session) {
    std::fputs(session.error().str().c_str(), stderr);
    return std::nullopt;
  }
  if (!session->recovery.message.empty()) std::fprintf(stderr, "%s\n", session->recovery.message.c_str());
  return std::move(*session);
}

// --rig alone cannot convert counts (a rig map has no offsets): refuse it with what to do instead.
bool checkRigArgs(const LiveArgs& a) {
  if (!a.rig.empty() && a.calibration.empty()) {
    std::fprintf(stderr,
                 "puppeteer: error: --rig %s: a rig map has no offsets; run `puppeteer calibrate` and pass the "
                 "calibration it writes with --calibration\n",
                 a.rig.c_str());
    return false;
  }
  if (!a.rig.empty())
    std::fprintf(stderr, "puppeteer: note: --rig is ignored: the calibration %s contains its rig map\n",
                 a.calibration.c_str());
  return true;
}

// --calibration FILE, checked against the character (and the device when known, or the bits a line-protocol
// spec gives: `calibrate` checks the same); nullopt after printing errors.
std::optional<SampleMapper> readCalibration(const std::string& path, const Character& character,
                                            const drivers::DeviceInfo* device,
                                            std::span<const drivers::DeviceInfo> devices = {}, int lineBits = 0) {
  auto c = calibration::Calibration::readFile(path, &character, device, devices);
  if (!c) {
    std::fputs(c.error().str().c_str(), stderr);
    return std::nullopt;
  }
  if (lineBits > 0 && c->rigMap().bits != lineBits) {
    std::fprintf(stderr,
                 "%s: error: the calibration is for %d-bit encoders but the line-protocol device reports %d bits "
                 "(lines carry no bit depth: add bits=%d to the device spec, docs/devices.md)\n",
                 path.c_str(), c->rigMap().bits, lineBits, c->rigMap().bits);
    return std::nullopt;
  }
  return SampleMapper(std::move(*c), std::filesystem::path(path).filename().string());
}

// --osc-out URLs, checked before anything is loaded or opened; false after printing the error.
bool checkOscOutArgs(const LiveArgs& a) {
  for (const std::string& url : a.oscOut) {
    if (auto ok = drivers::checkOscTargetUrl(url); !ok) {
      std::fprintf(stderr, "puppeteer: error: --osc-out %s: %s\n", url.c_str(), ok.error().all().front().str().c_str());
      return false;
    }
  }
  return true;
}

// Runs the viewer on `source`, streaming every pose it applies to the --osc-out targets when there are any.
int runWithOscOut(const LiveArgs& a, ViewerPipeline& pipeline, PoseSource& source, const ViewerOptions& v) {
  auto sender = openOscOut(a.oscOut, pipeline.character());
  if (!sender) return sender.error();
  if (!*sender) return runViewer(pipeline, &source, v);
  OscStreamingSource streaming(source, std::move(*sender), pipeline.character());
  return runViewer(pipeline, &streaming, v);
}

// Whether `path` is a scene file: by its #VRML header, or by a .wrl name when it cannot be read.
bool looksLikeScene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[5] = {};
  if (in.read(head, sizeof head)) return std::string_view(head, sizeof head) == "#VRML";
  return extensionOf(path) == ".wrl";
}

// Plays a.clip (a VRML 97 clip file) on a.scene in the app: `view --clip` and `replay CLIP.wrl SCENE`.
int runClip(const LiveArgs& a, const std::string& command) {
  if (int rc = checkOutputArgs(a, command.c_str()); rc != kExitOk) return rc;
  if (!checkOscOutArgs(a)) return kExitUsage;
  auto script = parseScript(a);
  if (!script) return kExitUsage;
  int code = kExitOk;
  auto pipeline = makePipeline(a, &code);
  if (!pipeline) return code;
  auto driver = ClipDriver::load(a.clip, a.clipName, a.map, pipeline->character());
  if (!driver) {
    std::fputs(driver.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  const std::string name = std::filesystem::path(a.clip).filename().string();
  std::printf("puppeteer: playing %s of %s on %zu joint%s", driver->describe().c_str(), name.c_str(),
              driver->bound().size(), driver->bound().size() == 1 ? "" : "s");
  if (!driver->unbound().empty()) {
    std::string names;
    for (const std::string& t : driver->unbound()) names += " " + t;
    std::printf(", targets driving no joint:%s", names.c_str());
  }
  std::printf("\n");
  if (driver->hasScale())
    std::printf("puppeteer: note: %s: scale tracks are not applied to the character (its joints are rigid)\n",
                name.c_str());
  // Headless runs (--frames) advance a fixed 1/60 s per frame, so a screenshot shows a known moment.
  ClipPoseSource source(std::move(*driver), a.speed, a.frames > 0 ? 1.0 / 60.0 : 0.0, name);
  ViewerOptions v = viewerOptions(a, "IMPS Puppeteer: " + command + " " + name);
  if (int rc = addPropsAndScript(a, pipeline->character(), std::move(*script), v); rc != kExitOk) return rc;
  return runWithOscOut(a, *pipeline, source, v);
}

// How a replayed session's samples reach `character`'s joints: --calibration, else a clip's skeleton retargeted
// (--map), else the calibration recorded with the session, else channel names. Prints what it chose; nullopt after
// printing the error (*code set).
std::optional<SampleMapper> replayMapper(const std::string& sessionPath, const sim::Session& session,
                                         const Character& character, const std::string& calibrationPath,
                                         const std::string& map, const std::string& scenePath, int* code) {
  auto fail = [code]() -> std::optional<SampleMapper> {
    *code = kExitInvalidInput;
    return std::nullopt;
  };
  const std::string name = std::filesystem::path(sessionPath).filename().string();
  const drivers::DeviceInfo* device = session.devices.empty() ? nullptr : &session.devices[0];
  std::optional<SampleMapper> mapper;
  if (!calibrationPath.empty()) {
    mapper = readCalibration(calibrationPath, character, device, session.devices);
    if (!mapper) return fail();
  } else if (session.skeleton) {
    auto clip = sim::readBvhText(session.skeleton->bvh, name + " skeleton");
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return fail();
    }
    const auto options = retargetOptionsFor(map, *clip, character);
    if (!options) return fail();
    auto clipMap = ClipPoseMap::create(session, character, *options);
    if (!clipMap) {
      const Diagnostic& d = clipMap.error().all().front();
      std::fprintf(stderr, "puppeteer: error: %s: %s\n", sessionPath.c_str(),
                   (d.loc.file.empty() ? d.message : d.str()).c_str());
      return fail();
    }
    printRetargetReport(name, map, clipMap->retargeter().report());
    mapper.emplace(std::move(*clipMap), map);
  } else {
    // The calibration recorded with the first sample, if any (a BVH clip's channel mapping is none: by name).
    auto c = calibrationForSample(session, 0, &character, name);
    if (c && *c) {
      mapper.emplace(std::move(**c), "recorded in " + name);
    } else if (!c) {
      std::printf("puppeteer: note: the session's recorded calibration does not apply to this scene (%s); "
                  "mapping channels by name\n",
                  c.error().all().empty() ? "unknown format" : c.error().all().front().message.c_str());
    }
  }
  if (!mapper) mapper.emplace(session, character);
  const ChannelPoseMap* byName = mapper->byName();
  std::printf("puppeteer: replaying %zu samples of %s: %s", session.samples.size(), name.c_str(),
              mapper->describe().c_str());
  if (byName && !byName->unmatched().empty())
    std::printf(", %zu channels ignored (no such joint or not a rotation)", byName->unmatched().size());
  std::printf("\n");
  if (mapper->mappedJoints() == 0 && mapper->clip()) {
    std::fprintf(stderr, "puppeteer: error: %s: no clip joint drives a joint of %s (see the report above; pass --map "
                         "FILE.json, docs/calibration.md)\n", sessionPath.c_str(), scenePath.c_str());
    return fail();
  }
  if (mapper->mappedJoints() == 0) {
    std::fprintf(stderr,
                 "puppeteer: error: %s: no channel named JOINT:Xrotation/Yrotation/Zrotation matches a joint of %s "
                 "(pass --calibration)\n",
                 sessionPath.c_str(), scenePath.c_str());
    return fail();
  }
  return mapper;
}

int runReplay(const LiveArgs& given) {
  // SESSION SCENE, or SCENE SESSION as view and live take the scene first: told apart by content.
  LiveArgs a = given;
  if (looksLikeScene(a.session) && !looksLikeScene(a.scene)) std::swap(a.session, a.scene);
  if (isWorldFile(a.scene) && !isWorldFile(a.session)) std::swap(a.session, a.scene);  // SCENE CLIP.wrl
  if (isWorldFile(a.session)) {
    a.clip = a.session;
    return runClip(a, "replay");
  }
  if (int rc = checkOutputArgs(a, "replay"); rc != kExitOk) return rc;
  if (!checkRigArgs(a) || !checkOscOutArgs(a)) return kExitUsage;
  auto script = parseScript(a);
  if (!script) return kExitUsage;
  std::optional<sim::Session> session = loadSession(a.session);
  if (!session) return kExitInvalidInput;
  if (!a.exportSession.empty()) {
    if (auto saved = sim::saveSession(a.exportSession, *session); !saved) {
      std::fputs(saved.error().str().c_str(), stderr);
      return kExitIoError;
    }
    std::printf("puppeteer: wrote %s\n", a.exportSession.c_str());
  }
  int code = kExitOk;
  auto pipeline = makePipeline(a, &code);
  if (!pipeline) return code;
  const std::string name = std::filesystem::path(a.session).filename().string();
  std::optional<SampleMapper> mapper = replayMapper(a.session, *session, pipeline->character(), a.calibration, a.map,
                                                    a.scene, &code);
  if (!mapper) return code;
  std::unique_ptr<PoseSource> source;
  if (a.stepped)
    source = std::make_unique<SteppedReplayPoseSource>(*session, std::move(*mapper), name);
  else
    source = std::make_unique<ReplayPoseSource>(*session, std::move(*mapper), a.speed, name);
  ViewerOptions v = viewerOptions(a, "IMPS Puppeteer: replay " + name);
  if (int rc = addPropsAndScript(a, pipeline->character(), std::move(*script), v); rc != kExitOk) return rc;
  return runWithOscOut(a, *pipeline, *source, v);
}

int runLive(const LiveArgs& a) {
  if (int rc = checkOutputArgs(a, "live"); rc != kExitOk) return rc;
  if (isWorldFile(a.scene)) {
    std::fprintf(stderr, "puppeteer live: error: %s is a world: drive its characters with `puppeteer view %s "
                         "--drive NAME=%s` (docs/world-format.md#worlds)\n",
                 a.scene.c_str(), a.scene.c_str(), a.device.c_str());
    return kExitUsage;
  }
  if (!checkOscOutArgs(a)) return kExitUsage;
  // --rig alone is allowed here: key k calibrates it (and saves to --calibration-out); until then channels map by
  // name.
  if (!a.rig.empty() && a.calibration.empty() && a.calibrationOut.empty()) {
    std::fprintf(stderr,
                 "puppeteer: error: --rig %s: a rig map has no offsets; pass --calibration FILE, or "
                 "--calibration-out FILE and press k to calibrate it\n",
                 a.rig.c_str());
    return kExitUsage;
  }
  if (!a.rig.empty() && !a.calibration.empty())
    std::fprintf(stderr, "puppeteer: note: --rig is ignored: the calibration %s contains its rig map\n",
                 a.calibration.c_str());
  if (!a.record.empty() && std::filesystem::exists(a.record)) {
    std::fprintf(stderr, "puppeteer: error: --record %s: the file exists; recordings never overwrite a file\n",
                 a.record.c_str());
    return kExitIoError;
  }
  if (!(a.calibrate.windowMs > 0) || !(a.calibrate.delayMs >= 0) || !(a.calibrate.maxNoiseDeg > 0)) {
    std::fprintf(stderr, "puppeteer: error: --window-ms and --max-noise-deg must be positive, --calibrate-delay-ms "
                         "not negative\n");
    return kExitUsage;
  }
  auto script = parseScript(a);
  if (!script) return kExitUsage;
  auto spec = drivers::parseDeviceSpec(a.device);
  if (!spec) {
    std::fputs(spec.error().str().c_str(), stderr);
    return kExitUsage;
  }
  int code = kExitOk;
  auto pipeline = makePipeline(a, &code);
  if (!pipeline) return code;
  std::optional<SampleMapper> mapper;
  if (!a.calibration.empty()) {
    const drivers::DeviceSessionOptions session = drivers::sessionOptionsFor(*spec);
    const bool lines = session.protocol == drivers::WireProtocol::Lines;
    mapper = readCalibration(a.calibration, pipeline->character(), nullptr, {}, lines ? session.lineBitsPerChannel : 0);
    if (!mapper) return kExitInvalidInput;
  }
  ViewerOptions v = viewerOptions(a, "IMPS Puppeteer: live " + a.device);
  if (int rc = addPropsAndScript(a, pipeline->character(), std::move(*script), v); rc != kExitOk) return rc;
  if (spec->kind == drivers::DeviceKind::Osc) {
    if (!a.record.empty()) {
      std::fprintf(stderr, "puppeteer: error: --record: an OSC pose stream is not recorded (record at the sender)\n");
      return kExitUsage;
    }
    auto source = OscPoseSource::open(*spec, pipeline->character(), std::move(mapper));
    if (!source) {
      std::fprintf(stderr, "puppeteer live: %s\n", drivers::errorText(source.error()).c_str());
      return kExitIoError;
    }
    return runWithOscOut(a, *pipeline, **source, v);
  }
  imps::SteadyClock clock;  // the simulated armature's; outlives the source below
  auto opener = openerForSpec(*spec, clock, "live");
  if (!opener) {
    std::fputs(opener.error().diagnostics.str().c_str(), stderr);
    return exitCodeFor(opener.error().kind);
  }
  LiveSourceOptions live;
  live.recordPath = a.record;
  live.recordDir = a.recordDir;
  live.scenePath = a.scene;
  live.rigPath = a.rig;
  live.calibrationPath = a.calibration;
  live.calibrationOut = a.calibrationOut;
  live.calibrate = a.calibrate;
  LivePoseSource source(*opener, drivers::sessionOptionsFor(*spec), pipeline->character(), a.device,
                        std::move(mapper), std::move(live));
  return runWithOscOut(a, *pipeline, source, v);
}

}  // namespace

// view --clip: which clip, how its targets map to joints, how fast.
void addClipOptions(CLI::App* cmd, LiveArgs& a) {
  cmd->add_option("--clip-name", a.clipName, "With --clip: the TimeSensor to play (default: the file's first clip)");
  cmd->add_option("--map", a.map, "With --clip: names (targets drive joints of the same name) or a joint map FILE.json")
      ->capture_default_str();
  cmd->add_option("--speed", a.speed, "With --clip: playback speed (1 = real time)")->check(nonNegativeNumber());
}

void addLiveCommands(CLI::App& app, Commands& commands) {
  auto view = std::make_shared<LiveArgs>();
  CLI::App* viewCmd = app.add_subcommand("view", "Open the live app on a scene and pose it by hand with the mouse");
  viewCmd->add_option("scene", view->scene, "Scene file (.wrl)")->required()->check(inputFile());
  viewCmd->add_option("--clip", view->clip, "Play a VRML 97 clip file's keyframes on the scene (docs/world-format.md)")
      ->check(inputFile());
  addClipOptions(viewCmd, *view);
  viewCmd->add_option("--drive", view->drives,
                      "With a world: NAME=SOURCE drives the character NAME from a clip FILE.wrl[#TIMESENSOR], a "
                      "session or .bvh file, or a device spec (repeatable; docs/world-format.md#worlds)");
  addCommonOptions(viewCmd, *view);
  commands.push_back({viewCmd, [view] { return runView(*view); }});

  auto replay = std::make_shared<LiveArgs>();
  CLI::App* replayCmd =
      app.add_subcommand("replay", "Play a recorded session (or a .bvh clip) on a scene in the live app");
  replayCmd->add_option("session", replay->session,
                        "Session file, or a .bvh clip converted on the fly (SCENE SESSION works too)")
      ->required()
      ->check(inputFile());
  replayCmd->add_option("scene", replay->scene, "Scene file (.wrl)")->required()->check(inputFile());
  replayCmd->add_option("--calibration", replay->calibration,
                        "Calibration file (default: the one recorded in the session, else channels by name)")
      ->check(inputFile());
  replayCmd->add_option("--rig", replay->rig, "Rig map (only together with --calibration, which contains it)")
      ->check(inputFile());
  replayCmd->add_option("--map", replay->map,
                        "BVH clips: auto (name rules for CMU, Mixamo, Rokoko, Biovision, Bandai-Namco, 3ds-Max Biped "
                        "+ the hierarchy), names (same joint names) or a joint map FILE.json")
      ->capture_default_str();
  replayCmd->add_option("--speed", replay->speed, "Playback speed (1 = real time; 0 = as fast as possible)")
      ->check(nonNegativeNumber());
  replayCmd->add_flag("--stepped", replay->stepped,
                      "One recorded sample per rendered frame, no clock: deterministic (tests)");
  replayCmd->add_option("--export-session", replay->exportSession,
                        "Also save the session (e.g. a converted .bvh) to this new file");
  replayCmd->add_option("--clip-name", replay->clipName,
                         "VRML clips: the TimeSensor to play (default: the file's first clip)");
  addOscOutOption(replayCmd, *replay);
  addCommonOptions(replayCmd, *replay);
  commands.push_back({replayCmd, [replay] { return runReplay(*replay); }});

  auto live = std::make_shared<LiveArgs>();
  CLI::App* liveCmd = app.add_subcommand("live", "Drive a scene's character from an armature in the live app");
  liveCmd->add_option("scene", live->scene, "Scene file (.wrl)")->required()->check(inputFile());
  liveCmd
      ->add_option("--device", live->device,
                   "Device spec (docs/devices.md): serial:/dev/ttyACM0, sim:SESSION, osc.udp://:PORT …")
      ->required();
  liveCmd->add_option("--calibration", live->calibration,
                      "Calibration file (puppeteer calibrate); without one, channels map to joints by name")
      ->check(inputFile());
  liveCmd->add_option("--rig", live->rig,
                      "Rig map for key k when no --calibration is given (with --calibration-out); ignored with "
                      "--calibration, which contains its rig map")
      ->check(inputFile());
  liveCmd->add_option("--record", live->record, "Start recording every raw sample into this new session file at once");
  liveCmd->add_option("--record-dir", live->recordDir, "Where key o creates take-YYYYMMDD-HHMMSS.session")
      ->capture_default_str();
  liveCmd->add_option("--calibration-out", live->calibrationOut,
                      "Where key k saves the new calibration (default: the --calibration file, replaced atomically)");
  liveCmd->add_option("--calibrate-delay-ms", live->calibrate.delayMs,
                      "Key k: time to get into the calibration pose before averaging")
      ->capture_default_str();
  liveCmd->add_option("--window-ms", live->calibrate.windowMs, "Key k: how long to average the calibration pose")
      ->capture_default_str();
  liveCmd->add_option("--max-noise-deg", live->calibrate.maxNoiseDeg,
                      "Key k: reject the window above this per-channel standard deviation")
      ->capture_default_str();
  addOscOutOption(liveCmd, *live);
  addCommonOptions(liveCmd, *live);
  commands.push_back({liveCmd, [live] { return runLive(*live); }});
}

}  // namespace imps::app
