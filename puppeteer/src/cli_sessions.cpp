// SPDX-License-Identifier: MIT
// `puppeteer info` and `puppeteer convert`: what a recorded session holds, and sessions <-> BVH clips.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli.h"
#include "json_output.h"
#include "progress.h"
#include "drivers/device_session.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "sim/session_file.h"
#include "sim/session_link.h"

namespace imps::app {
namespace {

// One device's link as `info` prints it: samples, rate while sending, missing sequence numbers, restarts, outages.

void printLink(const sim::SessionLink& a) {
  const double seconds = a.spanSeconds;
  std::printf("    %zu samples over %.3f s (%.1f per second while sending), %llu sequence numbers missing, "
              "%llu restart%s of the numbering (device reboots)\n",
              a.samples, seconds, a.rateHz(), static_cast<unsigned long long>(a.missing),
              static_cast<unsigned long long>(a.restarts), a.restarts == 1 ? "" : "s");
  if (a.outages.empty()) return;
  std::printf("    %zu outage%s (pauses over 100 ms), %.3f s in all:\n", a.outages.size(),
              a.outages.size() == 1 ? "" : "s", double(a.outageNs) * 1e-9);
  constexpr size_t kShown = 10;
  for (size_t i = 0; i < a.outages.size() && i < kShown; ++i) {
    const sim::SessionOutage& o = a.outages[i];
    std::printf("      at %.3f s (after sample %zu): %.3f s, %llu sequence numbers missing\n", double(o.startNs) * 1e-9,
                o.afterSample, double(o.lengthNs) * 1e-9, static_cast<unsigned long long>(o.missing));
  }
  if (a.outages.size() > kShown) std::printf("      … and %zu more\n", a.outages.size() - kShown);
}

// The link's counters as the recorder stored them (COUNTERS record), labelled when this build knows the name.
void printCounters(const sim::SessionCounters& c) {
  std::printf("  device link counters (device %u):", unsigned(c.device));
  const char* separator = " ";
  for (const sim::SessionCounter& v : c.values) {
    const char* label = drivers::counterLabel(v.name);
    std::printf("%s%s: %llu", separator, label ? label : v.name.c_str(), static_cast<unsigned long long>(v.value));
    separator = ", ";
  }
  std::printf("\n");
}

Json infoJson(const std::string& path, const sim::Session& s) {
  Json devices = Json::array(), calibrations = Json::array(), markers = Json::array();
  for (size_t d = 0; d < s.devices.size(); ++d) {
    const drivers::DeviceInfo& info = s.devices[d];
    const sim::SessionLink link = sim::analyzeSessionLink(s, d);
    Json outages = Json::array();
    for (const sim::SessionOutage& o : link.outages)
      outages.push_back({{"startSeconds", double(o.startNs) * 1e-9}, {"afterSample", o.afterSample},
                         {"seconds", double(o.lengthNs) * 1e-9}, {"missing", o.missing}});
    Json counters = Json::object();
    for (const sim::SessionCounters& c : s.counters)
      if (c.device == d)
        for (const sim::SessionCounter& v : c.values) counters[v.name] = v.value;
    devices.push_back({{"name", info.name},
                       {"serialNumber", info.serialNumber},
                       {"firmware", info.firmwareVersion},
                       {"channels", info.channelCount},
                       {"bits", info.bitsPerChannel},
                       {"deviceTimestamps", info.hasDeviceTimestamp},
                       {"samples", link.samples},
                       {"seconds", link.spanSeconds},
                       {"rateHz", link.rateHz()},
                       {"missingSequenceNumbers", link.missing},
                       {"restarts", link.restarts},
                       {"outages", std::move(outages)},
                       {"counters", std::move(counters)}});
  }
  for (const auto& c : s.calibrations) calibrations.push_back({{"firstSample", c.firstSample}});
  for (const auto& m : s.markers) markers.push_back({{"firstSample", m.firstSample}, {"label", m.label}});
  return Json{{"file", path},
              {"formatVersion", s.formatVersion},
              {"samples", s.samples.size()},
              {"devices", std::move(devices)},
              {"calibrations", std::move(calibrations)},
              {"markers", std::move(markers)},
              {"notes", s.notes.size()},
              {"skeleton", s.skeleton.has_value()},
              {"closedCleanly", s.recovery.closedCleanly},
              {"recovery", s.recovery.message}};
}

int runInfo(const std::string& path, bool json) {
  Progress progress("info");
  progress.phase("reading " + path);
  auto session = sim::readSession(path);
  progress.done();
  if (!session) {
    std::fputs(session.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  const sim::Session& s = *session;
  if (json) {
    printJson(infoJson(path, s));
    return kExitOk;
  }
  std::printf("%s: session format %u, %zu samples from %zu device%s\n", path.c_str(), unsigned(s.formatVersion),
              s.samples.size(), s.devices.size(), s.devices.size() == 1 ? "" : "s");
  for (size_t d = 0; d < s.devices.size(); ++d) {
    const drivers::DeviceInfo& info = s.devices[d];
    std::printf("  device %zu: \"%s\" serial \"%s\" firmware \"%s\": %d channels of %d bits%s\n", d, info.name.c_str(),
                info.serialNumber.c_str(), info.firmwareVersion.c_str(), info.channelCount, info.bitsPerChannel,
                info.hasDeviceTimestamp ? ", device timestamps" : "");
    for (const sim::SessionLayoutChange& change : s.layoutChanges)
      if (change.device == d)
        std::printf("    the same armature as device %u with a new channel layout, from sample %llu on\n",
                    unsigned(change.previous), static_cast<unsigned long long>(change.firstSample));
    printLink(sim::analyzeSessionLink(s, d));
  }
  for (const sim::SessionCounters& c : s.counters) printCounters(c);
  std::printf("  calibrations: %zu", s.calibrations.size());
  for (const auto& c : s.calibrations)
    std::printf(" (from sample %llu)", static_cast<unsigned long long>(c.firstSample));
  std::printf("\n  markers: %zu, notes: %zu, skeleton: %s\n", s.markers.size(), s.notes.size(),
              s.skeleton ? "yes (BVH hierarchy)" : "no");
  for (const auto& m : s.markers)
    std::printf("    marker at sample %llu: %s\n", static_cast<unsigned long long>(m.firstSample), m.label.c_str());
  const sim::SessionRecovery& r = s.recovery;
  if (r.closedCleanly && r.message.empty()) {
    std::printf("  the file is whole and was closed cleanly\n");
  } else {
    std::printf("  %s%s\n", r.closedCleanly ? "" : "not closed cleanly (recording interrupted); ",
                r.message.empty() ? "every record read" : r.message.c_str());
  }
  return kExitOk;
}

struct ConvertArgs {
  std::string input, output;
  int bits = 16;
  bool json = false;
};

// BVH -> session and session -> BVH, chosen by the file extensions.
int runConvert(const ConvertArgs& a) {
  const std::string in = extensionOf(a.input), out = extensionOf(a.output);
  if (int rc = checkOutputPath("convert", "OUT", a.output, {".session", ".bvh"}); rc != kExitOk) return rc;
  if (std::filesystem::exists(a.output)) {
    std::fprintf(stderr, "puppeteer convert: error: %s exists; convert never overwrites a file\n", a.output.c_str());
    return kExitIoError;
  }
  Progress progress("convert");
  if (in == ".bvh" && out == ".session") {
    Diagnostics warnings;
    progress.phase("reading " + a.input);
    auto clip = sim::readBvh(a.input, &warnings);
    progress.done();
    std::fputs(warnings.str().c_str(), stderr);
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    sim::BvhToSessionOptions options;
    options.bitsPerChannel = a.bits;
    progress.phase("converting " + std::to_string(clip->frames.size()) + " frames");
    auto session = sim::bvhToSession(*clip, std::filesystem::path(a.input).filename().string(), options);
    progress.phase("writing " + a.output);
    auto saved = session ? sim::saveSession(a.output, *session) : std::expected<void, Diagnostics>();
    progress.done();
    if (!session) {
      std::fputs(session.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    if (!saved) {
      std::fprintf(stderr, "puppeteer convert: error: %s\n", saved.error().firstError().c_str());
      return kExitIoError;
    }
    if (a.json) {
      printJson(Json{{"input", a.input}, {"output", a.output}, {"joints", clip->joints.size()},
                     {"frames", clip->frames.size()}, {"samples", session->samples.size()},
                     {"devices", session->devices.size()}, {"bits", a.bits}});
      return kExitOk;
    }
    std::printf("%s: %zu joints, %zu frames -> %s: %zu samples on %zu device%s (%d-bit counts)\n", a.input.c_str(),
                clip->joints.size(), clip->frames.size(), a.output.c_str(), session->samples.size(),
                session->devices.size(), session->devices.size() == 1 ? "" : "s", a.bits);
    return kExitOk;
  }
  if (in == ".session" && out == ".bvh") {
    progress.phase("reading " + a.input);
    auto session = sim::readSession(a.input);
    progress.done();
    if (!session) {
      std::fputs(session.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    if (!session->recovery.message.empty()) std::fprintf(stderr, "%s\n", session->recovery.message.c_str());
    progress.phase("converting " + std::to_string(session->samples.size()) + " samples");
    auto clip = sim::sessionToBvh(*session);
    progress.phase("writing " + a.output);
    auto saved = clip ? sim::saveBvh(a.output, *clip) : std::expected<void, Diagnostics>();
    progress.done();
    if (!clip) {
      std::fputs(clip.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    if (!saved) {
      std::fprintf(stderr, "puppeteer convert: error: %s\n", saved.error().firstError().c_str());
      return kExitIoError;
    }
    if (a.json) {
      printJson(Json{{"input", a.input}, {"output", a.output}, {"samples", session->samples.size()},
                     {"joints", clip->joints.size()}, {"frames", clip->frames.size()},
                     {"frameTime", clip->frameTime}});
      return kExitOk;
    }
    std::printf("%s: %zu samples -> %s: %zu joints, %zu frames at %.4g s\n", a.input.c_str(), session->samples.size(),
                a.output.c_str(), clip->joints.size(), clip->frames.size(), clip->frameTime);
    return kExitOk;
  }
  std::fprintf(stderr,
               "puppeteer convert: error: cannot convert %s to %s (supported: .bvh -> .session, .session -> .bvh)\n",
               in.empty() ? "(no extension)" : in.c_str(), out.empty() ? "(no extension)" : out.c_str());
  return kExitUsage;
}

}  // namespace

void addSessionCommands(CLI::App& app, Commands& commands) {
  auto infoPath = std::make_shared<std::string>();
  auto infoJsonFlag = std::make_shared<bool>(false);
  CLI::App* info = app.add_subcommand("info", "Describe a recorded session: devices, samples, rate, calibrations");
  info->add_option("session", *infoPath, "Session file (.session)")->required()->check(inputFile());
  info->add_flag("--json", *infoJsonFlag, "Print the description as JSON (for scripts)");
  commands.push_back({info, [infoPath, infoJsonFlag] { return runInfo(*infoPath, *infoJsonFlag); }});

  auto convert = std::make_shared<ConvertArgs>();
  CLI::App* conv = app.add_subcommand("convert", "Convert between BVH clips and sessions (by file extension)");
  conv->add_option("input", convert->input, "A .bvh clip or a .session")->required()->check(inputFile());
  conv->add_option("output", convert->output, "The .session or .bvh to create (never overwritten)")->required();
  conv->add_option("--bits", convert->bits, "Encoder resolution for BVH -> session (counts per turn = 2^bits)")
      ->check(CLI::Range(8, 20));
  conv->add_flag("--json", convert->json, "Print the report as JSON (for scripts)");
  commands.push_back({conv, [convert] { return runConvert(*convert); }});
}

}  // namespace imps::app
