// SPDX-License-Identifier: MIT
// libFuzzer target for readScene: any bytes must give a scene or diagnostics (never a crash or hang), and every
// scene that reads must survive write -> read unchanged, with writeScene a fixed point.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <version>

#include "imps/scene_writer.h"
#if defined(__cpp_lib_expected)
#include "imps/scene_reader.h"
#else
// clang 14 cannot compile libstdc++ 12's <expected>; it then drives the parser and builder that readScene wraps
// directly (build with imps/src on the include path and without scene_reader.cpp).
#include "scene_builder.h"
#endif

namespace {

// What readScene does: the scene, or nullopt with the errors in `diagnostics`.
std::optional<imps::Scene> read(std::string_view text, const std::string& name, imps::Diagnostics& diagnostics) {
#if defined(__cpp_lib_expected)
  auto scene = imps::readScene(text, name);
  if (scene) return std::move(*scene);
  diagnostics = scene.error();
  return std::nullopt;
#else
  imps::vrml::DiagnosticSink sink(diagnostics);
  imps::vrml::SceneBuilder builder(name, sink);
  const bool parsedToEnd = imps::vrml::parse(text, name, builder, sink);
  imps::Scene scene = builder.finish(parsedToEnd);
  if (diagnostics.hasErrors()) return std::nullopt;
  return scene;
#endif
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  imps::Diagnostics diagnostics;
  const auto scene = read(text, "fuzz.wrl", diagnostics);
  if (!scene) {
    if (!diagnostics.hasErrors()) {
      std::fprintf(stderr, "read failed without an error:\n%s", diagnostics.str().c_str());
      std::abort();
    }
    return 0;
  }
  for (const imps::Diagnostic& d : diagnostics.all()) {
    if (d.severity == imps::Severity::Error) std::abort();  // a scene was returned despite an error
  }
  const std::string written = imps::writeScene(*scene);
  imps::Diagnostics again;
  const auto reread = read(written, "written.wrl", again);
  if (!reread) {
    std::fprintf(stderr, "written scene does not read back:\n%s\n%s", again.str().c_str(), written.c_str());
    std::abort();
  }
  if (!(*reread == *scene)) {
    std::fprintf(stderr, "written scene reads back different:\n%s", written.c_str());
    std::abort();
  }
  if (imps::writeScene(*reread) != written) {
    std::fprintf(stderr, "writeScene is not a fixed point:\n%s", written.c_str());
    std::abort();
  }
  return 0;
}
