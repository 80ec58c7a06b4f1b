// SPDX-License-Identifier: MIT
// PNG files for snapshots and screenshots, written atomically. OpenImageIO does the encoding from a plugin loaded
// on first use, so commands that write no image start without it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace imps::app {

// Saves width x height RGBA8 pixels (rows from the top) to `path`, which must end in ".png" (any case):
// encoded in memory, then temporary file, fsync, rename. On failure returns false, leaves `path` untouched and sets
// *error (if non-null) to "path: reason" — including when the encoder plugin (libimps_png.so, looked up beside
// the executable, then in the build tree, or at $IMPS_PNG_PLUGIN) cannot be loaded.
bool savePng(const std::vector<uint8_t>& rgba, int width, int height, const std::string& path, std::string* error);

// The PNG bytes of width x height RGBA8 pixels (rows from the top), or nullopt with *error set to the reason.
std::optional<std::vector<uint8_t>> encodePng(const std::vector<uint8_t>& rgba, int width, int height,
                                              std::string* error);

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
// linear). On failure returns false and sets *error (if non-null) to the reason (without the path).
bool readImage(const std::string& path, RgbaImage& image, std::string* error);

}  // namespace imps::app
