// SPDX-License-Identifier: MIT
// BVH clip <-> recorded session conversion (mapping in docs/session-format.md, "BVH conversion").
#include "sim/bvh_session.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

namespace imps::sim {

namespace {

constexpr int kMinBits = 8;
constexpr int kMaxBits = 20;

// Shortest text that reads back as the same double.
std::string jsonNumber(double v) {
  char buf[64];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, end);
}

int64_t halfScale(int bits) { return int64_t{1} << (bits - 1); }

// Counts for a position value; nullopt when it does not fit the bit depth.
std::optional<uint32_t> positionToCounts(double value, double unitsPerCount, int bits) {
  const double q = std::nearbyint(value / unitsPerCount);
  const double h = static_cast<double>(halfScale(bits));
  if (!(q >= -h && q < h)) return std::nullopt;
  return static_cast<uint32_t>(static_cast<int64_t>(q) + halfScale(bits));
}

double countsToPosition(uint32_t counts, double unitsPerCount, int bits) {
  return static_cast<double>(static_cast<int64_t>(counts) - halfScale(bits)) * unitsPerCount;
}

// Splits "<joint>:<BVH channel>" at the last ':'.
std::optional<std::pair<std::string, BvhChannel>> splitChannelName(std::string_view name) {
  const size_t colon = name.rfind(':');
  if (colon == std::string_view::npos || colon == 0) return std::nullopt;
  const std::string_view tail = name.substr(colon + 1);
  for (int k = 0; k < 6; ++k)
    if (tail == bvhChannelName(static_cast<BvhChannel>(k)))
      return std::pair{std::string(name.substr(0, colon)), static_cast<BvhChannel>(k)};
  return std::nullopt;
}

std::string writableName(std::string name) {
  for (char& c : name)
    if (c == '{' || c == '}' || c == ' ' || c == '\t' || c == '\r' || c == '\n') c = '_';
  return name.empty() ? std::string("channel") : name;
}

}  // namespace

uint32_t degreesToCounts(double degrees, int bits) {
  const int64_t turn = int64_t{1} << bits;
  const double q = std::nearbyint(degrees * static_cast<double>(turn) / 360.0);
  // fmod keeps huge angles exact before the integer conversion.
  const double wrapped = std::fmod(q, static_cast<double>(turn));
  int64_t c = static_cast<int64_t>(wrapped) + halfScale(bits);
  c %= turn;
  if (c < 0) c += turn;
  return static_cast<uint32_t>(c);
}

double countsToDegrees(uint32_t counts, int bits) {
  return static_cast<double>(static_cast<int64_t>(counts) - halfScale(bits)) * 360.0 /
         static_cast<double>(int64_t{1} << bits);
}

namespace {

// "the clip's WHAT takes N bytes, more than the 64 MiB a session record holds".
std::string recordTooLarge(const std::string& what, size_t bytes) {
  return "the clip's " + what + " takes " + std::to_string(bytes) + " bytes, more than the " +
         std::to_string(kMaxRecordPayloadBytes >> 20) + " MiB a session record holds";
}

}  // namespace

