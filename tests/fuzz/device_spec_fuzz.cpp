// SPDX-License-Identifier: MIT
// libFuzzer target for the device spec parser (drivers/device_spec): any text must parse or give an error, never
// crash, and whatever parses must survive a format → parse round trip unchanged.
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "drivers/device_spec.h"

using namespace imps::drivers;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto spec = parseDeviceSpec(text);
  if (!spec) {
    if (spec.error().str().rfind("spec:1:", 0) != 0) {
      std::fprintf(stderr, "error without a location: %s\n", spec.error().str().c_str());
      std::abort();
    }
    return 0;
  }
  auto again = parseDeviceSpec(formatDeviceSpec(*spec));
  if (!again || !(*again == *spec)) {
    std::fprintf(stderr, "round trip failed for: %s\n", formatDeviceSpec(*spec).c_str());
    std::abort();
  }
  return 0;
}
