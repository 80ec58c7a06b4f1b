// SPDX-License-Identifier: MIT
// libFuzzer target for the OSC pose-stream decoder (drivers/osc_codec): any datagram must decode or give a located
// error, never crash or read outside it, and whatever decodes must hold the documented invariants (docs/osc.md).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <span>
#include <string>

#include "drivers/osc_codec.h"

#include "fuzz_check.h"

using namespace imps::drivers;

namespace {

void checkPose(const OscPose& p) {
  FUZZ_CHECK(p.jointCount <= kMaxOscJoints);
  FUZZ_CHECK(p.arrivalTimeNs == 42);
  for (int i = 0; i < p.jointCount; ++i) {
    const OscJointRotation& j = p.joints[i];
    const size_t n = j.nameView().size();
    FUZZ_CHECK(n >= 1 && n <= kMaxOscJointName);
    FUZZ_CHECK(std::isfinite(j.w) && std::isfinite(j.x) && std::isfinite(j.y) && std::isfinite(j.z));
    FUZZ_CHECK(j.w != 0 || j.x != 0 || j.y != 0 || j.z != 0);
  }
  if (p.hasRoot)
    for (float v : p.root) FUZZ_CHECK(std::isfinite(v));
}

void checkChannels(const Sample& s) {
  FUZZ_CHECK(s.channelCount >= 1 && s.channelCount <= kMaxChannels);
  FUZZ_CHECK(s.arrivalTimeNs == 42);
  for (int i = s.channelCount; i < kMaxChannels; ++i) FUZZ_CHECK(s.counts[i] == 0);
  for (auto f : s.flags) FUZZ_CHECK(f == ChannelFlag::Valid);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static auto pose = std::make_unique<OscPose>();
  static auto again = std::make_unique<OscPose>();
  Sample channels, channelsAgain;
  const std::span<const uint8_t> packet(data, size);
  auto decoded = decodeOscPacket(packet, 42, *pose, channels);
  if (!decoded) {
    FUZZ_CHECK(decoded.error().errorCount() == 1);
    const std::string e = decoded.error().str();
    FUZZ_CHECK(e.rfind("osc:byte ", 0) == 0);
    FUZZ_CHECK(e.find(": error: ") != std::string::npos);
    FUZZ_CHECK(std::strtoull(e.c_str() + 9, nullptr, 10) <= size);
  } else if (decoded->kind == OscPacketKind::Pose) {
    FUZZ_CHECK(decoded->hasFrame);
    checkPose(*pose);
  } else if (decoded->kind == OscPacketKind::Channels) {
    checkChannels(channels);
  }
  // Decoding is a function of the bytes alone.
  auto second = decodeOscPacket(packet, 42, *again, channelsAgain);
  FUZZ_CHECK(bool(second) == bool(decoded));
  if (decoded && second) {
    FUZZ_CHECK(second->kind == decoded->kind && second->hasFrame == decoded->hasFrame);
    if (decoded->kind == OscPacketKind::Pose) {
      FUZZ_CHECK(again->frame == pose->frame && again->jointCount == pose->jointCount);
      for (int i = 0; i < pose->jointCount; ++i) FUZZ_CHECK(again->joints[i].nameView() == pose->joints[i].nameView());
    }
    if (decoded->kind == OscPacketKind::Channels) FUZZ_CHECK(channelsAgain == channels);
  }
  return 0;
}
