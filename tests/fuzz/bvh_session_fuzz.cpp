// SPDX-License-Identifier: MIT
// libFuzzer target for BVH -> session -> BVH conversion (sim/bvh_session): whatever clip the reader accepts converts
// to a self-consistent session (one sample per frame and device, timestamps that never go back) or to an error, and
// the session converts back to a clip of the same shape. Never a crash, an overflow or an exception.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "fuzz_check.h"
#include "sim/bvh.h"
#include "sim/bvh_session.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto clip = imps::sim::readBvhText(text, "fuzz.bvh");
  if (!clip) return 0;
  for (int bits : {8, 16, 20}) {
    auto session = imps::sim::bvhToSession(*clip, "fuzz.bvh", {.bitsPerChannel = bits});
    if (!session) continue;
    FUZZ_CHECK(!session->devices.empty());
    FUZZ_CHECK(session->samples.size() == clip->frames.size() * session->devices.size());
    FUZZ_CHECK(session->samples.size() == session->sampleDevice.size());
    size_t channels = 0;
    for (const auto& d : session->devices) channels += static_cast<size_t>(d.channelCount);
    FUZZ_CHECK(channels == clip->channelCount());
    for (size_t i = 0; i < session->samples.size(); ++i) {
      const auto& s = session->samples[i];
      FUZZ_CHECK(s.channelCount == session->devices.at(session->sampleDevice[i]).channelCount);
      if (i > 0) FUZZ_CHECK(s.arrivalTimeNs >= session->samples[i - 1].arrivalTimeNs);
    }
    auto back = imps::sim::sessionToBvh(*session);
    if (!back) {
      std::fprintf(stderr, "a converted session does not convert back: %s\n", back.error().firstError().c_str());
      std::abort();
    }
    FUZZ_CHECK(back->frames.size() == clip->frames.size());
    FUZZ_CHECK(back->channelCount() == clip->channelCount());
  }
  return 0;
}
