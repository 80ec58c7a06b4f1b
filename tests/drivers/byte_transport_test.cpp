// SPDX-License-Identifier: MIT
// Tests for drivers/byte_transport: the one text a device failure is shown as.
#include "drivers/byte_transport.h"

#include <gtest/gtest.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace imps::drivers {
namespace {

TEST(ByteTransport, ErrorTextNamesTheDeviceThenTheSeverity) {
  EXPECT_EQ(errorText(IoError{"/dev/ttyACM0", "the device hung up (unplugged?)", EIO}),
            "/dev/ttyACM0: error: the device hung up (unplugged?)");
  EXPECT_EQ(errorText(IoError::fromErrno("usb 1209:0001", "cannot open", EACCES)),
            "usb 1209:0001: error: cannot open: " + std::string(std::strerror(EACCES)));
}

TEST(ByteTransport, ErrorTextWithoutAPathIsTheMessageAlone) {
  // Callers put such a message after their own "…: error: " (e.g. `puppeteer sim` for a pseudo-terminal).
  EXPECT_EQ(errorText(IoError{"", "cannot create a pseudo-terminal: No space left on device", ENOSPC}),
            "cannot create a pseudo-terminal: No space left on device");
}

}  // namespace
}  // namespace imps::drivers
