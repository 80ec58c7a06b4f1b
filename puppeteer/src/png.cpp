// SPDX-License-Identifier: MIT
// PNG saving through the lazily loaded OpenImageIO plugin (puppeteer/plugins/png_plugin.cpp).
#include "png.h"

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <mutex>

#include "imps/atomic_file.h"

namespace imps::app {
namespace {

using EncodeFn = int (*)(int, int, const uint8_t*, uint8_t**, size_t*, char*, size_t);
using FreeFn = void (*)(uint8_t*);
using ReadFn = int (*)(const char*, int*, int*, uint8_t**, char*, size_t);

struct Plugin {
  EncodeFn encode = nullptr;
  FreeFn release = nullptr;
  ReadFn read = nullptr;
  std::string error;
};

// Loads the plugin once; later calls return the same result.
const Plugin& plugin() {
  static Plugin p;
  static std::once_flag once;
  std::call_once(once, [] {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv("IMPS_PNG_PLUGIN")) candidates.push_back(env);
    std::error_code ec;
    const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back((exe.parent_path() / "libimps_png.so").string());
    if (!ec) candidates.push_back((exe.parent_path().parent_path() / "lib/imps_puppeteer/libimps_png.so").string());
    candidates.push_back(IMPS_PNG_PLUGIN_PATH);  // the build tree
    std::string tried;
    for (const std::string& path : candidates) {
      void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (!handle) {
        tried += std::string(tried.empty() ? "" : "; ") + dlerror();
        continue;
      }
      p.encode = reinterpret_cast<EncodeFn>(dlsym(handle, "imps_png_encode"));
      p.release = reinterpret_cast<FreeFn>(dlsym(handle, "imps_png_free"));
      p.read = reinterpret_cast<ReadFn>(dlsym(handle, "imps_image_read"));
      if (p.encode && p.release && p.read) return;
      tried += "; " + path + ": not an IMPS PNG plugin";
    }
    p.encode = nullptr;
    p.error = "cannot load the PNG encoder plugin (" + tried + ")";
  });
  return p;
}

}  // namespace

std::optional<std::vector<uint8_t>> encodePng(const std::vector<uint8_t>& rgba, int width, int height,
                                              std::string* error) {
  const Plugin& p = plugin();
  if (!p.encode) {
    if (error) *error = p.error;
    return std::nullopt;
  }
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4) {
    if (error) *error = "no pixels to encode";
    return std::nullopt;
  }
  uint8_t* png = nullptr;
  size_t size = 0;
  char message[512] = "";
  if (p.encode(width, height, rgba.data(), &png, &size, message, sizeof message) != 0) {
    if (error) *error = message;
    return std::nullopt;
  }
  std::vector<uint8_t> bytes(png, png + size);
  p.release(png);
  return bytes;
}

bool savePng(const std::vector<uint8_t>& rgba, int width, int height, const std::string& path, std::string* error) {
  auto fail = [&](const std::string& reason) {
    if (error) *error = path + ": " + reason;
    return false;
  };
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext != ".png") return fail("image files must end in .png");
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4) return fail("no pixels to save");
  const Plugin& p = plugin();
  if (!p.encode) return fail(p.error);
  uint8_t* png = nullptr;
  size_t size = 0;
  char message[512] = "";
  if (p.encode(width, height, rgba.data(), &png, &size, message, sizeof message) != 0) return fail(message);
  std::vector<uint8_t> bytes(png, png + size);
  p.release(png);
  return writeFileAtomically(path, bytes, error);
}

bool readImage(const std::string& path, RgbaImage& image, std::string* error) {
  const Plugin& p = plugin();
  if (!p.encode) {
    if (error) *error = p.error;
    return false;
  }
  uint8_t* rgba = nullptr;
  int width = 0, height = 0;
  char message[512] = "";
  if (p.read(path.c_str(), &width, &height, &rgba, message, sizeof message) != 0) {
    if (error) *error = message;
    return false;
  }
  image.width = width;
  image.height = height;
  image.rgba.assign(rgba, rgba + size_t(width) * size_t(height) * 4);
  p.release(rgba);
  return true;
}

}  // namespace imps::app
