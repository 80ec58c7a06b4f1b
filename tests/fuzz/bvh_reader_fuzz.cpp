// SPDX-License-Identifier: MIT
// libFuzzer target for the BVH reader (sim/bvh): any text gives a clip or an error, never a crash; a clip that
// was read writes back (writeBvh never refuses it) to text that reads as the same clip.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "sim/bvh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto clip = imps::sim::readBvhText(text, "fuzz.bvh");
  if (!clip) return 0;
  const auto written = imps::sim::writeBvh(*clip);
  if (!written) std::abort();
  auto again = imps::sim::readBvhText(*written, "written.bvh");
  if (!again || !(*again == *clip)) std::abort();
  return 0;
}
