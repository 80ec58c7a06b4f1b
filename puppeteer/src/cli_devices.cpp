// SPDX-License-Identifier: MIT
// `puppeteer devices`, `puppeteer sim` and `puppeteer record`: what is attached, a simulated armature on a
// pseudo-terminal, and recording a live device to a session file. docs/devices.md.
#include "cli.h"
#include "device_opener.h"
#include "device_ranking.h"
#include "json_output.h"
#include "progress.h"
#include "interrupts.h"
#include "session_recorder.h"

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "calibration/calibration.h"
#include "drivers/device_session.h"
#include "drivers/device_spec.h"
#include "drivers/hid_transport.h"
#include "drivers/serial_transport.h"
#include "drivers/usb_transport.h"
#include "sim/pseudo_terminal.h"
#include "sim/session_file.h"
#include "sim/simulated_armature.h"

namespace imps::app {
namespace {

bool timeUp(std::chrono::steady_clock::time_point start, double seconds) {
  return seconds > 0 &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= seconds;
}

// ---- puppeteer devices

// "VID:PID[?serial=…]" for a spec.
std::string hexId(uint16_t vendorId, uint16_t productId, const std::string& serial) {
  char ids[16];
  std::snprintf(ids, sizeof ids, "%04x:%04x", vendorId, productId);
  return ids + (serial.empty() ? "" : "?serial=" + serial);
}

// HID devices (hidapi): VID:PID, serial, product, usage page, hidraw node, and whether the report descriptor
// looks like an IMPS armature (docs/protocol.md, "HID armatures").
void printHidDevices(Json* json) {
  auto hid = drivers::listHidDevices();
  if (json) {
    Json list = Json::array();
    if (hid)
      for (const drivers::HidDeviceEntry& d : *hid)
        list.push_back({{"path", d.path}, {"vendorId", d.vendorId}, {"productId", d.productId},
                        {"usagePage", d.usagePage}, {"usage", d.usage}, {"serialNumber", d.serialNumber},
                        {"product", d.product}, {"armature", d.looksLikeArmature()},
                        {"channels", d.layout ? Json(d.layout->channels.size()) : Json(nullptr)},
                        {"problem", d.layout ? "" : d.layoutError},
                        {"spec", "hid:" + hexId(d.vendorId, d.productId, d.serialNumber)}});
    (*json)["hid"] = {{"error", hid ? "" : drivers::errorText(hid.error())}, {"devices", std::move(list)}};
    return;
  }
  if (!hid) {
    std::printf("HID devices: cannot list: %s\n", drivers::errorText(hid.error()).c_str());
    return;
  }
  std::printf("HID devices (%zu):\n", hid->size());
  if (hid->empty()) std::printf("  none\n");
  for (const drivers::HidDeviceEntry& d : *hid) {
    std::printf("  %-16s usb %04x:%04x  usage page %04x:%04x", d.path.c_str(), d.vendorId, d.productId, d.usagePage,
                d.usage);
    if (!d.serialNumber.empty()) std::printf("  serial %s", d.serialNumber.c_str());
    if (!d.product.empty()) std::printf("  \"%s\"", d.product.c_str());
    if (d.layout)
      std::printf("\n    %s: %zu channels of up to %d bits%s", d.looksLikeArmature() ? "IMPS armature" : "other HID",
                  d.layout->channels.size(), d.layout->bitsPerChannel(),
                  d.layout->infoReportId ? ", INFO feature report" : "");
    else
      std::printf("\n    no channels: %s", d.layoutError.c_str());
    std::printf("\n    spec: hid:%04x:%04x%s%s\n", d.vendorId, d.productId, d.serialNumber.empty() ? "" : "?serial=",
                d.serialNumber.c_str());
  }
}

// Vendor-USB armatures (libusb) with the known VID:PIDs: bus/address, strings, and what their INFO request says.
void printUsbArmatures(Json* json) {
  auto usb = drivers::listUsbDevices();
  if (json) {
    Json list = Json::array();
    if (usb)
      for (const drivers::UsbDeviceInfo& d : *usb)
        list.push_back({{"bus", d.bus}, {"address", d.address}, {"vendorId", d.vendorId},
                        {"productId", d.productId}, {"serialNumber", d.serialNumber}, {"product", d.product},
                        {"name", d.info ? Json(d.info->name) : Json(nullptr)},
                        {"channels", d.info ? Json(d.info->channelCount) : Json(nullptr)},
                        {"bits", d.info ? Json(d.info->bitsPerChannel) : Json(nullptr)},
                        {"firmware", d.info ? Json(d.info->firmwareVersion) : Json(nullptr)},
                        {"problem", d.problem},
                        {"spec", "usb:" + hexId(d.vendorId, d.productId, d.serialNumber)}});
    (*json)["usb"] = {{"error", usb ? "" : drivers::errorText(usb.error())}, {"devices", std::move(list)}};
    return;
  }
  if (!usb) {
    std::printf("USB armatures: cannot list: %s\n", drivers::errorText(usb.error()).c_str());
    return;
  }
  std::printf("USB armatures (%zu):\n", usb->size());
  if (usb->empty()) std::printf("  none\n");
  for (const drivers::UsbDeviceInfo& d : *usb) {
    std::printf("  bus %03d address %03d  usb %04x:%04x", d.bus, d.address, d.vendorId, d.productId);
    if (!d.serialNumber.empty()) std::printf("  serial %s", d.serialNumber.c_str());
    if (!d.product.empty()) std::printf("  \"%s\"", d.product.c_str());
    if (d.info)
      std::printf("\n    \"%s\": %d channels of %d bits, firmware %s", d.info->name.c_str(), d.info->channelCount,
                  d.info->bitsPerChannel, d.info->firmwareVersion.c_str());
    if (!d.problem.empty()) std::printf("\n    %s", d.problem.c_str());
    std::printf("\n    spec: usb:%04x:%04x%s%s\n", d.vendorId, d.productId, d.serialNumber.empty() ? "" : "?serial=",
                d.serialNumber.c_str());
  }
}

Json serialPortsJson(const std::vector<drivers::SerialPortInfo>& ports) {
  Json list = Json::array();
  for (const drivers::SerialPortInfo& p : ports)
    list.push_back({{"path", p.path},
                    {"usb", p.isUsb},
                    {"vendorId", p.vendorId},
                    {"productId", p.productId},
                    {"serialNumber", p.serialNumber},
                    {"driver", p.driver},
                    {"description", p.description},
                    {"ftdiLatencyMs", p.latencyTimerMs ? Json(*p.latencyTimerMs) : Json(nullptr)},
                    {"likelihood", describe(portLikelihood(p))},
                    {"spec", "serial:" + p.path}});
  return list;
}

int runDevices(bool json) {
  auto ports = drivers::listSerialPorts();
  if (!ports) {
    std::fprintf(stderr, "puppeteer devices: error: %s\n", drivers::errorText(ports.error()).c_str());
    return kExitIoError;
  }
  rankPorts(*ports);  // likely armatures first, motherboard UARTs last
  if (json) {
    Json report{{"serialPorts", serialPortsJson(*ports)}};
    printHidDevices(&report);
    printUsbArmatures(&report);
    printJson(report);
    return kExitOk;
  }
  std::printf("Serial ports (%zu, likely armatures first):\n", ports->size());
  if (ports->empty()) std::printf("  none\n");
  for (const drivers::SerialPortInfo& p : *ports) {
    std::printf("  %-16s", p.path.c_str());
    if (p.isUsb) std::printf(" usb %04x:%04x", p.vendorId, p.productId);
    else std::printf(" %-13s", "native");
    if (!p.serialNumber.empty()) std::printf("  serial %s", p.serialNumber.c_str());
    if (!p.driver.empty()) std::printf("  driver %s", p.driver.c_str());
    if (!p.description.empty()) std::printf("  \"%s\"", p.description.c_str());
    if (p.latencyTimerMs) {
      std::printf("  FTDI latency %d ms%s", *p.latencyTimerMs,
                  *p.latencyTimerMs > 1 ? (p.latencyTimerWritable ? " (will be set to 1 ms when opened)"
                                                                  : " (slow: see docs/devices.md, udev rule)")
                                        : "");
    }
    std::printf("\n    %s; spec: serial:%s\n", describe(portLikelihood(p)), p.path.c_str());
  }
  printHidDevices(nullptr);
  printUsbArmatures(nullptr);
  return kExitOk;
}

// ---- puppeteer sim

struct SimArgs {
  std::string device = "sim:";
  bool pty = false;
  std::string link;
  double seconds = 0;
};

int runSim(const SimArgs& a) {
  auto spec = drivers::parseDeviceSpec(a.device);
  if (!spec) {
    std::fputs(spec.error().str().c_str(), stderr);
    return kExitUsage;
  }
  if (spec->kind != drivers::DeviceKind::Sim) {
    std::fprintf(stderr, "puppeteer sim: error: --device must be a sim: spec (docs/devices.md), got '%s'\n",
                 a.device.c_str());
    return kExitUsage;
  }
  auto options = sim::armatureOptionsFromSpec(*spec);
  if (!options) {
    std::fputs(options.error().str().c_str(), stderr);
    return kExitInvalidInput;
  }
  if (!a.pty) {
    std::fprintf(stderr, "puppeteer sim: error: choose where to serve the armature: --pty\n");
    return kExitUsage;
  }
  if (!a.link.empty())
    if (int rc = checkOutputPath("sim", "--link", a.link); rc != kExitOk) return rc;
  // ---- A pseudo-terminal pair: the simulator drives the master, the drivers open the slave path.
  auto pty = sim::PseudoTerminal::open();
  if (!pty) {
    std::fprintf(stderr, "puppeteer sim: error: %s\n", drivers::errorText(pty.error()).c_str());
    return kExitIoError;
  }
  const std::string slave = pty->slavePath();
  std::string path = slave;
  if (!a.link.empty()) {
    std::error_code ec;
    if (std::filesystem::is_symlink(a.link, ec)) std::filesystem::remove(a.link, ec);
    std::filesystem::create_symlink(slave, a.link, ec);
    if (ec) {
      std::fprintf(stderr, "puppeteer sim: error: cannot create link %s: %s\n", a.link.c_str(), ec.message().c_str());
      return kExitIoError;
    }
    path = a.link;
  }
  const char* protocol = drivers::toString(options->protocol);
  std::printf("Simulated armature \"%s\" (%d channels, %s protocol) on %s\n", options->info.name.c_str(),
              options->info.channelCount, protocol, path.c_str());
  std::printf("Try:  puppeteer record --device 'serial:%s?protocol=%s' -o take.session --seconds 5\n", path.c_str(),
              protocol);
  std::printf("Ctrl-C stops the simulator.\n");
  std::fflush(stdout);

  catchInterrupts();
  imps::SteadyClock clock;
  sim::ArmatureFdServer server(sim::SimulatedArmature(*options), pty->master(), clock);
  server.start();
  const auto start = std::chrono::steady_clock::now();
  while (!interruptRequested() && !timeUp(start, a.seconds)) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  server.stop();
  if (!a.link.empty()) std::filesystem::remove(a.link);
  std::printf("Sent %llu samples.\n", static_cast<unsigned long long>(server.samplesSent()));
  return kExitOk;
}

// ---- puppeteer record

struct RecordArgs {
  std::string device;
  std::string output;
  std::string calibration;
  double seconds = 0;
  bool json = false;
};

// How long `record --seconds N` waits for the first sample beyond N before giving up: a device's open, boot and
// hello take up to a few seconds (docs/cli.md).
constexpr double kFirstSampleGraceSeconds = 10.0;

// The live counter line `record` redraws on stderr.
void printRecordProgress(const std::string& state, const drivers::DeviceSessionStats& st) {
  std::fprintf(stderr, "\r%-18s samples %llu  dropped %llu  crc %llu  timeouts %llu  reconnects %llu   ",
               state.c_str(), static_cast<unsigned long long>(st.samples),
               static_cast<unsigned long long>(st.samplesDropped), static_cast<unsigned long long>(st.crcErrors),
               static_cast<unsigned long long>(st.timeouts), static_cast<unsigned long long>(st.reconnects));
}

int runRecord(const RecordArgs& a) {
  auto spec = drivers::parseDeviceSpec(a.device);
  if (!spec) {
    std::fputs(spec.error().str().c_str(), stderr);
    return kExitUsage;
  }
  if (int rc = checkOutputPath("record", "-o", a.output); rc != kExitOk) return rc;
  if (std::filesystem::exists(a.output)) {
    std::fprintf(stderr, "puppeteer record: error: %s exists; recordings never overwrite a file\n", a.output.c_str());
    return kExitIoError;
  }
  // The calibration in force is stored with the take (replay uses it; info lists it).
  std::optional<calibration::Calibration> cal;
  if (!a.calibration.empty()) {
    auto read = calibration::Calibration::readFile(a.calibration);
    if (!read) {
      std::fputs(read.error().str().c_str(), stderr);
      return kExitInvalidInput;
    }
    cal = std::move(*read);
  }
  imps::SteadyClock clock;
  auto opener = openerForSpec(*spec, clock, "record");
  if (!opener) {
    std::fputs(opener.error().diagnostics.str().c_str(), stderr);
    return exitCodeFor(opener.error().kind);
  }

  catchInterrupts();
  drivers::PoseMailboxOptions mo;
  mo.queueCapacity = 1 << 16;  // 65 s at 1 kHz: the recorder drains every 20 ms
  drivers::PoseMailbox mailbox(mo);
  drivers::DeviceSession session(*opener, mailbox, drivers::sessionOptionsFor(*spec));
  session.start();

  std::optional<app::SessionRecorder> recorder;
  std::vector<drivers::Sample> batch;
  std::string lastState;
  const bool onTerminal = Progress::stderrIsTerminal();
  const auto start = std::chrono::steady_clock::now();
  // --seconds counts from the first sample, not from opening the device and waiting for its hello.
  std::optional<std::chrono::steady_clock::time_point> firstSample;
  auto lastReport = start, lastCounters = start;
  int exitCode = kExitOk;
  auto drainInto = [&]() -> bool {
    batch.clear();
    mailbox.drain(batch);
    if (batch.empty()) return true;
    const std::optional<drivers::DeviceInfo> info = session.deviceInfo();
    if (!info) return true;  // cannot happen: samples come after the handshake
    if (!recorder) {
      // The description of the first sample's layout (the device may have re-locked since).
      auto created = app::SessionRecorder::create(a.output, withChannelCount(*info, batch.front().channelCount),
                                                  cal ? &*cal : nullptr);
      if (!created) {
        std::fprintf(stderr, "%s\n", drivers::errorText(created.error()).c_str());
        exitCode = kExitIoError;
        return false;
      }
      recorder.emplace(std::move(*created));
      firstSample = std::chrono::steady_clock::now();
      for (const std::string& w : session.warnings()) std::fprintf(stderr, "%s\n", w.c_str());
    }
    if (auto r = recorder->append(batch, &*info); !r) {
      std::fprintf(stderr, "%s\n", drivers::errorText(r.error()).c_str());
      exitCode = kExitIoError;
      return false;
    }
    return true;
  };
  auto done = [&] {
    if (firstSample) return timeUp(*firstSample, a.seconds);
    return a.seconds > 0 && timeUp(start, a.seconds + kFirstSampleGraceSeconds);
  };
  while (!interruptRequested() && !done()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!drainInto()) break;
    const std::string state = drivers::toString(session.state());
    const auto now = std::chrono::steady_clock::now();
    if (recorder && now - lastCounters >= std::chrono::seconds(1)) {
      // A crash keeps the counts of the last second.
      if (auto r = recorder->appendCounters(session.stats()); !r) {
        std::fprintf(stderr, "%s\n", drivers::errorText(r.error()).c_str());
        exitCode = kExitIoError;
        break;
      }
      lastCounters = now;
    }
    if (state != lastState || now - lastReport >= std::chrono::seconds(1)) {
      // On a terminal one redrawn line of counters; into a pipe or a log one line per change of state (the summary
      // at the end has every counter).
      if (onTerminal) printRecordProgress(state, session.stats());
      else if (state != lastState) std::fprintf(stderr, "puppeteer record: %s\n", state.c_str());
      if (state != lastState && !session.lastError().empty() && state != "streaming")
        std::fprintf(stderr, "\n  (%s)\n", session.lastError().c_str());
      lastState = state;
      lastReport = now;
    }
  }
  session.stop();
  if (exitCode == kExitOk) drainInto();
  if (onTerminal) std::fprintf(stderr, "\n");
  if (!recorder) {
    if (exitCode != kExitOk) return exitCode;  // the file could not be created: that cause is already printed
    std::fprintf(stderr, "puppeteer record: error: no samples from %s: %s\n", a.device.c_str(),
                 session.lastError().empty() ? "the device never started streaming" : session.lastError().c_str());
    return exitCode == kExitOk ? kExitIoError : exitCode;
  }
  const drivers::DeviceSessionStats st = session.stats();
  if (auto r = recorder->appendCounters(st); !r) {
    std::fprintf(stderr, "%s\n", drivers::errorText(r.error()).c_str());
    return kExitIoError;
  }
  if (auto r = recorder->close(); !r) {
    // else the write error was printed
    if (exitCode == kExitOk) std::fprintf(stderr, "%s\n", drivers::errorText(r.error()).c_str());
    return kExitIoError;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - *firstSample).count();
  if (a.json) {
    Json json{{"output", a.output}, {"device", a.device}, {"samples", recorder->samples()},
              {"secondsFromFirstSample", seconds}, {"layoutChanges", recorder->layoutChanges()},
              {"queueOverflows", mailbox.stats().queueOverflows}, {"calibration", a.calibration}};
    for (const drivers::NamedCounter& c : drivers::namedCounters(st)) json["counters"][c.name] = c.value;
    printJson(json);
    return exitCode;
  }
  std::printf("Recorded %llu samples (%.1f s from the first sample) to %s%s\n",
              static_cast<unsigned long long>(recorder->samples()), seconds, a.output.c_str(),
              recorder->layoutChanges()
                  ? (", " + std::to_string(recorder->layoutChanges()) + " channel-layout change(s) recorded").c_str()
                  : "");
  std::printf("%s, queue overflows: %llu\n", countersSummary(st).c_str(),
              static_cast<unsigned long long>(mailbox.stats().queueOverflows));
  return exitCode;
}

}  // namespace

