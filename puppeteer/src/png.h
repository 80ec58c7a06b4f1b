// SPDX-License-Identifier: MIT
// PNG files for snapshots and screenshots, written atomically. OpenImageIO does the encoding from a plugin loaded
// on first use, so commands that write no image start without it.
#pragma once

#include <cstdint>
#include <expected>
#include <string>
#include <vector>

#include "imps/diagnostic.h"

namespace imps::app {

// Saves width x height RGBA8 pixels (rows from the top) to `path`, which must end in ".png" (any case):
// encoded in memory, then temporary file, fsync, rename. On failure leaves `path` untouched and returns one error
// without a location whose message names the file as the commands print it: "path: reason" for the image (a wrong
// extension, no pixels, the encoder's refusal, or an encoder plugin — libimps_png.so, looked up beside the
// executable, then in the build tree, or at $IMPS_PNG_PLUGIN — that cannot be loaded), or the save's
// "cannot save 'path': STEP: REASON" (imps/atomic_file.h). Callers treat both as an output not written.
std::expected<void, Diagnostics> savePng(const std::vector<uint8_t>& rgba, int width, int height,
                                         const std::string& path);

// The PNG bytes of width x height RGBA8 pixels (rows from the top), or one error without a location: the reason.
std::expected<std::vector<uint8_t>, Diagnostics> encodePng(const std::vector<uint8_t>& rgba, int width, int height);

// An RGBA8 image, rows from the top.
struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // width * height * 4
  bool operator==(const RgbaImage&) const = default;
};

// Reads an image file OpenImageIO knows (PNG, JPEG, EXR, ...) through the same plugin: grey becomes RGB, a missing
// alpha is opaque. The colour bytes are always sRGB-encoded (as the renderers decode them): PNG's and JPEG's as
// stored, a linear image's (EXR, any floating-point image) clamped to [0, 1] and encoded linear -> sRGB (alpha stays
// linear). On failure returns one error at `path` whose message is the reason alone (the plugin's, which cannot tell a
// missing file from a corrupt one: both are a bad input to the reader's callers).
std::expected<RgbaImage, Diagnostics> readImage(const std::string& path);

}  // namespace imps::app
