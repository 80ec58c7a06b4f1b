// SPDX-License-Identifier: MIT
// The PNG encoder plugin: OpenImageIO behind a small C interface, loaded by puppeteer/src/png.cpp only when a PNG
// is written. OpenImageIO brings some 500 shared libraries whose start-up costs about 0.3 s; commands that write
// no image (mesh, check, record …) should not pay it.
#include <cctype>
#include <cmath>
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
  OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  // The pixels are straight (unassociated) alpha, as PNG stores them: without this OpenImageIO takes them for
  // premultiplied and divides the colour by alpha, so a half-transparent texel came back with another colour.
  spec.attribute("oiio:UnassociatedAlpha", 1);
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

// Whether an image's values are linear light (EXR, HDR, floating-point TIFF ...) rather than sRGB-encoded: a
// floating-point pixel type, or a colour space OpenImageIO names linear.
bool linearImage(const OIIO::ImageSpec& spec) {
  if (spec.format.is_floating_point()) return true;
  std::string space = spec.get_string_attribute("oiio:ColorSpace");
  for (char& c : space) c = char(std::tolower(static_cast<unsigned char>(c)));
  return space.find("linear") != std::string::npos || space.rfind("lin_", 0) == 0 || space == "scene_linear";
}

// Linear [0, 1] -> an sRGB-encoded byte (IEC 61966-2-1), rounded to nearest; NaN -> 0.
uint8_t encodeSrgb(float linear) {
  const float c = linear > 0.0f ? (linear < 1.0f ? linear : 1.0f) : 0.0f;
  const float e = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(e * 255.0f));
}

// Reads any image OpenImageIO knows (PNG, JPEG, EXR, ...) as RGBA8, rows from the top: grey gets copied to
// RGB, a missing alpha is opaque. The bytes are sRGB-encoded colour (as PNG and JPEG store it) and linear alpha:
// a linear image (EXR's floats, linearImage()) has its colour clamped to [0, 1] and encoded to sRGB, its alpha
// clamped and scaled; other types are converted by OpenImageIO. On success
// returns 0 and sets *rgba (malloc'd; release with imps_png_free), *width and *height; on failure returns -1 and
// writes a message into error.
extern "C" __attribute__((visibility("default"))) int imps_image_read(const char* path, int* width, int* height,
                                                                     uint8_t** rgba, char* error, size_t errorSize) {
  // Straight alpha, as PNG stores it (by default OpenImageIO premultiplies the colour by alpha on reading).
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
  if (!in) {
    std::string message = OIIO::geterror();
    copyError(message.empty() ? "not an image OpenImageIO can read" : message, error, errorSize);
    return -1;
  }
  const OIIO::ImageSpec& spec = in->spec();
  const int w = spec.width, h = spec.height, channels = spec.nchannels;
  if (w <= 0 || h <= 0 || channels <= 0 || int64_t(w) * h > (int64_t(1) << 28)) {
    copyError("unsupported image size " + std::to_string(w) + " x " + std::to_string(h), error, errorSize);
    return -1;
  }
  const bool linear = linearImage(spec);
  std::vector<uint8_t> pixels(size_t(w) * size_t(h) * size_t(channels));
  if (linear) {
    std::vector<float> values(pixels.size());
    if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, values.data())) {
      copyError("cannot decode: " + in->geterror(), error, errorSize);
      return -1;
    }
    // Colour channels: the first three (one or two channels: grey, then alpha).
    const int colour = channels >= 3 ? 3 : 1;
    for (size_t i = 0; i < values.size(); ++i) {
      const float x = values[i];
      pixels[i] = int(i % size_t(channels)) < colour
                      ? encodeSrgb(x)
                      : uint8_t(std::lround((x > 0.0f ? (x < 1.0f ? x : 1.0f) : 0.0f) * 255.0f));
    }
  } else if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, pixels.data())) {
    copyError("cannot decode: " + in->geterror(), error, errorSize);
    return -1;
  }
  *rgba = static_cast<uint8_t*>(std::malloc(size_t(w) * size_t(h) * 4));
  if (!*rgba) {
    copyError("out of memory", error, errorSize);
    return -1;
  }
  for (size_t p = 0; p < size_t(w) * size_t(h); ++p) {
    const uint8_t* s = pixels.data() + p * size_t(channels);
    uint8_t* d = *rgba + 4 * p;
    const bool grey = channels < 3;
    d[0] = s[0];
    d[1] = grey ? s[0] : s[1];
    d[2] = grey ? s[0] : s[2];
    d[3] = channels == 2 ? s[1] : channels >= 4 ? s[3] : 255;
  }
  *width = w;
  *height = h;
  return 0;
}