std::expected<Session, Diagnostics> bvhToSession(const BvhClip& clip, std::string_view sourceName,
                                                 BvhToSessionOptions options) {
  const std::string name(sourceName);
  auto fail = [&](std::string what) { return std::unexpected(singleError({name}, std::move(what))); };
  const int bits = options.bitsPerChannel;
  if (bits < kMinBits || bits > kMaxBits)
    return fail("bits per channel " + std::to_string(bits) + " outside " + std::to_string(kMinBits) + ".." +
                std::to_string(kMaxBits));
  const size_t channelCount = clip.channelCount();
  if (channelCount == 0) return fail("the clip has no channels");
  if (!(clip.frameTime >= 0) || !std::isfinite(clip.frameTime)) return fail("bad frame time");
  // Every timestamp, frame index * frame time in ns, must fit the session's int64 (about 292 years).
  if (static_cast<double>(clip.frames.size()) * clip.frameTime * 1e9 >= 0x1p62)
    return fail("the clip lasts longer than a session can time (" + std::to_string(clip.frames.size()) +
                " frames of " + std::to_string(clip.frameTime) + " s)");

  // A session of more channels than this would be thousands of devices and records beyond the format's limit.
  constexpr size_t kMaxSessionChannels = size_t{1} << 16;
  if (channelCount > kMaxSessionChannels)
    return fail("the clip has " + std::to_string(channelCount) + " channels, more than the " +
                std::to_string(kMaxSessionChannels) + " a session holds (" +
                std::to_string(kMaxSessionChannels / drivers::kMaxChannels) + " devices of " +
                std::to_string(drivers::kMaxChannels) + ")");

  // Per channel: joint, kind; and the largest position magnitude for the automatic scale.
  std::vector<std::string> channelNames;
  std::vector<bool> rotation;
  for (const auto& joint : clip.joints)
    for (BvhChannel c : joint.channels) {
      channelNames.push_back(joint.name + ":" + std::string(bvhChannelName(c)));
      rotation.push_back(isRotation(c));
    }
  double maxPosition = 0;
  for (const auto& frame : clip.frames) {
    if (frame.size() != channelCount) return fail("a frame's length differs from the channel count");
    for (size_t i = 0; i < channelCount; ++i)
      if (!rotation[i]) maxPosition = std::max(maxPosition, std::fabs(static_cast<double>(frame[i])));
  }
  double unitsPerCount = options.positionUnitsPerCount;
  if (!(unitsPerCount >= 0) || !std::isfinite(unitsPerCount)) return fail("bad position scale");
  if (unitsPerCount == 0) {
    // Finest power of two (no finer than 2^-20) that holds every position.
    unitsPerCount = std::ldexp(1.0, -20);
    while (std::nearbyint(maxPosition / unitsPerCount) >= static_cast<double>(halfScale(bits)) - 1)
      unitsPerCount *= 2;
  }

  Session s;
  s.formatVersion = 1;
  const size_t deviceCount = (channelCount + drivers::kMaxChannels - 1) / drivers::kMaxChannels;
  for (size_t d = 0; d < deviceCount; ++d) {
    DeviceInfo info;
    info.name = "BVH: " + name;
    if (deviceCount > 1) info.serialNumber = "part " + std::to_string(d + 1) + "/" + std::to_string(deviceCount);
    const size_t first = d * drivers::kMaxChannels;
    const size_t count = std::min<size_t>(drivers::kMaxChannels, channelCount - first);
    info.channelCount = static_cast<int>(count);
    info.bitsPerChannel = bits;
    info.channelNames.assign(channelNames.begin() + static_cast<std::ptrdiff_t>(first),
                             channelNames.begin() + static_cast<std::ptrdiff_t>(first + count));
    info.hasDeviceTimestamp = true;
    s.devices.push_back(std::move(info));
  }

  // No CALIBRATION record: the channel names (`Joint:Zrotation`) and the SKELETON record (hierarchy, position
  // units) say how counts become the clip's channels, and replay maps such channels by name. (Sessions converted
  // before version 0.2 carry a `{"source":"bvh",…}` blob saying the same; readers skip it.)

  BvhClip hierarchy = clip;
  hierarchy.frames.clear();
  auto hierarchyText = writeBvh(hierarchy);
  if (!hierarchyText) return fail(hierarchyText.error().all().front().message);
  s.skeleton = SessionSkeleton{std::move(*hierarchyText), unitsPerCount};
  if (s.skeleton->bvh.size() + 8 > kMaxRecordPayloadBytes)  // the SKELETON record: scale, then the text
    return fail(recordTooLarge("hierarchy (joint names and offsets)", s.skeleton->bvh.size() + 8));

  s.samples.reserve(clip.frames.size() * deviceCount);
  s.sampleDevice.reserve(clip.frames.size() * deviceCount);
  for (size_t f = 0; f < clip.frames.size(); ++f) {
    const auto t = static_cast<int64_t>(std::llround(static_cast<double>(f) * clip.frameTime * 1e9));
    for (size_t d = 0; d < deviceCount; ++d) {
      Sample sample;
      sample.sequence = static_cast<uint32_t>(f);
      sample.deviceTimeNs = t;
      sample.arrivalTimeNs = t;
      sample.channelCount = static_cast<uint16_t>(s.devices[d].channelCount);
      for (size_t k = 0; k < sample.channelCount; ++k) {
        const size_t i = d * drivers::kMaxChannels + k;
        const double v = clip.frames[f][i];
        if (rotation[i]) {
          sample.counts[k] = degreesToCounts(v, bits);
        } else {
          auto c = positionToCounts(v, unitsPerCount, bits);
          if (!c)
            return fail(channelNames[i] + " = " + jsonNumber(v) + " in frame " + std::to_string(f + 1) +
                        " does not fit " + std::to_string(bits) + " bits at " + jsonNumber(unitsPerCount) +
                        " units per count");
          sample.counts[k] = *c;
        }
      }
      s.samples.push_back(sample);
      s.sampleDevice.push_back(static_cast<uint16_t>(d));
    }
  }
  return s;
}

