// SPDX-License-Identifier: MIT
// Biovision Hierarchy (BVH) motion files: a lenient reader for files found in the wild, a canonical writer and an
// atomic save.
#pragma once

#include <array>
#include <cstdint>
#include <expected>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "imps/diagnostic.h"

namespace imps::sim {

// One channel of a BVH joint. Positions are in the file's length unit, rotations in degrees.
enum class BvhChannel : uint8_t { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

// "Xposition" ... "Zrotation", as written in files.
std::string_view bvhChannelName(BvhChannel channel);
inline bool isRotation(BvhChannel c) { return c >= BvhChannel::Xrotation; }

// A ROOT or JOINT. An `End Site` is not a joint: it is stored on the joint that contains it.
struct BvhJoint {
  std::string name;                         // as in the file; may contain ':' ("mixamorig:Hips") or be "End"
  int parent = -1;                          // index into BvhClip::joints, -1 for a ROOT; always < own index
  std::array<double, 3> offset{};           // from the parent joint, in the file's length unit
  std::vector<BvhChannel> channels;         // in file order (e.g. Zrotation Xrotation Yrotation); 0..6 entries
  bool hasEndSite = false;                  // the joint contains an `End Site { OFFSET ... }` block
  std::array<double, 3> endSiteOffset{};    // meaningful when hasEndSite
  bool operator==(const BvhJoint&) const = default;
};

// A whole clip. Joints are in file order (depth first, parents before children; several ROOTs allowed).
struct BvhClip {
  std::vector<BvhJoint> joints;
  double frameTime = 0;                     // seconds per frame
  std::vector<std::vector<float>> frames;   // frames[f] has channelCount() values, joints' channels in file order
  bool operator==(const BvhClip&) const = default;

  // Total number of channels (the length of every frame).
  size_t channelCount() const;
  // Index of joint j's first channel within a frame.
  size_t firstChannel(size_t joint) const;
};

// Reads a BVH file. Accepts CRLF, LF, CR and mixed line endings, tabs, blank lines anywhere, a UTF-8 BOM, per-joint
// channel orders, joint names with ':' or spaces, a joint named `End`, keywords in any letter case, and a `Frames:`
// count that disagrees with the data (the data wins; a warning says so). A last frame line cut short is dropped
// with a warning. Anything else wrong is an error at the file, line and column where it was found, naming what was
// expected; the reader stops there, so a failure holds exactly one diagnostic (printed "file:line:column: error:
// ..."; a file that cannot be read, "file: error: cannot open BVH file: REASON"). Warnings, if `warnings` is given,
// are appended there (printed "file:line:column: warning: ...").
std::expected<BvhClip, Diagnostics> readBvh(const std::filesystem::path& path, Diagnostics* warnings = nullptr);
// The same from text; `name` stands for the file in messages.
std::expected<BvhClip, Diagnostics> readBvhText(std::string_view text, std::string_view name = "<text>",
                                                Diagnostics* warnings = nullptr);

// Writes a clip in a canonical form: LF line endings, tab indentation, numbers in the shortest form that reads
// back to the same value, so readBvhText(writeBvh(c)) == c. A clip that cannot be written (a parent after its child,
// joints not in depth-first order, a name with braces or line breaks, a frame not channelCount() long) is one error
// without a location saying which joint or frame.
std::expected<std::string, Diagnostics> writeBvh(const BvhClip& clip);

// Writes writeBvh(clip) to `path` without ever leaving a half-written file: a temporary file beside it is written,
// flushed to disk and renamed over the target. Fails with one error at `path` (printed "path: error: ..."): the
// clip's problem, or the save's "cannot save 'PATH': STEP: REASON" (atomic_file.h).
std::expected<void, Diagnostics> saveBvh(const std::filesystem::path& path, const BvhClip& clip);

}  // namespace imps::sim
