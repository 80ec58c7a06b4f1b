// SPDX-License-Identifier: MIT
// Tests for puppeteer/device_opener: a spec gives an opener, or a result the command prints and maps to an exit code.
#include "device_opener.h"

#include <gtest/gtest.h>

#include <string>

#include "cli.h"
#include "imps/clock.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

drivers::DeviceSpec specOf(const std::string& text) {
  auto spec = drivers::parseDeviceSpec(text);
  EXPECT_TRUE(spec) << (spec ? "" : spec.error().str());
  return spec ? *spec : drivers::DeviceSpec{};
}

TEST(DeviceOpener, SimSpecGivesAnOpenerThatOpens) {
  ManualClock clock;
  auto opener = openerForSpec(specOf("sim:?channels=4"), clock, "record");
  ASSERT_TRUE(opener) << opener.error().diagnostics.str();
  auto transport = (*opener)();
  ASSERT_TRUE(transport) << transport.error().str();
  EXPECT_NE((*transport)->description().find("4 channels"), std::string::npos) << (*transport)->description();
}

TEST(DeviceOpener, BadSimKeyIsBadInputWithTheSpecsDiagnostic) {
  ManualClock clock;
  auto opener = openerForSpec(specOf("sim:?chanels=4"), clock, "record");
  ASSERT_FALSE(opener);
  EXPECT_EQ(opener.error().kind, OpenerError::Kind::BadSpec);
  EXPECT_EQ(exitCodeFor(opener.error().kind), kExitInvalidInput);
  ASSERT_EQ(opener.error().diagnostics.errorCount(), 1);
  EXPECT_EQ(opener.error().diagnostics.all().front().loc.file, "spec");
  EXPECT_EQ(opener.error().diagnostics.str().rfind("spec: error: sim key 'chanels': unknown", 0), 0u)
      << opener.error().diagnostics.str();
}

// A sim: spec whose session file is missing or is not a session is bad input, naming the file.
TEST(DeviceOpener, AnUnreadableSimSessionIsBadInputNamingTheFile) {
  const ScratchDir dir("imps_device_opener");
  writeBytes(dir / "garbage.session", "not a session\n");
  ManualClock clock;
  for (const std::string name : {"none.session", "garbage.session"}) {
    auto opener = openerForSpec(specOf("sim:" + (dir / name).string()), clock, "record");
    ASSERT_FALSE(opener) << name;
    EXPECT_EQ(opener.error().kind, OpenerError::Kind::BadSpec) << name;
    EXPECT_EQ(exitCodeFor(opener.error().kind), kExitInvalidInput) << name;
    EXPECT_NE(opener.error().diagnostics.str().find(name), std::string::npos) << opener.error().diagnostics.str();
  }
}

TEST(DeviceOpener, OscStreamIsAUsageErrorNamingTheCommand) {
  ManualClock clock;
  auto opener = openerForSpec(specOf("osc.udp://:9000"), clock, "calibrate");
  ASSERT_FALSE(opener);
  EXPECT_EQ(opener.error().kind, OpenerError::Kind::NotBytes);
  EXPECT_EQ(exitCodeFor(opener.error().kind), kExitUsage);
  EXPECT_EQ(opener.error().diagnostics.str(),
            "puppeteer calibrate: error: osc.udp://:9000 is an OSC pose stream (docs/osc.md): drive a character "
            "with it in `puppeteer live SCENE --device osc.udp://:9000`\n");
}

TEST(DeviceOpener, AbsentSerialPortIsReportedWhenOpenedNotWhenTheOpenerIsMade) {
  ManualClock clock;
  auto opener = openerForSpec(specOf("serial:/dev/imps-no-such-port"), clock, "record");
  ASSERT_TRUE(opener) << opener.error().diagnostics.str();  // the device may be plugged in later
  auto transport = (*opener)();
  ASSERT_FALSE(transport);
  EXPECT_EQ(transport.error().path, "/dev/imps-no-such-port");
  EXPECT_EQ(drivers::errorText(transport.error()).rfind("/dev/imps-no-such-port: error: ", 0), 0u)
      << drivers::errorText(transport.error());
}

}  // namespace
}  // namespace imps::app
