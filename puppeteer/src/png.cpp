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

std::expected<std::vector<uint8_t>, Diagnostics> encodePng(const std::vector<uint8_t>& rgba, int width, int height) {
  const auto fail = [](std::string reason) { return std::unexpected(singleError({}, std::move(reason))); };
  const Plugin& p = plugin();
  if (!p.encode) return fail(p.error);
  if (width <= 0 || height <= 0 || rgba.size() != size_t(width) * size_t(height) * 4)
    return fail("no pixels to encode");
  uint8_t* png = nullptr;
  size_t size = 0;
  char message[512] = "";
  if (p.encode(width, height, rgba.data(), &png, &size, message, sizeof message) != 0) return fail(message);
  std::vector<uint8_t> bytes(png, png + size);
  p.release(png);
  return bytes;
}

std::expected<void, Diagnostics> savePng(const std::vector<uint8_t>& rgba, int width, int height,
                                         const std::string& path) {
  auto fail = [&](const std::string& reason) { return std::unexpected(singleError({}, path + ": " + reason)); };
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
  if (auto saved = writeFileAtomically(path, bytes); !saved)
    return std::unexpected(singleError({}, saved.error().message));
  return {};
}

std::expected<RgbaImage, Diagnostics> readImage(const std::string& path) {
  const auto fail = [&](std::string reason) { return std::unexpected(singleError({path}, std::move(reason))); };
  const Plugin& p = plugin();
  if (!p.encode) return fail(p.error);
  uint8_t* rgba = nullptr;
  int width = 0, height = 0;
  char message[512] = "";
  if (p.read(path.c_str(), &width, &height, &rgba, message, sizeof message) != 0) return fail(message);
  RgbaImage image;
  image.width = width;
  image.height = height;
  image.rgba.assign(rgba, rgba + size_t(width) * size_t(height) * 4);
  p.release(rgba);
  return image;
}

}  // namespace imps::app
