// SPDX-License-Identifier: MIT
// `puppeteer devices`, `sim` and `record` (puppeteer/src/cli_devices.cpp) run as a user would: takes recorded from the
// simulated armature read back with the session reader and agree with the summaries; the simulator's pseudo-terminal
// is recorded through the real serial driver; every failure has docs/cli.md's exit code and message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibration/calibration.h"
#include "cli_run.h"
#include "scratch_dir.h"
#include "sim/session_file.h"

namespace imps::app {
namespace {

namespace fs = std::filesystem;
using test::contains;
using test::describe;
using test::kCliInvalidInput;
using test::kCliIo;
using test::kCliOk;
using test::kCliUsage;
using test::runPuppeteer;
using test::sourceFile;

const std::string kCalibration = sourceFile("examples/simple_biped.calibration.json");

sim::Session readBack(const fs::path& path) {
  auto session = sim::readSession(path);
  EXPECT_TRUE(session) << path << ": " << session.error().str();
  return session ? std::move(*session) : sim::Session{};
}

// ---- devices

// The listing is one JSON document with the three kinds of device, each serial port with a spec to use.
TEST(DevicesCommand, ListsSerialHidAndUsbDevices) {
  const test::ProgramRun text = runPuppeteer({"devices"});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  EXPECT_TRUE(contains(text.out, "Serial ports ("));
  EXPECT_TRUE(contains(text.out, "HID devices ("));
  const test::ProgramRun json = runPuppeteer({"devices", "--json"});
  ASSERT_EQ(json.exitCode, kCliOk) << describe(json);
  const nlohmann::json report = nlohmann::json::parse(json.out);
  ASSERT_TRUE(report["serialPorts"].is_array());
  for (const nlohmann::json& port : report["serialPorts"])
    EXPECT_EQ(port["spec"], "serial:" + port["path"].get<std::string>()) << port;
  EXPECT_TRUE(report["hid"]["devices"].is_array());
  EXPECT_TRUE(report["usb"]["devices"].is_array());
  test::expectFailures({
      {"unknown option", {"devices", "--jsn"}, kCliUsage, "did you mean '--json'?"},
      {"an argument", {"devices", "extra"}, kCliUsage, "extra"},
  });
}

// ---- sim

// The simulator serves a pseudo-terminal under --link; `record` reads it through the real serial driver; Ctrl-C stops
// the simulator, which removes its link.
TEST(SimCommand, ServesAnArmatureThatRecordReadsThroughTheSerialDriver) {
  const ScratchDir dir("imps_cli_devices");
  const std::string link = (dir / "arm").string(), take = (dir / "pty.session").string();
  const test::ProgramRun run = test::runProgram(
      "/bin/bash",
      {"-c",
       "\"$0\" sim --device 'sim:?rate=200&channels=8' --pty --link \"$1\" --seconds 60 > \"$1.out\" & sim=$!\n"
       "for i in $(seq 200); do [ -e \"$1\" ] && break; sleep 0.02; done\n"
       "\"$0\" record --device \"serial:$1?protocol=binary\" -o \"$2\" --seconds 0.3 --json; code=$?\n"
       "kill -INT $sim; wait $sim; exit $code",  // Ctrl-C stops the simulator
       test::puppeteerProgram().string(), link, take});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const std::string served = fileBytes(link + ".out");
  EXPECT_TRUE(contains(served, "Simulated armature"));
  EXPECT_TRUE(contains(served, "8 channels"));
  EXPECT_TRUE(contains(served, "Try:  puppeteer record --device 'serial:" + link + "?protocol=binary'"));
  EXPECT_FALSE(fs::exists(fs::symlink_status(link))) << "the link goes with the simulator";
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  const sim::Session session = readBack(take);
  ASSERT_EQ(session.devices.size(), 1u);
  EXPECT_EQ(session.devices[0].channelCount, 8);
  EXPECT_EQ(session.devices[0].name, "IMPS Simulated Monkey");
  EXPECT_EQ(session.samples.size(), summary["samples"].get<size_t>());
  EXPECT_GT(session.samples.size(), 10u);
}

TEST(SimCommand, Failures) {
  const ScratchDir dir("imps_cli_devices");
  std::ofstream(dir / "garbage.session") << "this is not a session file\n";
  test::expectFailures({
      {"no --pty", {"sim"}, kCliUsage, "--pty"},
      {"not a sim spec", {"sim", "--device", "serial:/dev/null", "--pty"}, kCliUsage, "must be a sim: spec"},
      {"a bad spec", {"sim", "--device", "nope", "--pty"}, kCliUsage, "spec:1:1: error"},
      {"missing session",
       {"sim", "--device", "sim:" + (dir / "none.session").string(), "--pty"},
       kCliInvalidInput,
       "none.session"},
      {"garbage session",
       {"sim", "--device", "sim:" + (dir / "garbage.session").string(), "--pty"},
       kCliInvalidInput,
       "garbage.session"},
      {"link in a missing directory",
       {"sim", "--pty", "--link", (dir / "nodir/arm").string()},
       kCliIo,
       "does not exist"},
      {"unknown option", {"sim", "--pty", "--secnds", "1"}, kCliUsage, "did you mean '--seconds'?"},
  });
}

// ---- record

// What record writes reads back as the summary says: the device, every sample, the link's counters; info agrees.
TEST(RecordCommand, TheTakeReadsBackAsTheSummarySays) {
  const ScratchDir dir("imps_cli_devices");
  const std::string take = (dir / "take.session").string();
  const test::ProgramRun run =
      runPuppeteer({"record", "--json", "--device", "sim:?rate=200&channels=32", "-o", take, "--seconds", "0.4"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  const sim::Session session = readBack(take);
  ASSERT_EQ(session.devices.size(), 1u);
  EXPECT_EQ(session.devices[0].channelCount, 32);
  EXPECT_EQ(session.samples.size(), summary["samples"].get<size_t>());
  EXPECT_GE(summary["secondsFromFirstSample"].get<double>(), 0.4);
  EXPECT_TRUE(session.calibrations.empty());
  ASSERT_EQ(session.counters.size(), 1u) << "the link's counters are stored in the take";
  EXPECT_TRUE(summary["counters"].contains("garbageBytes"));
  // The text summary names every counter of the link.
  const test::ProgramRun text =
      runPuppeteer({"record", "--device", "sim:?rate=200", "-o", (dir / "text.session").string(), "--seconds", "0.2"});
  ASSERT_EQ(text.exitCode, kCliOk) << describe(text);
  for (const char* counter : {"dropped", "reconnects", "CRC errors", "garbage bytes", "line parse errors"})
    EXPECT_TRUE(contains(text.out, counter));
  // Piped, the live counter line is not redrawn with \r: one line per change of state.
  EXPECT_EQ(text.err.find('\r'), std::string::npos) << text.err;
  EXPECT_TRUE(contains(text.err, "puppeteer record: streaming\n"));
  // info describes the take the same way.
  const test::ProgramRun info = runPuppeteer({"info", "--json", take});
  ASSERT_EQ(info.exitCode, kCliOk) << describe(info);
  EXPECT_EQ(nlohmann::json::parse(info.out)["samples"], summary["samples"]);
}

// record --calibration stores the calibration in force from the first sample.
TEST(RecordCommand, StoresTheCalibrationGiven) {
  const ScratchDir dir("imps_cli_devices");
  const std::string take = (dir / "cal.session").string();
  const test::ProgramRun run = runPuppeteer(
      {"record", "--device", "sim:?rate=200", "--calibration", kCalibration, "-o", take, "--seconds", "0.2"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const sim::Session session = readBack(take);
  ASSERT_EQ(session.calibrations.size(), 1u);
  EXPECT_EQ(session.calibrations[0].firstSample, 0u);
  // The calibration file's contents, as the calibration library writes it.
  auto given = calibration::Calibration::readFile(kCalibration, nullptr, nullptr);
  ASSERT_TRUE(given) << given.error().str();
  EXPECT_EQ(session.calibrations[0].json, given->toJson());
}

// A line-protocol device whose boot banner is a number keeps its 8-channel layout and every sample (issue 14).
TEST(RecordCommand, ALineDeviceWithANumericBannerKeepsItsLayout) {
  const ScratchDir dir("imps_cli_devices");
  const std::string take = (dir / "banner.session").string();
  const test::ProgramRun run = runPuppeteer(
      {"record", "--device", "sim:?protocol=lines&banner=115200&channels=8&rate=200", "-o", take, "--seconds", "0.3"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  EXPECT_EQ(run.out.find("skipped"), std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("different device"), std::string::npos) << run.out;
  EXPECT_TRUE(contains(run.out, "line parse errors: 0"));
  const sim::Session session = readBack(take);
  ASSERT_EQ(session.devices.size(), 1u);
  EXPECT_EQ(session.devices[0].channelCount, 8);
  EXPECT_TRUE(session.layoutChanges.empty());
  const test::ProgramRun info = runPuppeteer({"info", take});
  EXPECT_TRUE(contains(info.out, ": 8 channels of"));
  EXPECT_TRUE(contains(info.out, "device link counters (device 0):"));
}

// --seconds counts from the first sample: a device that boots for 1 s still gives a take of most of 0.5 s.
TEST(RecordCommand, SecondsCountFromTheFirstSample) {
  const ScratchDir dir("imps_cli_devices");
  const std::string take = (dir / "slow.session").string();
  const test::ProgramRun run =
      runPuppeteer({"record", "--json", "--device", "sim:?rate=200&boot_ms=1000", "-o", take, "--seconds", "0.5"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const test::ProgramRun info = runPuppeteer({"info", "--json", take});
  ASSERT_EQ(info.exitCode, kCliOk) << describe(info);
  // Counted from the start instead, the 1 s boot would leave no samples at all; a loaded machine may deliver the
  // half second's samples late, so anything clearly above zero shows the rule.
  EXPECT_GE(nlohmann::json::parse(info.out)["devices"][0]["seconds"].get<double>(), 0.2);
}

// An unplugged and replugged device: the take goes on, info locates the outage and calls the restart a reboot.
TEST(RecordCommand, AnUnplugIsAnOutageAndTheRestartAReboot) {
  const ScratchDir dir("imps_cli_devices");
  const std::string take = (dir / "unplug.session").string();
  const test::ProgramRun run =
      runPuppeteer({"record", "--device", "sim:?rate=200&unplug_ms=300&replug_ms=600", "-o", take, "--seconds", "1.5"});
  ASSERT_EQ(run.exitCode, kCliOk) << describe(run);
  const test::ProgramRun info = runPuppeteer({"info", take});
  ASSERT_EQ(info.exitCode, kCliOk) << describe(info);
  EXPECT_TRUE(contains(info.out, "1 outage"));
  EXPECT_TRUE(contains(info.out, "1 restart of the numbering (device reboots)"));
}

TEST(RecordCommand, Failures) {
  const ScratchDir dir("imps_cli_devices");
  std::ofstream(dir / "garbage.session") << "this is not a session file\n";
  std::ofstream(dir / "existing.session") << "precious";
  const std::string take = (dir / "t.session").string();
  test::expectFailures({
      {"no device", {"record", "-o", take}, kCliUsage, "--device"},
      {"no output", {"record", "--device", "sim:"}, kCliUsage, "--output"},
      {"a bad spec", {"record", "--device", "nope", "-o", take}, kCliUsage, "spec:1:1: error"},
      {"an OSC stream", {"record", "--device", "osc.udp://:9000", "-o", take}, kCliUsage, "OSC pose stream"},
      {"missing calibration",
       {"record", "--device", "sim:", "--calibration", (dir / "none.json").string(), "-o", take},
       kCliInvalidInput,
       "no such file"},
      {"missing sim session",
       {"record", "--device", "sim:" + (dir / "none.session").string(), "-o", take},
       kCliInvalidInput,
       "none.session"},
      {"garbage sim session",
       {"record", "--device", "sim:" + (dir / "garbage.session").string(), "-o", take},
       kCliInvalidInput,
       "garbage.session"},
      {"missing directory",
       {"record", "--device", "sim:", "-o", (dir / "nodir/t.session").string(), "--seconds", "5"},
       kCliIo,
       "does not exist"},
      {"never overwrites",
       {"record", "--device", "sim:?rate=200", "-o", (dir / "existing.session").string(), "--seconds", "0.2"},
       kCliIo,
       "never overwrite"},
      {"misspelt option",
       {"record", "--device", "sim:", "-o", take, "--second", "1"},
       kCliUsage,
       "did you mean '--seconds'?"},
  });
  EXPECT_FALSE(fs::exists(take));
  EXPECT_EQ(fileBytes(dir / "existing.session"), "precious");
}

// A file-size limit fails the take like a full disk: exit 3, said once.
TEST(RecordCommand, AFileSizeLimitFailsTheTakeOnce) {
  const ScratchDir dir("imps_cli_devices");
  const test::ProgramRun run = test::runProgram(
      "/bin/bash", {"-c", "ulimit -f 8; exec \"$0\" record --device 'sim:?rate=1000&channels=32' -o \"$1\" --seconds 2",
                    test::puppeteerProgram().string(), (dir / "take.session").string()});
  EXPECT_EQ(run.exitCode, kCliIo) << describe(run);
  EXPECT_EQ(test::occurrences(run.err, "File too large"), 1u) << run.err;
}

}  // namespace
}  // namespace imps::app
