// SPDX-License-Identifier: MIT
// libFuzzer target for the rig-map / calibration JSON reader (calibration/rig_map): any bytes give a map or
// diagnostics (never a crash, an exception or quadratic time), and a map that was read writes back (toJson) to valid
// UTF-8 that reads as the same map, with toJson a fixed point. Checked with and without a device to resolve against.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "calibration/rig_map.h"
#include "fuzz_check.h"
#include "imps/utf8.h"

namespace {

// A 32-channel armature whose channel names a map may use.
const imps::drivers::DeviceInfo& device() {
  static const imps::drivers::DeviceInfo d = [] {
    imps::drivers::DeviceInfo info;
    info.name = "fuzz";
    info.channelCount = 32;
    info.bitsPerChannel = 12;
    for (int i = 0; i < 32; ++i) info.channelNames.push_back("ch" + std::to_string(i));
    return info;
  }();
  return d;
}

void roundTrip(const imps::calibration::RigMap& map, const imps::calibration::RigMapContext& context) {
  const std::string written = imps::calibration::toJson(map);
  FUZZ_CHECK(imps::firstInvalidUtf8(written) == written.size());
  auto again = imps::calibration::parseRigMap(written, "written.json", context);
  if (!again) {
    std::fprintf(stderr, "written map does not read back:\n%s\n%s", again.error().str().c_str(), written.c_str());
    std::abort();
  }
  FUZZ_CHECK(again->channels.size() == map.channels.size());
  FUZZ_CHECK(again->joints.size() == map.joints.size());
  FUZZ_CHECK(imps::calibration::toJson(*again) == written);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  for (const imps::calibration::RigMapContext& context :
       {imps::calibration::RigMapContext{}, imps::calibration::RigMapContext{nullptr, &device(), false}}) {
    auto map = imps::calibration::parseRigMap(text, "fuzz.json", context);
    if (!map) {
      FUZZ_CHECK(map.error().hasErrors());
      FUZZ_CHECK(!map.error().str().empty());
      continue;
    }
    roundTrip(*map, context);
  }
  return 0;
}
