// `puppeteer info` and `puppeteer convert`: what a recorded session holds, and sessions <-> BVH clips.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cli.h"
#include "drivers/device_session.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"
#include "sim/session_file.h"
#include "sim/session_link.h"

namespace imps::app {
namespace {

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

void printLink(const sim::SessionLink& a) {
  const double seconds = double(a.spanNs) * 1e-9;
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

int runInfo(const std::string& path) {
  auto session = sim::readSession(path);
  if (!session) {
    std::fprintf(stderr, "%s\n", session.error().c_str());
    return kExitInvalidInput;
  }
  const sim::Session& s = *session;
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
  for (const auto& c : s.calibrations) std::printf(" (from sample %llu)", static_cast<unsigned long long>(c.firstSample));
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
};

// BVH -> session and session -> BVH, chosen by the file extensions.
int runConvert(const ConvertArgs& a) {
  const std::string in = extensionOf(a.input), out = extensionOf(a.output);
  if (std::filesystem::exists(a.output)) {
    std::fprintf(stderr, "puppeteer convert: error: %s exists; convert never overwrites a file\n", a.output.c_str());
    return kExitIoError;
  }
  if (in == ".bvh" && out == ".session") {
    std::vector<std::string> warnings;
    auto clip = sim::readBvh(a.input, &warnings);
    for (const std::string& w : warnings) std::fprintf(stderr, "%s\n", w.c_str());
    if (!clip) {
      std::fprintf(stderr, "%s\n", clip.error().c_str());
      return kExitInvalidInput;
    }
    sim::BvhToSessionOptions options;
    options.bitsPerChannel = a.bits;
    auto session = sim::bvhToSession(*clip, std::filesystem::path(a.input).filename().string(), options);
    if (!session) {
      std::fprintf(stderr, "%s\n", session.error().c_str());
      return kExitInvalidInput;
    }
    if (auto saved = sim::saveSession(a.output, *session); !saved) {
      std::fprintf(stderr, "puppeteer convert: error: %s\n", saved.error().c_str());
      return kExitIoError;
    }
    std::printf("%s: %zu joints, %zu frames -> %s: %zu samples on %zu device%s (%d-bit counts)\n", a.input.c_str(),
                clip->joints.size(), clip->frames.size(), a.output.c_str(), session->samples.size(),
                session->devices.size(), session->devices.size() == 1 ? "" : "s", a.bits);
    return kExitOk;
  }
  if (in == ".session" && out == ".bvh") {
    auto session = sim::readSession(a.input);
    if (!session) {
      std::fprintf(stderr, "%s\n", session.error().c_str());
      return kExitInvalidInput;
    }
    if (!session->recovery.message.empty()) std::fprintf(stderr, "%s\n", session->recovery.message.c_str());
    auto clip = sim::sessionToBvh(*session);
    if (!clip) {
      std::fprintf(stderr, "%s\n", clip.error().c_str());
      return kExitInvalidInput;
    }
    if (auto saved = sim::saveBvh(a.output, *clip); !saved) {
      std::fprintf(stderr, "puppeteer convert: error: %s\n", saved.error().c_str());
      return kExitIoError;
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
  CLI::App* info = app.add_subcommand("info", "Describe a recorded session: devices, samples, rate, calibrations");
  info->add_option("session", *infoPath, "Session file (.session)")->required()->check(CLI::ExistingFile);
  commands.push_back({info, [infoPath] { return runInfo(*infoPath); }});

  auto convert = std::make_shared<ConvertArgs>();
  CLI::App* conv = app.add_subcommand("convert", "Convert between BVH clips and sessions (by file extension)");
  conv->add_option("input", convert->input, "A .bvh clip or a .session")->required()->check(CLI::ExistingFile);
  conv->add_option("output", convert->output, "The .session or .bvh to create (never overwritten)")->required();
  conv->add_option("--bits", convert->bits, "Encoder resolution for BVH -> session (counts per turn = 2^bits)")
      ->check(CLI::Range(8, 20));
  commands.push_back({conv, [convert] { return runConvert(*convert); }});
}

}  // namespace imps::app
