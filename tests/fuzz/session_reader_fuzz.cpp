// SPDX-License-Identifier: MIT
// libFuzzer target for the session file reader (sim/session_file): any bytes must give a Session or an error,
// never a crash, and a Session must be self-consistent.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "sim/bvh_session.h"
#include "sim/session_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto session = imps::sim::readSessionBytes(std::span(data, size), "fuzz.session");
  if (!session) return 0;
  const auto& rec = session->recovery;
  if (session->samples.size() != session->sampleDevice.size()) std::abort();
  if (rec.bytesUsed + rec.bytesIgnored != size || rec.fileBytes != size) std::abort();
  for (size_t i = 0; i < session->samples.size(); ++i) {
    const auto& device = session->devices.at(session->sampleDevice[i]);
    if (session->samples[i].channelCount != device.channelCount) std::abort();
  }
  // Conversion must cope with whatever the reader accepted.
  (void)imps::sim::sessionToBvh(*session);
  return 0;
}