void addDeviceCommands(CLI::App& app, Commands& commands) {
  CLI::App* devices = app.add_subcommand(
      "devices", "List attached armatures (serial ports with USB VID:PID, HID devices, USB armatures)");
  auto devicesJson = std::make_shared<bool>(false);
  devices->add_flag("--json", *devicesJson, "Print the listing as JSON (for scripts)");
  commands.push_back({devices, [devicesJson] { return runDevices(*devicesJson); }});

  auto simArgs = std::make_shared<SimArgs>();
  CLI::App* simCmd = app.add_subcommand("sim", "Run a simulated armature on a path the drivers can open");
  simCmd->add_option("--device", simArgs->device, "sim: spec: generated motion or a session (docs/devices.md)")
      ->capture_default_str();
  simCmd->add_flag("--pty", simArgs->pty, "serve on a new pseudo-terminal (its path is printed)");
  simCmd->add_option("--link", simArgs->link, "also create this symlink to the pseudo-terminal");
  simCmd->add_option("--seconds", simArgs->seconds, "stop after this long (default: until Ctrl-C)");
  commands.push_back({simCmd, [simArgs] { return runSim(*simArgs); }});

  auto recordArgs = std::make_shared<RecordArgs>();
  CLI::App* record = app.add_subcommand("record", "Record a device's raw samples to a session file");
  record->add_option("--device", recordArgs->device, "device spec, e.g. serial:/dev/ttyACM0 (docs/devices.md)")
      ->required();
  record->add_option("-o,--output", recordArgs->output, "session file to create (never overwritten)")->required();
  record->add_option("--seconds", recordArgs->seconds,
                     "stop this long after the first sample (default: until Ctrl-C); waits at most 10 s more for it");
  record->add_flag("--json", recordArgs->json, "Print the summary as JSON (for scripts)");
  record->add_option("--calibration", recordArgs->calibration,
                     "calibration in force (puppeteer calibrate), stored with the take for replay")
      ->check(inputFile());
  commands.push_back({record, [recordArgs] { return runRecord(*recordArgs); }});
}

}  // namespace imps::app
