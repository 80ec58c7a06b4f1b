// SPDX-License-Identifier: MIT
// `puppeteer calibrate`: joint-offset calibration of an armature against a character's calibration pose, from a
// live device (interactive) or the first milliseconds of a recorded session (non-interactive). docs/calibration.md.
#include "calibration_flow.h"
#include "cli.h"
#include "device_opener.h"
#include "json_output.h"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "calibration/calibration.h"
#include "calibration/offset_calibration.h"
#include "calibration/rig_map.h"
#include "drivers/device_session.h"
#include "drivers/device_spec.h"
#include "drivers/serial_transport.h"
#include "imps/character.h"
#include "imps/diagnostic.h"
#include "sim/session_file.h"
#include "sim/simulated_armature.h"

namespace imps::app {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

// Where the walkthrough talks to the technician: stdout, or stderr with --json (stdout then holds only the report).
FILE* talk = stdout;

struct CalibrateArgs {
  std::string rig, scene, session, device, output, checkPose;
  double windowMs = 500;
  double maxNoiseDeg = 0.5;
  bool noWait = false;
  bool json = false;
};

int64_t timeOf(const drivers::Sample& s, bool deviceTime) { return deviceTime ? s.deviceTimeNs : s.arrivalTimeNs; }

// The samples of device 0 within `windowMs` of the first (fromEnd: of the last) one.
std::vector<drivers::Sample> sessionWindow(const sim::Session& session, double windowMs, bool fromEnd) {
  std::vector<drivers::Sample> all;
  for (size_t i = 0; i < session.samples.size(); ++i)
    if (session.sampleDevice[i] == 0) all.push_back(session.samples[i]);
  std::vector<drivers::Sample> out;
  if (all.empty()) return out;
  const bool deviceTime = !session.devices.empty() && session.devices[0].hasDeviceTimestamp;
  const auto span = static_cast<int64_t>(windowMs * 1e6);
  if (!fromEnd) {
    const int64_t t0 = timeOf(all.front(), deviceTime);
    for (const drivers::Sample& s : all)
      if (timeOf(s, deviceTime) - t0 <= span) out.push_back(s);
  } else {
    const int64_t t1 = timeOf(all.back(), deviceTime);
    for (const drivers::Sample& s : all)
      if (t1 - timeOf(s, deviceTime) <= span) out.push_back(s);
  }
  return out;
}

// A live device for the interactive flow: the I/O thread and its mailbox.
// Members are destroyed bottom-up: the session (and its I/O thread) goes before the mailbox and clock it uses.
struct LiveDevice {
  imps::SteadyClock clock;
  std::unique_ptr<drivers::PoseMailbox> mailbox;
  std::unique_ptr<drivers::DeviceSession> session;

