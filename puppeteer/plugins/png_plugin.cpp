// The PNG encoder plugin: OpenImageIO behind a small C interface, loaded by puppeteer/src/png.cpp only when a PNG
// is written. OpenImageIO brings some 500 shared libraries whose start-up costs about 0.3 s; commands that write
// no image (mesh, check, record …) should not pay it.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

namespace {
void copyError(const std::string& message, char* error, size_t errorSize) {
  if (!error || errorSize == 0) return;
  std::strncpy(error, message.c_str(), errorSize - 1);
  error[errorSize - 1] = '\0';
}
}  // namespace

// Encodes width x height RGBA8 pixels (rows from the top) as a PNG in memory. On success returns 0 and sets *png
// (malloc'd; release with imps_png_free) and *pngSize; on failure returns -1 and writes a message into error.
extern "C" __attribute__((visibility("default"))) int imps_png_encode(int width, int height, const uint8_t* rgba,
                                                                     uint8_t** png, size_t* pngSize, char* error,
                                                                     size_t errorSize) {
  std::vector<unsigned char> bytes;
  OIIO::Filesystem::IOVecOutput memory(bytes);
  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create("png", &memory);
  if (!out) {
    copyError("OpenImageIO cannot write PNG: " + OIIO::geterror(), error, errorSize);
    return -1;
  }
  const OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  if (!out->open("memory.png", spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgba) || !out->close()) {
    copyError("PNG encoding failed: " + out->geterror(), error, errorSize);
    return -1;
  }
  out.reset();
  *png = static_cast<uint8_t*>(std::malloc(bytes.size()));
  if (!*png) {
    copyError("out of memory", error, errorSize);
    return -1;
  }
  std::memcpy(*png, bytes.data(), bytes.size());
  *pngSize = bytes.size();
  return 0;
}

extern "C" __attribute__((visibility("default"))) void imps_png_free(uint8_t* png) { std::free(png); }
