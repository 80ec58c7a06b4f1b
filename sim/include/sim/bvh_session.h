// SPDX-License-Identifier: MIT
// Conversion between BVH clips and recorded sessions: a clip becomes a pose stream of encoder counts (so public
// motion capture can drive the rig without hardware) and a session becomes a clip (so a performance opens in
// Blender). The count mapping is specified in docs/session-format.md ("BVH conversion").
#pragma once

#include <cstdint>
#include <expected>
#include <string>
#include <string_view>

#include "sim/bvh.h"
#include "sim/session_file.h"

namespace imps::sim {

// Raw encoder mapping for rotations: 2^bits counts per turn, 0 degrees at mid-scale 2^(bits-1), so counts cover
// [-180, 180) degrees. degreesToCounts wraps any angle into that turn and rounds to the nearest count;
// countsToDegrees(degreesToCounts(a)) is within half a count (180 / 2^bits degrees) of a modulo 360, and
// degreesToCounts(countsToDegrees(c)) == c for every c < 2^bits, also after a float round trip when bits <= 20.
uint32_t degreesToCounts(double degrees, int bits);
double countsToDegrees(uint32_t counts, int bits);

struct BvhToSessionOptions {
  int bitsPerChannel = 16;            // 8..20 (a float angle cannot resolve finer steps near 180 degrees)
  // BVH length units per count for position channels, 0 = automatic: the finest power of two for which every
  // position in the clip fits in [-2^(bits-1), 2^(bits-1)) counts around mid-scale.
  double positionUnitsPerCount = 0;
};

// Turns a clip into a session. Every channel of every joint (rotations and positions, in file order) becomes one
// session channel named "<joint>:<channel>" (e.g. "mixamorig:Hips:Zrotation"); clips with more than kMaxChannels
// channels are split across several devices of at most kMaxChannels channels each. Frame f becomes one sample per
// device with sequence f and deviceTimeNs = arrivalTimeNs = round(f * frameTime * 1e9). The devices are named
// "BVH: <sourceName>". The session carries a SKELETON record (the hierarchy as a zero-frame BVH file) and one
// CALIBRATION JSON blob describing the mapping. Fails with one error at `sourceName` (no channels, bad options,
// positions out of range, a hierarchy writeBvh refuses).
std::expected<Session, Diagnostics> bvhToSession(const BvhClip& clip, std::string_view sourceName,
                                                 BvhToSessionOptions options = {});

struct SessionToBvhOptions {
  // Rotation angles come back in [-180, 180); with unwrap each is shifted by whole turns to lie nearest the
  // previous frame's value, which reproduces continuous tracks that cross +-180 degrees.
  bool unwrap = true;
  // Position scale when the session has no SKELETON record.
  double positionUnitsPerCount = 0.01;
};

// Turns a session into a clip. With a SKELETON record the hierarchy comes from it and the session's channels
// (all devices' channels, in device order) must match its channels one for one. Without one, a flat skeleton is
// made: a root "Session" without channels and one child joint per channel group, where channels named
// "<joint>:<BVH channel>" that follow each other form one joint and any other channel becomes a joint with one
// Zrotation channel. One frame is written per sample of device 0, taking every other device's most recent sample
// (samples of one frame are recorded device 0 first). Channels flagged NotConnected or Outlier hold their last
// valid value (0 degrees / mid-scale before any). Frame time: the skeleton's, else the median spacing of device
// 0's timestamps (device time when it has one), else 1/60 s. Fails with one error at "session" (printed
// "session: error: ..."), or at "session skeleton:LINE:COLUMN" for a SKELETON record the BVH reader refuses.
std::expected<BvhClip, Diagnostics> sessionToBvh(const Session& session, SessionToBvhOptions options = {});

}  // namespace imps::sim
