// SPDX-License-Identifier: MIT
// Device spec → transport opener (puppeteer/src/device_opener.cpp): a sim: spec opens the in-process armature,
// which says hello; a serial port that is not there is an error when opened (the session retries), not before;
// a sim: session that cannot be read is an input error and an OSC stream a usage error, each said once.
#include "device_opener.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli.h"
#include "cli_run.h"
#include "drivers/device_spec.h"
#include "imps/clock.h"
#include "scratch_dir.h"

namespace imps::app {
namespace {

drivers::DeviceSpec spec(const std::string& text) {
  auto parsed = drivers::parseDeviceSpec(text);
  EXPECT_TRUE(parsed) << text << ": " << (parsed ? "" : parsed.error());
  return parsed ? *parsed : drivers::DeviceSpec{};
}

TEST(DeviceOpener, ASimSpecOpensTheSimulatedArmatureWhichSendsBytes) {
  SteadyClock clock;
  auto opener = openerForSpec(spec("sim:?rate=200&channels=8"), clock, "test");
  ASSERT_TRUE(opener);
  auto transport = (*opener)();
  ASSERT_TRUE(transport) << transport.error();
  ASSERT_NE(*transport, nullptr);
  EXPECT_FALSE((*transport)->description().empty());
  std::vector<uint8_t> buffer(4096);
  size_t received = 0;
  for (int i = 0; i < 50 && received == 0; ++i) {
    auto n = (*transport)->read(buffer, 20);
    ASSERT_TRUE(n) << n.error();
    received += *n;
  }
  EXPECT_GT(received, 0u) << "the armature says hello";
}

TEST(DeviceOpener, AMissingSerialPortFailsWhenOpened) {
  const ScratchDir dir("imps_device_opener");
  SteadyClock clock;
  auto opener = openerForSpec(spec("serial:" + (dir / "nodevice").string()), clock, "test");
  ASSERT_TRUE(opener) << "a serial port is looked for when the session opens it";
  auto transport = (*opener)();
  ASSERT_FALSE(transport);
  EXPECT_NE(transport.error().find("nodevice"), std::string::npos) << transport.error();
}

TEST(DeviceOpener, UnreadableSessionsAndOscStreamsAreRefusedWithTheirExitCodes) {
  const ScratchDir dir("imps_device_opener");
  writeBytes(dir / "garbage.session", "not a session\n");
  SteadyClock clock;
  struct Case {
    std::string spec;
    int exitCode;
    std::string says;
  } cases[] = {
      {"sim:" + (dir / "none.session").string(), kExitInvalidInput, "none.session"},
      {"sim:" + (dir / "garbage.session").string(), kExitInvalidInput, "garbage.session"},
      {"osc.udp://:9000", kExitUsage, "puppeteer record: error: osc.udp://:9000 is an OSC pose stream"},
  };
  for (const Case& c : cases) {
    testing::internal::CaptureStderr();
    auto opener = openerForSpec(spec(c.spec), clock, "record");
    const std::string err = testing::internal::GetCapturedStderr();
    ASSERT_FALSE(opener) << c.spec;
    EXPECT_EQ(opener.error(), c.exitCode) << c.spec;
    EXPECT_TRUE(test::contains(err, c.says)) << c.spec;
    EXPECT_EQ(test::occurrences(err, "error:"), 1u) << c.spec << ":\n" << err;
  }
}

}  // namespace
}  // namespace imps::app