  // Collects `windowMs` of samples, starting now.
  std::vector<drivers::Sample> collect(double windowMs) {
    std::vector<drivers::Sample> discard, out;
    mailbox->drain(discard);  // what arrived while the technician was getting ready
    const auto end = std::chrono::steady_clock::now() + std::chrono::microseconds(static_cast<int64_t>(windowMs * 1e3));
    while (std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      mailbox->drain(out);
    }
    mailbox->drain(out);
    return out;
  }
};

int openDevice(const std::string& specText, LiveDevice& live, drivers::DeviceInfo& info) {
  auto spec = drivers::parseDeviceSpec(specText);
  if (!spec) {
    std::fputs(spec.error().str().c_str(), stderr);
    return kExitUsage;
  }
  auto opener = openerForSpec(*spec, live.clock, "calibrate");
  if (!opener) {
    std::fputs(opener.error().diagnostics.str().c_str(), stderr);
    return exitCodeFor(opener.error().kind);
  }
  drivers::PoseMailboxOptions mo;
  mo.queueCapacity = 1 << 14;
  live.mailbox = std::make_unique<drivers::PoseMailbox>(mo);
  live.session = std::make_unique<drivers::DeviceSession>(*opener, *live.mailbox, drivers::sessionOptionsFor(*spec));
  live.session->start();
  std::fprintf(talk, "Connecting to %s ...\n", specText.c_str());
  std::fflush(talk);
  if (!live.session->waitForState(drivers::ConnectionState::Streaming, 10'000) || !live.session->deviceInfo()) {
    std::fprintf(stderr, "puppeteer calibrate: error: %s did not start streaming: %s\n", specText.c_str(),
                 live.session->lastError().empty() ? "timed out" : live.session->lastError().c_str());
    return kExitIoError;
  }
  info = *live.session->deviceInfo();
  std::fprintf(talk, "Connected: \"%s\", %d channels of %d bits\n", info.name.c_str(), info.channelCount,
               info.bitsPerChannel);
  return kExitOk;
}

void waitForEnter(const std::string& instruction, bool noWait) {
  std::fprintf(talk, "\n%s\n", instruction.c_str());
  if (noWait) {
    std::fprintf(talk, "(--no-wait: averaging now)\n");
    std::fflush(talk);
    return;
  }
  std::fprintf(talk, "Press Enter when ready.");
  std::fflush(talk);
  std::string line;
  std::getline(std::cin, line);
  if (!::isatty(STDIN_FILENO)) std::fprintf(talk, "\n");
}

int runCalibrate(const CalibrateArgs& a) {
  talk = a.json ? stderr : stdout;
  if (a.session.empty() == a.device.empty()) {
    std::fprintf(stderr, "puppeteer calibrate: error: give exactly one of --session SESSION or --device SPEC\n");
    return kExitUsage;
  }
  if (!(a.windowMs > 0)) {
    std::fprintf(stderr, "puppeteer calibrate: error: --window-ms must be positive\n");
    return kExitUsage;
  }
  if (int rc = checkOutputPath("calibrate", "-o", a.output); rc != kExitOk) return rc;
  // ---- Inputs: the character, the device description and samples source, the rig map, the check pose.
  auto loaded = loadScene(a.scene);
  if (!loaded) return kExitInvalidInput;
  const Character& character = loaded->character;

  drivers::DeviceInfo info;
  std::optional<sim::Session> session;
  LiveDevice live;
  if (!a.session.empty()) {
    auto read = sim::readSession(a.session);
    if (!read) {
      std::fputs(read.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    if (!read->recovery.message.empty()) std::fprintf(stderr, "%s\n", read->recovery.message.c_str());
    if (read->devices.empty() || read->samples.empty()) {
      std::fprintf(stderr, "%s: error: the session holds no samples to calibrate from\n", a.session.c_str());
      return kExitInvalidInput;
    }
    session = std::move(*read);
    info = session->devices[0];
  } else if (int rc = openDevice(a.device, live, info); rc != kExitOk) {
    return rc;
  }

  Diagnostics warnings;
  auto rig = calibration::readRigMapFile(a.rig, {&character, &info, false}, &warnings);
  std::fputs(warnings.str().c_str(), stderr);
  if (!rig) {
    std::fputs(rig.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  std::optional<std::vector<calibration::PoseTarget>> targets;
  Json report{{"output", a.output}, {"rig", a.rig}, {"scene", a.scene}, {"source", session ? a.session : a.device}};
  if (!a.checkPose.empty()) {
    auto t = calibration::readCheckPoseFile(a.checkPose, &character);
    if (!t) {
      std::fputs(t.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    targets = std::move(*t);
  }
  std::fprintf(talk, "Rig map %s: %zu channels drive %zu joints of %s\n", a.rig.c_str(), rig->channels.size(),
              rig->joints.size(), a.scene.c_str());

  // ---- The calibration pose: average a window, reject it when noisy.
  calibration::WindowOptions wo;
  wo.maxStdDev = a.maxNoiseDeg * kDegree;
  wo.device = &info;
  std::vector<drivers::Sample> window;
  if (session) {
    window = sessionWindow(*session, a.windowMs, false);
    std::fprintf(talk, "Calibration pose: the first %.0f ms of %s (%zu samples)\n", a.windowMs, a.session.c_str(),
                window.size());
  } else {
    waitForEnter("Hold the armature in the calibration pose (the T-pose of " + a.scene +
                 ": arms straight out to the sides, legs straight, facing forward) and keep it still.",
                 a.noWait);
    window = live.collect(a.windowMs);
    std::fprintf(talk, "Averaged %zu samples over %.0f ms.\n", window.size(), a.windowMs);
  }
  calibration::WindowAverage average;
  auto calibrated = calibration::calibrateOffsets(*rig, window, wo, &average);
  if (!calibrated) {
    std::fprintf(stderr, "puppeteer calibrate: error: the calibration-pose window was rejected:\n");
    for (const Diagnostic& p : calibrated.error().all()) std::fprintf(stderr, "  %s\n", p.message.c_str());
    std::fprintf(stderr, "Nothing was written. Hold the armature still in the calibration pose and try again.\n");
    return kExitInvalidInput;
  }
  const auto noisiest =
      std::max_element(average.channels.begin(), average.channels.end(),
                       [](const auto& x, const auto& y) { return x.stdDevRadians < y.stdDevRadians; });
  if (noisiest != average.channels.end()) {
    std::fprintf(talk, "Noise: at most %.3f deg (%s)\n", noisiest->stdDevRadians / kDegree, noisiest->label.c_str());
    report["noiseMaxDeg"] = noisiest->stdDevRadians / kDegree;
    report["noisiestChannel"] = noisiest->label;
  }
  report["windowSamples"] = window.size();

  calibrated->info =
      calibrationInfoJson(a.scene, a.rig, session ? a.session : a.device, a.windowMs, window.size(), info.serialNumber);
  calibrated->device = info.name;
  auto cal = calibration::Calibration::create(std::move(*calibrated), &character, &info);
  if (!cal) {
    std::fputs(cal.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }

  // ---- The optional check pose: signs and gains.
  if (targets) {
    std::vector<drivers::Sample> checkWindow;
    if (session) {
      checkWindow = sessionWindow(*session, a.windowMs, true);
      std::fprintf(talk, "Check pose: the last %.0f ms of %s (%zu samples)\n", a.windowMs, a.session.c_str(),
                  checkWindow.size());
    } else {
      waitForEnter("Now hold the check pose described in " + a.checkPose + " and keep it still.", a.noWait);
      checkWindow = live.collect(a.windowMs);
    }
    const calibration::WindowAverage checkAverage = calibration::averageWindow(cal->rigMap(), checkWindow, wo);
    for (const std::string& p : checkAverage.problems) std::fprintf(stderr, "warning: check pose: %s\n", p.c_str());
    const calibration::PoseCheck check = calibration::checkPose(*cal, checkAverage, *targets);
    for (const std::string& w : check.warnings) std::fprintf(stderr, "warning: check pose: %s\n", w.c_str());
    std::fprintf(talk, "Check pose: %zu channels checked, %zu look wrong\n", check.channels.size(),
                 check.problems.size());
    report["checkPose"] = {{"checked", check.channels.size()}, {"wrong", check.problems.size()}};
    if (!check.ok()) {
      for (const std::string& p : check.problems) std::fprintf(stderr, "%s: error: %s\n", a.rig.c_str(), p.c_str());
      std::fprintf(stderr, "Nothing was written. Fix the rig map and calibrate again.\n");
      return kExitInvalidInput;
    }
  }

  if (auto saved = cal->save(a.output); !saved) {
    std::fprintf(stderr, "%s\n", saved.error().message.c_str());
    return kExitIoError;
  }
  std::fprintf(talk, "Wrote %s (%zu channels, %zu joints)\n", a.output.c_str(), cal->rigMap().channels.size(),
              cal->rigMap().joints.size());
  report["channels"] = cal->rigMap().channels.size();
  report["joints"] = cal->rigMap().joints.size();
  if (a.json) printJson(report);
  return kExitOk;
}

}  // namespace

void addCalibrationCommands(CLI::App& app, Commands& commands) {
  auto args = std::make_shared<CalibrateArgs>();
  CLI::App* cmd =
      app.add_subcommand("calibrate", "Calibrate an armature's offsets in the character's calibration pose");
  cmd->add_option("--rig", args->rig, "rig map (docs/calibration.md)")->required()->check(inputFile());
  cmd->add_option("--scene", args->scene, "the character's scene file (its pose is the calibration pose)")
      ->required()
      ->check(inputFile());
  cmd->add_option("--session", args->session, "use the first --window-ms of a recorded session (non-interactive)")
      ->check(inputFile());
  cmd->add_option("--device", args->device, "calibrate a live device, e.g. serial:/dev/ttyACM0 (interactive)");
  cmd->add_option("-o,--output", args->output, "calibration file to write (replaced atomically)")->required();
  cmd->add_option("--window-ms", args->windowMs, "how long to average each pose")->capture_default_str();
  cmd->add_option("--check-pose", args->checkPose, "a second known pose to check signs and gains (JSON)")
      ->check(inputFile());
  cmd->add_option("--max-noise-deg", args->maxNoiseDeg, "reject the window above this per-channel std deviation")
      ->capture_default_str()
      ->check(positiveNumber());
  cmd->add_flag("--json", args->json, "Print the result as JSON on stdout (the walkthrough's text goes to stderr)");
  cmd->add_flag("--no-wait", args->noWait, "with --device: do not wait for Enter before each pose (scripts, tests)");
  commands.push_back({cmd, [args] { return runCalibrate(*args); }});
}

}  // namespace imps::app
