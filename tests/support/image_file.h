// SPDX-License-Identifier: MIT
// Images written by the program under test, read back with OpenImageIO directly (not through puppeteer/src/png.h),
// for command-line tests. Header-only: include it only in test binaries linked with OpenImageIO (puppeteer_tests).
#pragma once

#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace imps::test {

// 8-bit pixels, rows from the top, `channels` values per pixel as stored (PNG: 3 or 4).
struct ImageFile {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<uint8_t> pixels;
};

// The image at `path`, or nullopt when it cannot be opened or decoded (a truncated file included).
inline std::optional<ImageFile> readImageFile(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) {
    (void)OIIO::geterror();  // clear OIIO's per-thread error so it is not printed at exit
    return std::nullopt;
  }
  const OIIO::ImageSpec& spec = in->spec();
  ImageFile image{spec.width, spec.height, spec.nchannels, {}};
  image.pixels.resize(size_t(image.width) * size_t(image.height) * size_t(image.channels));
  const bool read = in->read_image(0, 0, 0, image.channels, OIIO::TypeDesc::UINT8, image.pixels.data());
  (void)in->geterror();
  return read ? std::optional<ImageFile>(std::move(image)) : std::nullopt;
}

}  // namespace imps::test
