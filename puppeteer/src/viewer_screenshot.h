// Screenshots of the live app: RGBA8 pixels to a PNG file (OpenImageIO), saved atomically.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace imps::app {

// Writes width x height RGBA8 pixels (rows from the top) to `path`, which must end in ".png", through a temporary
// file renamed over the target. On failure returns false, leaves `path` untouched and sets *error ("path: reason").
bool saveScreenshotPng(const std::vector<uint8_t>& pixels, int width, int height, const std::string& path,
                       std::string* error);

}  // namespace imps::app
