// PNG files for snapshots and screenshots, written atomically. OpenImageIO does the encoding from a plugin loaded
// on first use, so commands that write no image start without it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace imps::app {

// Saves width x height RGBA8 pixels (rows from the top) to `path`, which must end in ".png" (any case):
// encoded in memory, then temporary file, fsync, rename. On failure returns false, leaves `path` untouched and sets
// *error (if non-null) to "path: reason" — including when the encoder plugin (libimps_png.so, looked up beside
// the executable, then in the build tree, or at $IMPS_PNG_PLUGIN) cannot be loaded.
bool savePng(const std::vector<uint8_t>& rgba, int width, int height, const std::string& path, std::string* error);

}  // namespace imps::app
