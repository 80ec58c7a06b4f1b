// SPDX-License-Identifier: MIT
// Calibrations stored in recorded sessions: writing the one in force, and finding the one a replayed sample was
// captured with. Lives in puppeteer/ because it is where calibration/ and sim/ meet.
#pragma once

#include <cstddef>
#include <expected>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

#include "calibration/calibration.h"
#include "imps/io_error.h"
#include "sim/session_file.h"

namespace imps::app {

// Appends `calibration` as the session's calibration from the next sample on (SessionWriter::appendCalibration
// with the calibration file's text). Errors are the writer's, as an IoError (sessionWriterError).
IoResult<void> appendCalibration(sim::SessionWriter& writer, const calibration::Calibration& c);

// A SessionWriter error (Diagnostics at the session file) as the IoError a recorder reports: the first diagnostic's
// file and message, or "cannot write" at `path` when there is none.
IoError sessionWriterError(const std::filesystem::path& path, const Diagnostics& error);

// Whether a CALIBRATION blob is the BVH channel mapping `puppeteer convert` wrote into sessions made from BVH clips
// before rig-map calibrations existed (`{"source":"bvh",…}`, no version; examples/simple_biped_wave.session had
// one). It says no more than the channel names (`Joint:Zrotation`) and the SKELETON record, so it is read as "no
// calibration": replay maps those channels by name, silently. docs/session-format.md.
bool isBvhChannelMapping(std::string_view json);

// The calibration in force for sample `sampleIndex` of `session`: the last CALIBRATION record whose firstSample is
// <= sampleIndex, BVH channel mappings skipped; nullopt when the session has none that early. The blob is parsed
// and checked against the character (may be null) and the sample's device; errors are reported as "SESSION
// calibration #N:line:column: error: …" with the given session name.
std::expected<std::optional<calibration::Calibration>, Diagnostics> calibrationForSample(
    const sim::Session& session, size_t sampleIndex, const Character* character = nullptr,
    const std::string& sessionName = "session");

}  // namespace imps::app