std::expected<BvhClip, Diagnostics> sessionToBvh(const Session& session, SessionToBvhOptions options) {
  auto fail = [](std::string what) { return std::unexpected(singleError({"session"}, std::move(what))); };
  if (session.devices.empty()) return fail("the session has no devices");
  if (session.samples.size() != session.sampleDevice.size()) return fail("samples and sampleDevice differ in length");

  // The session's channels, all devices in order.
  std::vector<size_t> deviceFirst;
  std::vector<std::string> names;
  for (size_t d = 0; d < session.devices.size(); ++d) {
    const DeviceInfo& info = session.devices[d];
    deviceFirst.push_back(names.size());
    for (int k = 0; k < info.channelCount; ++k)
      names.push_back(static_cast<size_t>(k) < info.channelNames.size()
                          ? info.channelNames[static_cast<size_t>(k)]
                          : "d" + std::to_string(d) + "ch" + std::to_string(k));
  }

  BvhClip clip;
  double unitsPerCount = options.positionUnitsPerCount;
  if (session.skeleton) {
    auto parsed = readBvhText(session.skeleton->bvh, "session skeleton");
    if (!parsed) {  // the reader's first error, where it is in the skeleton's text
      const Diagnostic& first = parsed.error().all().front();
      return std::unexpected(singleError(first.loc, first.message));
    }
    clip = std::move(*parsed);
    clip.frames.clear();
    unitsPerCount = session.skeleton->positionUnitsPerCount;
    if (clip.channelCount() != names.size())
      return fail("the skeleton has " + std::to_string(clip.channelCount()) + " channels but the devices have " +
                  std::to_string(names.size()));
    size_t i = 0;
    for (const auto& joint : clip.joints)
      for (BvhChannel c : joint.channels) {
        const std::string expected = joint.name + ":" + std::string(bvhChannelName(c));
        if (names[i] != expected)
          return fail("channel " + std::to_string(i) + " is '" + names[i] + "', the skeleton says '" + expected + "'");
        ++i;
      }
  } else {
    // A flat skeleton: one joint per run of channels naming the same joint.
    clip.joints.push_back({"Session", -1, {0, 0, 0}, {}, false, {}});
    for (size_t i = 0; i < names.size(); ++i) {
      const auto split = splitChannelName(names[i]);
      BvhJoint* last = clip.joints.size() > 1 ? &clip.joints.back() : nullptr;
      if (split && last && last->name == writableName(split->first) &&
          std::find(last->channels.begin(), last->channels.end(), split->second) == last->channels.end()) {
        last->channels.push_back(split->second);
        continue;
      }
      BvhJoint j;
      j.name = writableName(split ? split->first : names[i]);
      j.parent = 0;
      j.channels = {split ? split->second : BvhChannel::Zrotation};
      j.hasEndSite = true;
      j.endSiteOffset = {0, 10, 0};
      clip.joints.push_back(std::move(j));
    }
  }
  if (!(unitsPerCount > 0) || !std::isfinite(unitsPerCount)) return fail("bad position scale");

  std::vector<bool> rotation;
  for (const auto& joint : clip.joints)
    for (BvhChannel c : joint.channels) rotation.push_back(isRotation(c));

  // Frame time.
  auto timeOf = [&](size_t i) {
    return session.devices[0].hasDeviceTimestamp ? session.samples.deviceTimeNs(i) : session.samples.arrivalTimeNs(i);
  };
  if (!session.skeleton) {
    std::vector<int64_t> deltas;
    std::optional<int64_t> previous;
    for (size_t i = 0; i < session.samples.size(); ++i) {
      if (session.sampleDevice[i] != 0) continue;
      // Timestamps are whatever the file holds: a difference that overflows int64 is no frame time.
      if (int64_t delta; previous && !__builtin_sub_overflow(timeOf(i), *previous, &delta)) deltas.push_back(delta);
      previous = timeOf(i);
    }
    clip.frameTime = 1.0 / 60.0;
    if (!deltas.empty()) {
      std::nth_element(deltas.begin(), deltas.begin() + static_cast<std::ptrdiff_t>(deltas.size() / 2), deltas.end());
      const int64_t median = deltas[deltas.size() / 2];
      if (median > 0) clip.frameTime = static_cast<double>(median) * 1e-9;
    }
  }

  // Frames: hold each channel's last valid count; emit a frame when device 0 starts the next one.
  std::vector<uint32_t> counts(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    const size_t d =
        static_cast<size_t>(std::upper_bound(deviceFirst.begin(), deviceFirst.end(), i) - deviceFirst.begin()) - 1;
    counts[i] = static_cast<uint32_t>(halfScale(session.devices[d].bitsPerChannel));
  }
  std::vector<double> previousValue(names.size(), 0.0);
  bool havePrevious = false, pending = false;
  auto emit = [&]() {
    std::vector<float> frame(names.size());
    for (size_t i = 0; i < names.size(); ++i) {
      const size_t d =
          static_cast<size_t>(std::upper_bound(deviceFirst.begin(), deviceFirst.end(), i) - deviceFirst.begin()) - 1;
      const int bits = session.devices[d].bitsPerChannel;
      double v;
      if (rotation[i]) {
        v = countsToDegrees(counts[i], bits);
        if (options.unwrap && havePrevious) v += 360.0 * std::nearbyint((previousValue[i] - v) / 360.0);
      } else {
        v = countsToPosition(counts[i], unitsPerCount, bits);
      }
      previousValue[i] = v;
      frame[i] = static_cast<float>(v);
    }
    havePrevious = true;
    clip.frames.push_back(std::move(frame));
  };
  for (size_t i = 0; i < session.samples.size(); ++i) {
    const uint16_t d = session.sampleDevice[i];
    if (d >= session.devices.size()) return fail("sample " + std::to_string(i) + " names device " + std::to_string(d));
    if (d == 0) {
      if (pending) emit();
      pending = true;
    }
    const Sample sample = session.samples[i];
    const size_t n = std::min<size_t>(sample.channelCount, static_cast<size_t>(session.devices[d].channelCount));
    for (size_t k = 0; k < n; ++k)
      if (sample.flags[k] == drivers::ChannelFlag::Valid) counts[deviceFirst[d] + k] = sample.counts[k];
  }
  if (pending) emit();
  return clip;
}

}  // namespace imps::sim
