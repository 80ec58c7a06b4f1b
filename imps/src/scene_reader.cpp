// SPDX-License-Identifier: MIT
// readScene / readSceneFile: the parser driving the SceneBuilder, and file input.
#include "imps/scene_reader.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <system_error>

#include "imps/file_read.h"
#include "scene_builder.h"
#include "scene_parser.h"

namespace imps {

namespace {

constexpr size_t kMaxFileBytes = size_t{256} << 20;

// Moves the warnings (not the errors) of `all` into `warnings`.
void copyWarnings(const Diagnostics& all, Diagnostics* warnings) {
  if (warnings == nullptr) return;
  for (const Diagnostic& d : all.all())
    if (d.severity == Severity::Warning) warnings->warning(d.loc, d.message);
}

}  // namespace

std::expected<Scene, Diagnostics> readScene(std::string_view text, const std::string& fileName,
                                            Diagnostics* warnings) {
  Diagnostics diagnostics;
  vrml::DiagnosticSink sink(diagnostics);
  vrml::SceneBuilder builder(fileName, sink);
  const bool parsedToEnd = vrml::parse(text, fileName, builder, sink);
  Scene scene = builder.finish(parsedToEnd);
  copyWarnings(diagnostics, warnings);
  if (diagnostics.hasErrors()) return std::unexpected(std::move(diagnostics));
  return scene;
}

std::expected<Scene, Diagnostics> readScene(std::string_view text, const std::string& fileName) {
  return readScene(text, fileName, nullptr);
}

std::expected<Scene, Diagnostics> readSceneFile(const std::string& path, Diagnostics* warnings) {
  auto fail = [&](const std::string& reason) {
    Diagnostics d;
    d.error(SourceLoc{path, 0, 0}, "cannot read scene file: " + reason);
    return std::unexpected(std::move(d));
  };
  auto text = readFileText(path, kMaxFileBytes);
  if (!text) return fail(text.error().message);
  return readScene(*text, path, warnings);
}

std::expected<Scene, Diagnostics> readSceneFile(const std::string& path) { return readSceneFile(path, nullptr); }

}  // namespace imps
