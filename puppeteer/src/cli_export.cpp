// SPDX-License-Identifier: MIT
// `puppeteer export INPUT SCENE -o OUT`: a take (a .session through its calibration) or a clip (a .bvh, retargeted)
// on the character, written as the character's skeleton (.bvh), a skinned animated glTF (.glb) or a baked surface
// sequence (numbered .ply/.obj); or the old raw-channel BVH with --raw-channels.
#include <CLI/CLI.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cli.h"
#include "export_gltf.h"
#include "export_surfaces.h"
#include "export_take.h"
#include "map_option.h"
#include "session_calibration.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

struct ExportArgs {
  std::string input, scene, output;
  std::string calibration, map = "auto";
  double fps = 0;
  std::string frames;
  bool rawChannels = false;
  float cell = 0.02f;
  std::string polygonizer = "mc";
};

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// "A:B" (inclusive, 0-based; either side may be empty) into the selection; false on bad text.
bool parseFrameRange(const std::string& text, FrameSelection& s) {
  if (text.empty()) return true;
  const size_t colon = text.find(':');
  if (colon == std::string::npos) return false;
  try {
    size_t used = 0;
    if (colon > 0) {
      s.first = std::stol(text.substr(0, colon), &used);
      if (used != colon || s.first < 0) return false;
    }
    if (colon + 1 < text.size()) {
      s.last = std::stol(text.substr(colon + 1), &used);
      if (used != text.size() - colon - 1 || s.last < 0) return false;
    }
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

// A progress line on a terminal (frames done, rate, time left); nothing when stderr is not a terminal.
class Progress {
 public:
  explicit Progress(size_t total) : total_(total), tty_(isatty(fileno(stderr)) != 0), start_(clock::now()) {}
  void operator()(size_t done) {
    if (!tty_) return;
    const double s = std::chrono::duration<double>(clock::now() - start_).count();
    const double rate = s > 0 ? double(done) / s : 0;
    const double left = rate > 0 ? double(total_ - done) / rate : 0;
    std::fprintf(stderr, "\rframe %zu/%zu  %.1f frames/s  %.0f s left   ", done, total_, rate, left);
    if (done == total_) std::fputc('\n', stderr);
    std::fflush(stderr);
  }

 private:
  using clock = std::chrono::steady_clock;
  size_t total_;
  bool tty_;
  clock::time_point start_;
};

// The old conversion: every raw channel as a one-channel joint (or the clip's own skeleton for sessions made
// from BVH), no calibration.
int writeRawChannels(const ExportArgs& a) {
  if (lowerExtension(a.input) != ".session" || lowerExtension(a.output) != ".bvh") {
    std::fprintf(stderr, "puppeteer export: error: --raw-channels writes a .session's raw channels to a .bvh\n");
    return kExitUsage;
  }
  if (int rc = checkOutputPath("export", "-o", a.output); rc != kExitOk) return rc;
  auto session = sim::readSession(a.input);
  if (!session) {
    std::fputs(session.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  auto clip = sim::sessionToBvh(*session);
  if (!clip) {
    std::fputs(clip.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  if (auto saved = sim::saveBvh(a.output, *clip); !saved) {
    std::fprintf(stderr, "puppeteer export: error: %s\n", saved.error().firstError().c_str());
    return kExitIoError;
  }
  std::printf("%s: raw channels (encoder counts as angles, no calibration, not the character's skeleton) -> %s: "
              "%zu joints, %zu frames\n",
              a.input.c_str(), a.output.c_str(), clip->joints.size(), clip->frames.size());
  return kExitOk;
}

// A clip (a .bvh, or a session made from one) through the retargeter.
std::optional<Take> clipTake(const sim::BvhClip& clip, const ExportArgs& a, const Character& character,
                             const FrameSelection& selection, int* code) {
  const auto options = retargetOptionsFor(a.map, clip, character);
  if (!options) return *code = kExitInvalidInput, std::nullopt;
  auto r = Retargeter::create(clip, character, *options);
  if (!r) {
    std::fprintf(stderr, "puppeteer export: error: %s: %s\n", a.input.c_str(), r.error().all().front().message.c_str());
    return *code = kExitInvalidInput, std::nullopt;
  }
  printRetargetReport(std::filesystem::path(a.input).filename().string(), a.map, r->report());
  auto take = takeFromClip(clip, *r, character, selection);
  if (!take) {
    std::fprintf(stderr, "puppeteer export: error: %s\n", take.error().all().front().message.c_str());
    return *code = kExitUsage, std::nullopt;
  }
  return std::move(*take);
}

// The take on the character from INPUT: a .bvh (retargeted), a session made from a BVH clip (retargeted), or a
// session through --calibration or its own recorded calibration.
std::optional<Take> loadTake(const ExportArgs& a, const Character& character, int* code) {
  FrameSelection selection;
  selection.fps = a.fps;
  if (!parseFrameRange(a.frames, selection)) {
    std::fprintf(stderr, "puppeteer export: error: --frames %s: expected A:B (0-based, inclusive)\n", a.frames.c_str());
    return *code = kExitUsage, std::nullopt;
  }
  if (lowerExtension(a.input) == ".bvh") {
    Diagnostics warnings;
    auto clip = sim::readBvh(a.input, &warnings);
    std::fputs(warnings.str().c_str(), stderr);
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return *code = kExitInvalidInput, std::nullopt;
    }
    return clipTake(*clip, a, character, selection, code);
  }
  auto session = sim::readSession(a.input);
  if (!session) {
    std::fputs(session.error().str().c_str(), stderr);
    return *code = kExitInvalidInput, std::nullopt;
  }
  if (!session->recovery.message.empty()) std::fprintf(stderr, "%s\n", session->recovery.message.c_str());
  if (a.calibration.empty() && session->skeleton) {
    auto clip = sim::sessionToBvh(*session);
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return *code = kExitInvalidInput, std::nullopt;
    }
    return clipTake(*clip, a, character, selection, code);
  }
  std::optional<calibration::Calibration> cal;
  const drivers::DeviceInfo* device = session->devices.empty() ? nullptr : &session->devices[0];
  if (!a.calibration.empty()) {
    auto c = calibration::Calibration::readFile(a.calibration, &character, device, session->devices);
    if (!c) {
      std::fputs(c.error().str().c_str(), stderr);
      return *code = kExitInvalidInput, std::nullopt;
    }
    cal = std::move(*c);
  } else {
    auto c = calibrationForSample(*session, session->samples.size(), &character, a.input);
    if (!c) {
      std::fputs(c.error().str().c_str(), stderr);
      return *code = kExitInvalidInput, std::nullopt;
    }
    if (!*c) {
      std::fprintf(stderr, "puppeteer export: error: %s has no recorded calibration: pass --calibration FILE\n",
                   a.input.c_str());
      return *code = kExitInvalidInput, std::nullopt;
    }
    cal = std::move(**c);
  }
  auto take = takeFromSession(*session, *cal, character, selection);
  if (!take) {
    std::fprintf(stderr, "puppeteer export: error: %s\n", take.error().all().front().message.c_str());
    return *code = kExitUsage, std::nullopt;
  }
  return std::move(*take);
}

int runExport(const ExportArgs& a) {
  if (a.rawChannels) return writeRawChannels(a);
  const std::string ext = lowerExtension(a.output);
  const bool sequence = (ext == ".ply" || ext == ".obj") && a.output.find('#') != std::string::npos;
  if (ext != ".bvh" && ext != ".glb" && !sequence) {
    std::fprintf(stderr,
                 "puppeteer export: error: %s: OUT must end in .bvh (the character's skeleton), .glb (skinned, "
                 "animated glTF) or be a numbered .ply/.obj pattern such as take_####.ply (a surface sequence)\n",
                 a.output.c_str());
    return kExitUsage;
  }
  // A sequence's folder is created when missing; a single file's must exist, found before any work.
  if (!sequence)
    if (int rc = checkOutputPath("export", "-o", a.output); rc != kExitOk) return rc;
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;
  int code = kExitOk;
  const std::optional<Take> take = loadTake(a, character, &code);
  if (!take) return code;
  Progress progress(take->frames());
  if (ext == ".bvh") {
    if (auto saved = sim::saveBvh(a.output, characterClip(character, *take)); !saved) {
      std::fprintf(stderr, "puppeteer export: error: %s\n", saved.error().firstError().c_str());
      return kExitIoError;
    }
  } else if (ext == ".glb") {
    GltfExportOptions o;
    o.cellSize = a.cell;
    if (auto written = writeSkinnedGlb(character, *take, o, a.output); !written) {
      std::fprintf(stderr, "puppeteer export: error: %s\n", written.error().all().front().message.c_str());
      return kExitIoError;
    }
  } else {
    SurfaceSequenceOptions o;
    o.cellSize = a.cell;
    o.particles = a.polygonizer == "particles";
    o.progress = [&](size_t done) { progress(done); };
    if (auto written = writeSurfaceSequence(loaded->scene, character, *take, o, a.output); !written) {
      std::fprintf(stderr, "puppeteer export: error: %s\n", written.error().all().front().message.c_str());
      return kExitIoError;
    }
  }
  std::printf("puppeteer: wrote %s: %zu frames at %.4g frames per second, %zu joints\n", a.output.c_str(),
              take->frames(), 1.0 / take->frameTime, character.joints().size());
  return kExitOk;
}

}  // namespace

void addExportCommands(CLI::App& app, Commands& commands) {
  auto a = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Write a take (.session) or a clip (.bvh) on the character: its skeleton as BVH, a skinned animated "
                "glTF (.glb) or a baked surface sequence (take_####.ply)");
  cmd->add_option("input", a->input, "A .session (through its calibration) or a .bvh clip (retargeted)")
      ->required()
      ->check(inputFile());
  cmd->add_option("scene", a->scene, "Scene file (.wrl): the character")->required()->check(inputFile());
  cmd->add_option("-o,--output", a->output,
                  "OUT.bvh, OUT.glb, or a numbered OUT_####.ply / OUT_####.obj sequence (# = frame digits)")
      ->required();
  cmd->add_option("--calibration", a->calibration, "Calibration for a .session (default: the one it recorded)")
      ->check(inputFile());
  cmd->add_option("--map", a->map, "BVH clips: auto, names or a joint map FILE.json (docs/calibration.md)")
      ->capture_default_str();
  cmd->add_option("--fps", a->fps, "Resample to this frame rate (default: the input's own frames)")
      ->check(positiveNumber());
  cmd->add_option("--frames", a->frames, "A:B: only output frames A to B (0-based, inclusive; after --fps)");
  cmd->add_option("--cell", a->cell, "Marching Cubes cell in metres for .glb and surface sequences")
      ->check(CLI::Range(0.002f, 0.5f))
      ->capture_default_str();
  cmd->add_option("--polygonizer", a->polygonizer, "Surface sequences: mc (Marching Cubes) or particles")
      ->check(CLI::IsMember({"mc", "particles"}))
      ->capture_default_str();
  cmd->add_flag("--raw-channels", a->rawChannels,
                "The old conversion: a .session's raw channels as BVH joints (no calibration, not the character)");
  commands.push_back({cmd, [a] { return runExport(*a); }});
}

}  // namespace imps::app
